//! The ESCs' telemetry over MAVLink (docs/firmware.md#esc-telemetry): each rotor's RPM in,
//! from the HIL plant as `ESC_STATUS` (the plant's stand-in for bidirectional DShot), and the
//! ESCs' state out to the ground station as `ESC_STATUS` and `ESC_INFO`, four ESCs a message
//! in motor order, as PX4 sends them (QGroundControl's ESC status page, MAVSDK's telemetry):
//! with DroneCAN ESCs also what their `Status` measures ([`EscElectrical`]).

use crate::hil::MAX_ROBOTS;
use crate::msg::{ESC_INFO_DATA, ESC_STATUS_DATA, EscConnectionType};
use crate::telemetry::VehicleSnapshot;

/// ESCs in one `ESC_STATUS` or `ESC_INFO`.
pub const ESCS_PER_MESSAGE: usize = 4;
/// A reading counts for this long after its message's time, us (eight 400 Hz control steps):
/// an ESC not heard of since reads as not answering.
pub const RPM_MAX_AGE_US: u64 = 20_000;
/// `ESC_INFO`'s `failure_flags` for a rotor the vehicle flies without
/// (`ESC_FAILURE_GENERIC`): found stopped by the rotor monitor or its ESC.
pub const FAILURE_ROTOR_OUT: u16 = 64;
/// `ESC_INFO`'s `temperature` when the ESC gives none (`INT16_MAX`).
pub const NO_TEMPERATURE: i16 = i16::MAX;

const GROUPS: usize = MAX_ROBOTS / ESCS_PER_MESSAGE;

/// What four ESCs of one message measure beside their RPM (DroneCAN's `Status`): NaN for a
/// value not measured or not heard of.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EscElectrical {
    /// Each one's supply voltage, V.
    pub voltage: [f32; ESCS_PER_MESSAGE],
    /// Each one's current, A.
    pub current: [f32; ESCS_PER_MESSAGE],
    /// Each one's temperature, degrees Celsius.
    pub temperature_c: [f32; ESCS_PER_MESSAGE],
    /// Each one's error count since it started.
    pub errors: [u32; ESCS_PER_MESSAGE],
}

impl EscElectrical {
    /// Nothing measured.
    pub const NONE: Self = Self {
        voltage: [f32::NAN; ESCS_PER_MESSAGE],
        current: [f32::NAN; ESCS_PER_MESSAGE],
        temperature_c: [f32::NAN; ESCS_PER_MESSAGE],
        errors: [0; ESCS_PER_MESSAGE],
    };
}

/// A measured value for a message's float field: 0 when not measured, as PX4 sends it.
fn measured(v: f32) -> f32 {
    if v.is_finite() { v } else { 0.0 }
}

/// What is wrong with a received `ESC_STATUS`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EscError {
    /// `index` is not a multiple of four (the first ESC of its message).
    IndexNotFirstOfFour(u8),
    /// `index` beyond the robots the link carries.
    IndexBeyond(u8),
}

impl core::fmt::Display for EscError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::IndexNotFirstOfFour(i) => write!(
                f,
                "ESC_STATUS index {i} is not the first of four ESCs (0, 4, 8 or 12)"
            ),
            Self::IndexBeyond(i) => write!(
                f,
                "ESC_STATUS index {i} is beyond the {MAX_ROBOTS} ESCs the vehicle has"
            ),
        }
    }
}

/// What the vehicle reads of an `ESC_STATUS`: four ESCs' RPM and when.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EscRpmReport {
    /// The first ESC's index (0, 4, 8 or 12).
    pub index: u8,
    /// The message's time, us.
    pub time_us: u64,
    /// Each ESC's RPM (negative: turning backwards).
    pub rpm: [i32; ESCS_PER_MESSAGE],
}

impl From<&ESC_STATUS_DATA> for EscRpmReport {
    fn from(m: &ESC_STATUS_DATA) -> Self {
        Self {
            index: m.index,
            time_us: m.time_usec,
            rpm: m.rpm,
        }
    }
}

/// The latest RPM each ESC reported, and when: `ESC_STATUS` messages in, each rotor's RPM
/// for a control step out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EscRpmInbox {
    rpm: [f32; MAX_ROBOTS],
    /// Each message's `time_usec`, by its first ESC's index over four.
    stamp_us: [u64; GROUPS],
    /// Bit `g`: a message for ESCs `4g..4g+4` has come.
    heard: u8,
}

impl Default for EscRpmInbox {
    fn default() -> Self {
        Self::new()
    }
}

impl EscRpmInbox {
    /// Nothing heard yet.
    pub const fn new() -> Self {
        Self {
            rpm: [f32::NAN; MAX_ROBOTS],
            stamp_us: [0; GROUPS],
            heard: 0,
        }
    }

    /// Takes an `ESC_STATUS`'s RPM (voltage and current are not used), or says why not.
    pub fn receive(&mut self, m: &EscRpmReport) -> Result<(), EscError> {
        let first = usize::from(m.index);
        if first % ESCS_PER_MESSAGE != 0 {
            return Err(EscError::IndexNotFirstOfFour(m.index));
        }
        if first >= MAX_ROBOTS {
            return Err(EscError::IndexBeyond(m.index));
        }
        let group = first / ESCS_PER_MESSAGE;
        for (slot, &rpm) in self.rpm[first..first + ESCS_PER_MESSAGE]
            .iter_mut()
            .zip(&m.rpm)
        {
            *slot = rpm as f32;
        }
        self.stamp_us[group] = m.time_us;
        self.heard |= 1 << group;
        Ok(())
    }

    /// Each ESC's RPM at vehicle time `now_us` (NaN for one not heard of within
    /// [`RPM_MAX_AGE_US`]), or `None` when none was.
    pub fn rpm_at(&self, now_us: u64) -> Option<[f32; MAX_ROBOTS]> {
        if self.heard == 0 {
            return None;
        }
        let mut out = [f32::NAN; MAX_ROBOTS];
        let mut any = false;
        for (group, &stamp) in self.stamp_us.iter().enumerate() {
            let fresh = self.heard & (1 << group) != 0 && now_us.abs_diff(stamp) <= RPM_MAX_AGE_US;
            if fresh {
                let span = group * ESCS_PER_MESSAGE..(group + 1) * ESCS_PER_MESSAGE;
                out[span.clone()].copy_from_slice(&self.rpm[span]);
                any = true;
            }
        }
        any.then_some(out)
    }
}

/// Messages of four ESCs the vehicle's robots need.
pub fn messages(robots: u8) -> usize {
    usize::from(robots)
        .min(MAX_ROBOTS)
        .div_ceil(ESCS_PER_MESSAGE)
}

/// Whether any of the vehicle's ESCs reported its RPM, `rpm` each robot's in the last control
/// step that had any (the vehicle then sends `ESC_STATUS` and `ESC_INFO`).
pub fn reporting(vehicle: &VehicleSnapshot, rpm: &[f32; MAX_ROBOTS]) -> bool {
    let robots = usize::from(vehicle.robots).min(MAX_ROBOTS);
    rpm[..robots].iter().any(|r| r.is_finite())
}

/// `ESC_STATUS` of the ESCs from `4 * message` on, `rpm` each robot's (NaN: no answer): each
/// one's RPM (0 for one that did not answer, as PX4 sends it), and its voltage and current
/// from `electrical` (0 where not measured, and without it).
pub fn esc_status(
    vehicle: &VehicleSnapshot,
    esc_rpm: &[f32; MAX_ROBOTS],
    electrical: Option<&EscElectrical>,
    message: usize,
) -> ESC_STATUS_DATA {
    let first = first_esc(message);
    let mut rpm = [0i32; ESCS_PER_MESSAGE];
    for (out, &r) in rpm.iter_mut().zip(&esc_rpm[first..]) {
        // NaN as 0; `as` saturates the rest.
        *out = if r.is_finite() { r as i32 } else { 0 };
    }
    let e = electrical.unwrap_or(&EscElectrical::NONE);
    ESC_STATUS_DATA {
        time_usec: vehicle.time_us,
        rpm,
        voltage: e.voltage.map(measured),
        current: e.current.map(measured),
        index: first as u8,
    }
}

/// `ESC_INFO` of the ESCs from `4 * message` on, its `counter`-th, `rpm` each robot's (NaN:
/// no answer): how many ESCs there are, which answer (`info`, a bit per ESC of the first eight as
/// PX4 has it), and the rotors flown without ([`FAILURE_ROTOR_OUT`]). With `electrical` (CAN
/// ESCs) each one's temperature and error count, and the connection CAN; without, DShot, no
/// temperatures and no error counts.
pub fn esc_info(
    vehicle: &VehicleSnapshot,
    rpm: &[f32; MAX_ROBOTS],
    electrical: Option<&EscElectrical>,
    message: usize,
    counter: u16,
) -> ESC_INFO_DATA {
    let robots = usize::from(vehicle.robots).min(MAX_ROBOTS);
    let first = first_esc(message);
    let mut online = 0u8;
    for (j, r) in rpm[..robots.min(8)].iter().enumerate() {
        if r.is_finite() {
            online |= 1 << j;
        }
    }
    let mut failure_flags = [0u16; ESCS_PER_MESSAGE];
    for (i, flags) in failure_flags.iter_mut().enumerate() {
        if vehicle.rotors_out & (1 << (first + i)) != 0 {
            *flags = FAILURE_ROTOR_OUT;
        }
    }
    let (connection_type, temperature, error_count) = match electrical {
        // cdegC, INT16_MAX where not measured.
        Some(e) => (
            EscConnectionType::ESC_CONNECTION_TYPE_CAN,
            e.temperature_c.map(|c| {
                if c.is_finite() {
                    shared::math::clamp(shared::math::round(c * 100.0), -32_768.0, 32_766.0) as i16
                } else {
                    NO_TEMPERATURE
                }
            }),
            e.errors,
        ),
        None => (
            EscConnectionType::ESC_CONNECTION_TYPE_DSHOT,
            [NO_TEMPERATURE; ESCS_PER_MESSAGE],
            [0; ESCS_PER_MESSAGE],
        ),
    };
    ESC_INFO_DATA {
        time_usec: vehicle.time_us,
        counter,
        count: robots as u8,
        connection_type,
        info: online,
        failure_flags,
        error_count,
        temperature,
        index: first as u8,
    }
}

/// The first ESC of message `message` (four ESCs a message; the last message at most).
fn first_esc(message: usize) -> usize {
    (message * ESCS_PER_MESSAGE).min(MAX_ROBOTS - ESCS_PER_MESSAGE)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    fn status(index: u8, time_us: u64, rpm: [i32; 4]) -> EscRpmReport {
        EscRpmReport::from(&ESC_STATUS_DATA {
            time_usec: time_us,
            rpm,
            index,
            ..Default::default()
        })
    }

    #[test]
    fn two_messages_make_eight_rotors_and_an_old_one_reads_as_silent() {
        let mut inbox = EscRpmInbox::new();
        assert_eq!(inbox.rpm_at(0), None);
        inbox.receive(&status(0, 1_000, [1, 2, 3, 4])).unwrap();
        inbox.receive(&status(4, 1_000, [5, 6, 7, 8])).unwrap();
        let rpm = inbox.rpm_at(2_500).unwrap();
        assert_eq!(&rpm[..8], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]);
        assert!(rpm[8..].iter().all(|r| r.is_nan()));
        // Only the first four go on being sent: the others go silent after 20 ms.
        inbox.receive(&status(0, 30_000, [9, 9, 9, 9])).unwrap();
        let rpm = inbox.rpm_at(30_000).unwrap();
        assert_eq!(&rpm[..4], &[9.0; 4]);
        assert!(rpm[4..].iter().all(|r| r.is_nan()));
        assert_eq!(inbox.rpm_at(60_000), None);
    }

    #[test]
    fn a_message_for_no_group_of_four_is_refused_with_its_index() {
        let mut inbox = EscRpmInbox::new();
        let e = inbox.receive(&status(2, 0, [1; 4])).unwrap_err();
        assert_eq!(e, EscError::IndexNotFirstOfFour(2));
        assert!(e.to_string().contains("index 2"));
        let e = inbox.receive(&status(16, 0, [1; 4])).unwrap_err();
        assert_eq!(e, EscError::IndexBeyond(16));
        assert!(e.to_string().contains("16"));
        assert_eq!(inbox.rpm_at(0), None);
    }

    #[test]
    fn the_ground_is_told_each_rpm_which_escs_answer_and_the_rotors_out() {
        let mut vehicle = VehicleSnapshot::START;
        vehicle.robots = 6;
        let mut rpm = [f32::NAN; MAX_ROBOTS];
        assert!(!reporting(&vehicle, &rpm));
        rpm[..6].copy_from_slice(&[5000.0, 5100.0, f32::NAN, 5300.0, 1e12, 0.0]);
        vehicle.rotors_out = 1 << 5;
        assert!(reporting(&vehicle, &rpm));
        assert_eq!(messages(vehicle.robots), 2);
        let first = esc_status(&vehicle, &rpm, None, 0);
        assert_eq!(first.index, 0);
        assert_eq!(first.rpm, [5000, 5100, 0, 5300]);
        assert_eq!((first.voltage, first.current), ([0.0; 4], [0.0; 4]));
        let second = esc_status(&vehicle, &rpm, None, 1);
        assert_eq!(second.index, 4);
        assert_eq!(second.rpm, [i32::MAX, 0, 0, 0]);
        let info = esc_info(&vehicle, &rpm, None, 1, 7);
        assert_eq!((info.index, info.count, info.counter), (4, 6, 7));
        assert_eq!(info.info, 0b11_1011);
        assert_eq!(info.failure_flags, [0, FAILURE_ROTOR_OUT, 0, 0]);
        assert_eq!(info.temperature, [NO_TEMPERATURE; 4]);
        assert_eq!(
            info.connection_type,
            EscConnectionType::ESC_CONNECTION_TYPE_DSHOT
        );
    }

    #[test]
    fn can_escs_add_what_their_status_measures_and_not_what_they_did_not_say() {
        let mut vehicle = VehicleSnapshot::START;
        vehicle.robots = 4;
        let rpm = [4_000.0; MAX_ROBOTS];
        let electrical = EscElectrical {
            voltage: [15.8, 15.7, f32::NAN, 15.6],
            current: [3.5, 3.25, f32::NAN, f32::INFINITY],
            temperature_c: [36.85, 40.0, f32::NAN, 1_000.0],
            errors: [0, 2, 0, 7],
        };
        let status = esc_status(&vehicle, &rpm, Some(&electrical), 0);
        assert_eq!(status.voltage, [15.8, 15.7, 0.0, 15.6]);
        assert_eq!(status.current, [3.5, 3.25, 0.0, 0.0]);
        let info = esc_info(&vehicle, &rpm, Some(&electrical), 0, 0);
        assert_eq!(
            info.connection_type,
            EscConnectionType::ESC_CONNECTION_TYPE_CAN
        );
        assert_eq!(info.temperature, [3_685, 4_000, NO_TEMPERATURE, 32_766]);
        assert_eq!(info.error_count, [0, 2, 0, 7]);
    }
}
