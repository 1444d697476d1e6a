//! What the vehicle tells people and tools: `STATUSTEXT` for events (every mission transition,
//! refusals naming the key), `NAMED_VALUE_FLOAT`/`NAMED_VALUE_INT` for numbers, so any MAVLink tool
//! can show them.
//!
//! A text longer than one `STATUSTEXT` (50 bytes) goes out in chunks sharing a non-zero `id`,
//! numbered by `chunk_seq`; the last chunk is shorter than 50 bytes (an empty one follows a
//! text that fills its last chunk exactly), as the MAVLink spec has it. [`Reassembler`] puts
//! them back together on the ground side.
//!
//! Conventions the HIL plant reads (a ground station just shows them):
//! - a text starting with [`BOARD_PREFIX`] names the board the firmware runs on;
//! - a text starting with [`PHASE_PREFIX`] reports a mission transition (`phase: NAME: reason`).

use heapless::{String, Vec};

use crate::frame::{Encoder, Frame};
use crate::modes::FlightMode;

use crate::msg::{
    HEARTBEAT_DATA, MavAutopilot, MavModeFlag, MavProtocolCapability, MavSeverity, MavState,
    MavType, NAMED_VALUE_FLOAT_DATA, NAMED_VALUE_INT_DATA, STATUSTEXT_DATA,
};

/// `AUTOPILOT_VERSION.capabilities`: what the vehicle does
/// (docs/ground-link.md#the-declared-capabilities). MAVLink 2 (and its signing), `COMMAND_INT`
/// ([`crate::command`]), FTP ([`crate::ftp`]), the parameters' byte-wise encoding (every
/// parameter is a `REAL32`, sent as itself, [`crate::param`]) and the mission protocol's
/// `_INT` messages ([`crate::mission`]).
pub fn capabilities() -> MavProtocolCapability {
    MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MAVLINK2
        | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MISSION_INT
        | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_COMMAND_INT
        | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_FTP
        | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE
}

/// Bytes of text in one `STATUSTEXT`.
pub const CHUNK_LEN: usize = 50;
/// Longest text sent, bytes.
pub const MAX_TEXT_LEN: usize = 200;
/// Start of the text that names the board.
pub const BOARD_PREFIX: &str = "board: ";
/// Start of the text of a mission transition.
pub const PHASE_PREFIX: &str = "phase: ";
/// Longest name of a named value, bytes.
pub const NAME_LEN: usize = 10;

/// A text to send, with its severity.
pub type Text = String<MAX_TEXT_LEN>;

/// Where the mission stands, as the vehicle's `HEARTBEAT` carries it in `custom_mode` (and in
/// `system_status`: standby, active, or critical after an abort).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum MissionState {
    /// Waiting for its payload description and the start command.
    Idle = 0,
    /// Running (from the start command to landing and disarm).
    Running = 1,
    /// Ended as planned.
    Completed = 2,
    /// Ended early, for a reason the vehicle has sent as `STATUSTEXT`.
    Aborted = 3,
}

impl MissionState {
    /// The state coded in a `HEARTBEAT`'s `custom_mode` (its low byte; the flight mode is
    /// above it, [`crate::modes`]).
    pub fn from_custom_mode(code: u32) -> Option<Self> {
        [Self::Idle, Self::Running, Self::Completed, Self::Aborted]
            .into_iter()
            .find(|s| *s as u32 == code & 0xff)
    }

    /// The state's name for people and reports: `idle`, `running`, `completed`, `aborted`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Idle => "idle",
            Self::Running => "running",
            Self::Completed => "completed",
            Self::Aborted => "aborted",
        }
    }

    /// Whether the mission is over.
    pub fn is_over(self) -> bool {
        matches!(self, Self::Completed | Self::Aborted)
    }
}

/// The vehicle's `HEARTBEAT`: a multirotor whose `custom_mode` is its flight mode in PX4's
/// numbers with the [`MissionState`] in the low byte ([`crate::modes`]), armed and HIL flags
/// in `base_mode`.
pub fn heartbeat(
    state: MissionState,
    mode: FlightMode,
    armed: bool,
    in_hil: bool,
) -> HEARTBEAT_DATA {
    let mut base_mode = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
    if armed {
        base_mode |= MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
    }
    if in_hil {
        base_mode |= MavModeFlag::MAV_MODE_FLAG_HIL_ENABLED;
    }
    HEARTBEAT_DATA {
        custom_mode: mode.heartbeat_custom_mode(state),
        mavtype: MavType::MAV_TYPE_GENERIC_MULTIROTOR,
        autopilot: MavAutopilot::MAV_AUTOPILOT_GENERIC,
        base_mode,
        system_status: match state {
            MissionState::Idle | MissionState::Completed => MavState::MAV_STATE_STANDBY,
            MissionState::Running => MavState::MAV_STATE_ACTIVE,
            MissionState::Aborted => MavState::MAV_STATE_CRITICAL,
        },
        mavlink_version: 3,
    }
}

/// One `STATUSTEXT` with its MAVLink 2 extension fields `id` and `chunk_seq` (written and read
/// here: see the note on `mavlink` features in the workspace manifest).
#[derive(Clone, Debug, PartialEq)]
pub struct StatusChunk {
    /// The base message: severity and up to 50 bytes of text.
    pub message: STATUSTEXT_DATA,
    /// Number shared by the chunks of one text (0: a text of one chunk).
    pub id: u16,
    /// Place of this chunk in its text.
    pub chunk_seq: u8,
}

impl StatusChunk {
    /// Encodes it, extension fields included.
    pub fn encode(&self, encoder: &mut Encoder, out: &mut Frame) {
        let id = self.id.to_le_bytes();
        encoder.encode_extended(&self.message, &[id[0], id[1], self.chunk_seq], out);
    }

    /// Reads one from a frame (`None` if it is not a `STATUSTEXT`).
    pub fn from_frame(frame: &Frame) -> Option<Self> {
        let message = frame.decode::<STATUSTEXT_DATA>()?;
        let ext = |i: usize| {
            frame
                .payload()
                .get(STATUSTEXT_DATA::ENCODED_LEN + i)
                .copied()
                .unwrap_or(0)
        };
        Some(Self {
            message,
            id: u16::from_le_bytes([ext(0), ext(1)]),
            chunk_seq: ext(2),
        })
    }

    /// Its text (up to the first NUL).
    pub fn text(&self) -> &[u8] {
        let end = self
            .message
            .text
            .iter()
            .position(|&b| b == 0)
            .unwrap_or(CHUNK_LEN);
        &self.message.text[..end]
    }
}

/// The `STATUSTEXT` chunks of `text`; `id` numbers a multi-chunk text (never 0; a text of one
/// chunk goes with id 0). Bytes past [`MAX_TEXT_LEN`] are dropped.
pub fn chunks(
    text: &str,
    severity: MavSeverity,
    id: u16,
) -> Vec<StatusChunk, { MAX_TEXT_LEN / CHUNK_LEN + 1 }> {
    let bytes = &text.as_bytes()[..text.len().min(MAX_TEXT_LEN)];
    let mut out = Vec::new();
    let single = bytes.len() <= CHUNK_LEN;
    let id = if single { 0 } else { id.max(1) };
    let mut seq = 0u8;
    let mut rest = bytes;
    loop {
        let n = rest.len().min(CHUNK_LEN);
        let mut data = [0u8; CHUNK_LEN];
        data[..n].copy_from_slice(&rest[..n]);
        let _ = out.push(StatusChunk {
            message: STATUSTEXT_DATA {
                severity,
                text: data.into(),
            },
            id,
            chunk_seq: seq,
        });
        rest = &rest[n..];
        seq = seq.wrapping_add(1);
        // Stop after a short chunk; a text ending on a full chunk gets an empty one (multi-chunk
        // only: a single full chunk needs no terminator, its id is 0).
        if n < CHUNK_LEN || (single && rest.is_empty()) {
            break;
        }
    }
    out
}

/// A `NAMED_VALUE_FLOAT` (`name` cut to [`NAME_LEN`] bytes).
pub fn named_float(name: &str, value: f32, time_boot_ms: u32) -> NAMED_VALUE_FLOAT_DATA {
    NAMED_VALUE_FLOAT_DATA {
        time_boot_ms,
        value,
        name: name.into(),
    }
}

/// A `NAMED_VALUE_INT` (`name` cut to [`NAME_LEN`] bytes).
pub fn named_int(name: &str, value: i32, time_boot_ms: u32) -> NAMED_VALUE_INT_DATA {
    NAMED_VALUE_INT_DATA {
        time_boot_ms,
        value,
        name: name.into(),
    }
}

/// Puts chunked `STATUSTEXT`s back together (one text at a time, as the vehicle sends them).
#[derive(Default)]
pub struct Reassembler {
    id: u16,
    next_seq: u8,
    text: Vec<u8, MAX_TEXT_LEN>,
}

impl Reassembler {
    /// An empty reassembler.
    pub fn new() -> Self {
        Self::default()
    }

    /// Takes one `STATUSTEXT`; returns the whole text (lossy UTF-8 is the caller's) when this
    /// one completes it.
    pub fn push(&mut self, m: &StatusChunk) -> Option<Vec<u8, MAX_TEXT_LEN>> {
        let part = m.text();
        if m.id == 0 {
            return Vec::from_slice(part).ok();
        }
        if m.id != self.id || m.chunk_seq != self.next_seq {
            // A new text (or a lost chunk): start over from this chunk if it is a first one.
            self.text.clear();
            if m.chunk_seq != 0 {
                self.id = 0;
                return None;
            }
            self.id = m.id;
        }
        let _ = self.text.extend_from_slice(part);
        self.next_seq = m.chunk_seq.wrapping_add(1);
        if part.len() < CHUNK_LEN {
            self.id = 0;
            self.next_seq = 0;
            return Some(core::mem::take(&mut self.text));
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[allow(deprecated)] // PARAM_FLOAT, checked absent
    fn the_capabilities_are_what_the_vehicle_does_and_no_more() {
        let c = capabilities();
        assert!(c.contains(MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_COMMAND_INT));
        assert!(c.contains(MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MISSION_INT));
        // One parameter encoding; the mission's items as `_INT` only; no geofence or rally.
        assert!(!c.intersects(
            MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_C_CAST
                | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT
                | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MISSION_FLOAT
                | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MISSION_FENCE
                | MavProtocolCapability::MAV_PROTOCOL_CAPABILITY_MISSION_RALLY
        ));
        assert_eq!(c.bits(), 4 | 8 | 16 | 32 | 8192);
    }

    fn round_trip(text: &str) -> std::string::String {
        let mut r = Reassembler::new();
        let mut out = None;
        let mut encoder = Encoder::new(1, 1);
        let mut frame = Frame::default();
        for c in chunks(text, MavSeverity::MAV_SEVERITY_INFO, 7) {
            // Through the wire, extension fields included.
            c.encode(&mut encoder, &mut frame);
            let mut parser = crate::frame::Parser::new(crate::vehicle::crc_extra);
            let mut back = None;
            for &b in frame.bytes() {
                if let Some((f, _)) = parser.push(b) {
                    back = StatusChunk::from_frame(f);
                }
            }
            let c = back.expect("a STATUSTEXT");
            if let Some(t) = r.push(&c) {
                assert!(out.is_none(), "one text comes out once");
                out = Some(std::string::String::from_utf8_lossy(&t).into_owned());
            }
        }
        out.expect("text completed")
    }

    #[test]
    fn short_and_long_texts_come_back_whole() {
        let short = "phase: checks: started";
        assert_eq!(chunks(short, MavSeverity::MAV_SEVERITY_INFO, 3)[0].id, 0);
        assert_eq!(round_trip(short), short);
        let long = "payload refused: robots.initial: robots 7 and the next are 0.1 m apart, closer than min_spacing 0.25 m";
        assert!(long.len() > CHUNK_LEN);
        assert_eq!(round_trip(long), long);
        let exact = "x".repeat(100);
        let c = chunks(&exact, MavSeverity::MAV_SEVERITY_INFO, 3);
        assert_eq!(c.len(), 3, "two full chunks and an empty terminator");
        assert_eq!(round_trip(&exact), exact);
        let fifty = "y".repeat(50);
        assert_eq!(chunks(&fifty, MavSeverity::MAV_SEVERITY_INFO, 3).len(), 1);
        assert_eq!(round_trip(&fifty), fifty);
    }

    #[test]
    fn a_lost_chunk_drops_that_text_but_not_the_next() {
        let mut r = Reassembler::new();
        let first = chunks(&"a".repeat(120), MavSeverity::MAV_SEVERITY_INFO, 1);
        assert!(r.push(&first[0]).is_none());
        // first[1] lost
        assert!(r.push(&first[2]).is_none());
        let second = chunks(&"b".repeat(60), MavSeverity::MAV_SEVERITY_INFO, 2);
        assert!(r.push(&second[0]).is_none());
        let t = r.push(&second[1]).expect("second text whole");
        assert_eq!(&t[..], "b".repeat(60).as_bytes());
    }

    #[test]
    fn the_heartbeat_carries_the_mission_state() {
        for state in [
            MissionState::Idle,
            MissionState::Running,
            MissionState::Completed,
            MissionState::Aborted,
        ] {
            let h = heartbeat(
                state,
                FlightMode::Hold,
                state == MissionState::Running,
                true,
            );
            assert_eq!(MissionState::from_custom_mode(h.custom_mode), Some(state));
            assert_eq!(
                crate::modes::flight_mode(h.custom_mode),
                Some(FlightMode::Hold)
            );
            assert_eq!(
                h.base_mode
                    .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED),
                state == MissionState::Running
            );
        }
        assert_eq!(MissionState::from_custom_mode(9), None);
    }

    #[test]
    fn named_values_cut_their_names() {
        let v = named_float("tick_instructions", 1.5, 10);
        assert_eq!(&v.name[..], b"tick_instr");
        assert_eq!(named_int("ticks", 3, 0).value, 3);
    }
}
