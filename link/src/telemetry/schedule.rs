//! When each stream is due: the interval a ground station sets for each with
//! `MAV_CMD_SET_MESSAGE_INTERVAL` (or a message asked for once with `MAV_CMD_REQUEST_MESSAGE`),
//! as MAVLink's message interval protocol has it, over the vehicle's microsecond clock.

use crate::MessageData;
use crate::msg::{
    ACTUATOR_OUTPUT_STATUS_DATA, ATTITUDE_QUATERNION_DATA, DEBUG_FLOAT_ARRAY_DATA, ESC_INFO_DATA,
    ESC_STATUS_DATA, GLOBAL_POSITION_INT_DATA, LOCAL_POSITION_NED_DATA, MavResult,
    RC_CHANNELS_DATA, SERVO_OUTPUT_RAW_DATA, SYS_STATUS_DATA,
};

/// A message the vehicle streams.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stream {
    /// `SYS_STATUS`: sensors present, enabled and healthy; the control loop's load.
    SysStatus = 0,
    /// `ATTITUDE_QUATERNION`: attitude and body rates.
    AttitudeQuaternion = 1,
    /// `LOCAL_POSITION_NED`: position and velocity from the take-off point.
    LocalPositionNed = 2,
    /// `DEBUG_FLOAT_ARRAY` `rail` ([`RAIL_ARRAY_ID`](super::RAIL_ARRAY_ID)): each robot's
    /// commanded arc length.
    RailPositions = 3,
    /// `GLOBAL_POSITION_INT`: the local position through the map origin.
    GlobalPositionInt = 4,
    /// `SERVO_OUTPUT_RAW`: the first eight ESC outputs as pulses (MAVProxy's view).
    ServoOutputRaw = 5,
    /// `ACTUATOR_OUTPUT_STATUS`: every ESC output, fractions of full command.
    ActuatorOutputStatus = 6,
    /// `ESC_STATUS`: each rotor's RPM from its ESC ([`crate::esc`]; sent only while ESCs
    /// report).
    EscStatus = 7,
    /// `ESC_INFO`: which ESCs answer, the rotors flown without ([`crate::esc`]; sent only
    /// while ESCs report).
    EscInfo = 8,
    /// `RC_CHANNELS`: the RC receiver's last channels ([`super::RcStatus`]; sent only once a
    /// receiver has been heard).
    RcChannels = 9,
}

/// How many streams there are.
pub const STREAMS: usize = 10;

impl Stream {
    /// Every stream, in the order of their index.
    pub const ALL: [Stream; STREAMS] = [
        Stream::SysStatus,
        Stream::AttitudeQuaternion,
        Stream::LocalPositionNed,
        Stream::RailPositions,
        Stream::GlobalPositionInt,
        Stream::ServoOutputRaw,
        Stream::ActuatorOutputStatus,
        Stream::EscStatus,
        Stream::EscInfo,
        Stream::RcChannels,
    ];

    /// The MAVLink message id.
    pub const fn message_id(self) -> u32 {
        match self {
            Self::SysStatus => SYS_STATUS_DATA::ID,
            Self::AttitudeQuaternion => ATTITUDE_QUATERNION_DATA::ID,
            Self::LocalPositionNed => LOCAL_POSITION_NED_DATA::ID,
            Self::RailPositions => DEBUG_FLOAT_ARRAY_DATA::ID,
            Self::GlobalPositionInt => GLOBAL_POSITION_INT_DATA::ID,
            Self::ServoOutputRaw => SERVO_OUTPUT_RAW_DATA::ID,
            Self::ActuatorOutputStatus => ACTUATOR_OUTPUT_STATUS_DATA::ID,
            Self::EscStatus => ESC_STATUS_DATA::ID,
            Self::EscInfo => ESC_INFO_DATA::ID,
            Self::RcChannels => RC_CHANNELS_DATA::ID,
        }
    }

    /// The stream of a message id, if the vehicle streams it.
    pub fn of_message(id: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.message_id() == id)
    }

    /// The interval at start and after a request for the default (interval 0), us: 1 Hz for
    /// the status and the ESCs' information, 2 Hz for the rail positions, 4 Hz for the ESC
    /// outputs and their RPM, 5 Hz for the global position (a map's) and the RC channels (as
    /// PX4 streams `RC_CHANNELS` on a normal link), 10 Hz for attitude and local position.
    pub const fn default_interval_us(self) -> u32 {
        match self {
            Self::SysStatus | Self::EscInfo => 1_000_000,
            Self::RailPositions => 500_000,
            Self::ServoOutputRaw | Self::ActuatorOutputStatus | Self::EscStatus => 250_000,
            Self::GlobalPositionInt | Self::RcChannels => 200_000,
            Self::AttitudeQuaternion | Self::LocalPositionNed => 100_000,
        }
    }
}

/// Shortest interval a ground station may set: 5 ms (200 Hz, half the control rate).
pub const MIN_INTERVAL_US: u32 = 5_000;
/// Longest interval a ground station may set: 1 hour.
pub const MAX_INTERVAL_US: u32 = 3_600_000_000;

/// When each stream is next due. (Compact: it is one of the firmware's statics.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    /// Interval of each stream, us; 0: off (an interval is at least [`MIN_INTERVAL_US`]).
    interval_us: [u32; STREAMS],
    /// When each stream is next due, us (vehicle time).
    next_us: [u64; STREAMS],
    /// Bit `i` set: stream `i` is sent once at the next chance, on or off
    /// (`MAV_CMD_REQUEST_MESSAGE`).
    once: u16,
}

impl Default for Schedule {
    fn default() -> Self {
        Self::new()
    }
}

impl Schedule {
    /// Every stream at its default interval, all due at once.
    pub const fn new() -> Self {
        Self {
            interval_us: [
                Stream::SysStatus.default_interval_us(),
                Stream::AttitudeQuaternion.default_interval_us(),
                Stream::LocalPositionNed.default_interval_us(),
                Stream::RailPositions.default_interval_us(),
                Stream::GlobalPositionInt.default_interval_us(),
                Stream::ServoOutputRaw.default_interval_us(),
                Stream::ActuatorOutputStatus.default_interval_us(),
                Stream::EscStatus.default_interval_us(),
                Stream::EscInfo.default_interval_us(),
                Stream::RcChannels.default_interval_us(),
            ],
            next_us: [0; STREAMS],
            once: 0,
        }
    }

    /// `MAV_CMD_SET_MESSAGE_INTERVAL` (param1 the message id, param2 the interval in us: -1
    /// off, 0 the default) at vehicle time `now_us`. The result is the `COMMAND_ACK`'s:
    /// `UNSUPPORTED` for a message the vehicle does not stream, `DENIED` for an interval
    /// outside [`MIN_INTERVAL_US`] to [`MAX_INTERVAL_US`] or not a number (nothing changes
    /// then).
    pub fn set_interval(&mut self, message_id: f32, interval_us: f32, now_us: u64) -> MavResult {
        let Some(stream) = stream_of(message_id) else {
            return MavResult::MAV_RESULT_UNSUPPORTED;
        };
        let interval = if interval_us == -1.0 {
            0
        } else if interval_us == 0.0 {
            stream.default_interval_us()
        } else if interval_us >= MIN_INTERVAL_US as f32 && interval_us <= MAX_INTERVAL_US as f32 {
            interval_us as u32
        } else {
            return MavResult::MAV_RESULT_DENIED;
        };
        let i = stream as usize;
        self.interval_us[i] = interval;
        self.next_us[i] = now_us;
        MavResult::MAV_RESULT_ACCEPTED
    }

    /// `MAV_CMD_REQUEST_MESSAGE` of `message_id`: sent once at the next chance. `false` if the
    /// vehicle does not stream that message.
    pub fn request_once(&mut self, message_id: u32) -> bool {
        match Stream::of_message(message_id) {
            Some(stream) => {
                self.once |= 1 << stream as u16;
                true
            }
            None => false,
        }
    }

    /// The interval of `stream` now, us (`None`: off).
    pub fn interval_us(&self, stream: Stream) -> Option<u32> {
        Some(self.interval_us[stream as usize]).filter(|&i| i != 0)
    }

    fn once(&self, i: usize) -> bool {
        self.once & (1 << i) != 0
    }

    /// When the next stream is due, us; `None` when every stream is off.
    pub fn next_due(&self) -> Option<u64> {
        (0..STREAMS)
            .filter_map(|i| {
                if self.once(i) {
                    Some(0)
                } else {
                    (self.interval_us[i] != 0).then_some(self.next_us[i])
                }
            })
            .min()
    }

    /// A stream due at `now_us`, if any (the one due earliest), its next time set one interval
    /// on. A vehicle that fell behind by more than one interval skips what it missed rather
    /// than sending a burst.
    pub fn take_due(&mut self, now_us: u64) -> Option<Stream> {
        if let Some(i) = (0..STREAMS).find(|&i| self.once(i)) {
            self.once &= !(1 << i);
            return Some(Stream::ALL[i]);
        }
        let i = (0..STREAMS)
            .filter(|&i| self.interval_us[i] != 0 && self.next_us[i] <= now_us)
            .min_by_key(|&i| self.next_us[i])?;
        let interval = u64::from(self.interval_us[i]);
        let next = self.next_us[i] + interval;
        self.next_us[i] = if next <= now_us {
            now_us + interval
        } else {
            next
        };
        Some(Stream::ALL[i])
    }
}

/// The stream of a message id sent as a command's float parameter.
fn stream_of(message_id: f32) -> Option<Stream> {
    if message_id.is_finite() && message_id >= 0.0 && message_id == (message_id as u32) as f32 {
        Stream::of_message(message_id as u32)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ATT: f32 = ATTITUDE_QUATERNION_DATA::ID as f32;

    /// The streams sent over `[0, until_us)` when the sender wakes at every due time.
    fn sent(s: &mut Schedule, until_us: u64) -> std::vec::Vec<(u64, Stream)> {
        let mut out = std::vec::Vec::new();
        while let Some(t) = s.next_due() {
            if t >= until_us {
                break;
            }
            while let Some(stream) = s.take_due(t) {
                out.push((t, stream));
            }
        }
        out
    }

    fn count(log: &[(u64, Stream)], stream: Stream) -> usize {
        log.iter().filter(|(_, s)| *s == stream).count()
    }

    #[test]
    fn the_defaults_stream_at_their_rates() {
        let mut s = Schedule::new();
        let log = sent(&mut s, 2_000_000);
        assert_eq!(count(&log, Stream::SysStatus), 2);
        assert_eq!(count(&log, Stream::RailPositions), 4);
        assert_eq!(count(&log, Stream::AttitudeQuaternion), 20);
        assert_eq!(count(&log, Stream::LocalPositionNed), 20);
        assert_eq!(count(&log, Stream::GlobalPositionInt), 10);
    }

    #[test]
    fn a_set_interval_changes_the_rate_and_minus_one_stops_it() {
        let mut s = Schedule::new();
        assert_eq!(
            s.set_interval(ATT, 20_000.0, 0),
            MavResult::MAV_RESULT_ACCEPTED
        );
        let log = sent(&mut s, 1_000_000);
        assert_eq!(count(&log, Stream::AttitudeQuaternion), 50);
        assert_eq!(
            s.set_interval(ATT, -1.0, 1_000_000),
            MavResult::MAV_RESULT_ACCEPTED
        );
        assert_eq!(s.interval_us(Stream::AttitudeQuaternion), None);
        let log = sent(&mut s, 2_000_000);
        assert_eq!(count(&log, Stream::AttitudeQuaternion), 0);
        assert_eq!(count(&log, Stream::LocalPositionNed), 10);
        // 0: back to the default.
        assert_eq!(s.set_interval(ATT, 0.0, 0), MavResult::MAV_RESULT_ACCEPTED);
        assert_eq!(s.interval_us(Stream::AttitudeQuaternion), Some(100_000));
    }

    #[test]
    fn bad_requests_are_refused_and_change_nothing() {
        let mut s = Schedule::new();
        let before = s;
        for (id, interval, result) in [
            (0.0, 20_000.0, MavResult::MAV_RESULT_UNSUPPORTED), // HEARTBEAT: not a stream
            (f32::NAN, 20_000.0, MavResult::MAV_RESULT_UNSUPPORTED),
            (ATT + 0.5, 20_000.0, MavResult::MAV_RESULT_UNSUPPORTED),
            (ATT, 100.0, MavResult::MAV_RESULT_DENIED), // 10 kHz
            (ATT, -2.0, MavResult::MAV_RESULT_DENIED),
            (ATT, f32::INFINITY, MavResult::MAV_RESULT_DENIED),
            (ATT, f32::NAN, MavResult::MAV_RESULT_DENIED),
        ] {
            assert_eq!(s.set_interval(id, interval, 5), result, "{id} {interval}");
            assert_eq!(s, before);
        }
    }

    #[test]
    fn a_request_sends_once_even_when_off() {
        let mut s = Schedule::new();
        assert_eq!(
            s.set_interval(SYS_STATUS_DATA::ID as f32, -1.0, 0),
            MavResult::MAV_RESULT_ACCEPTED
        );
        let _ = sent(&mut s, 1_000_000);
        assert!(s.request_once(SYS_STATUS_DATA::ID));
        assert!(!s.request_once(0));
        assert_eq!(s.next_due(), Some(0));
        assert_eq!(s.take_due(1_000_000), Some(Stream::SysStatus));
        let log = sent(&mut s, 3_000_000);
        assert_eq!(count(&log, Stream::SysStatus), 0);
    }

    #[test]
    fn a_late_sender_skips_rather_than_bursts() {
        let mut s = Schedule::new();
        let _ = sent(&mut s, 1);
        // Woken 1 s late: each stream once, then on its interval from now.
        let mut late = std::vec::Vec::new();
        while let Some(stream) = s.take_due(1_000_000) {
            late.push(stream);
        }
        assert_eq!(late.len(), STREAMS);
        assert_eq!(s.next_due(), Some(1_100_000));
    }

    #[test]
    fn every_stream_off_means_nothing_due() {
        let mut s = Schedule::new();
        for stream in Stream::ALL {
            s.set_interval(stream.message_id() as f32, -1.0, 0);
        }
        assert_eq!(s.next_due(), None);
        assert_eq!(s.take_due(u64::MAX / 2), None);
    }
}
