//! The mission protocol's messages read from and written to their payload bytes
//! (docs/ground-link.md#missions). Read by hand: `MISSION_ITEM_INT`'s `command` and `frame`
//! and `MISSION_ACK`'s `type` are enums the `mavlink` crate refuses to decode when their value
//! is unknown, and a vehicle must answer such an item with a reason, not drop it; and the
//! `mission_type` extension field, which the crate leaves out (see the workspace manifest).
//! MAVLink 2 drops trailing zero bytes: what is absent reads as 0.
//!
//! `MISSION_REQUEST` and `MISSION_SET_CURRENT` are deprecated but still what older tools
//! (MAVProxy's `wp` module among them) send: they are read, hence the `allow`.
#![allow(deprecated)]

use crate::MessageData;
use crate::frame::{Encoder, Frame};
use crate::msg::{
    MISSION_ACK_DATA, MISSION_CLEAR_ALL_DATA, MISSION_COUNT_DATA, MISSION_CURRENT_DATA,
    MISSION_ITEM_INT_DATA, MISSION_ITEM_REACHED_DATA, MISSION_REQUEST_DATA,
    MISSION_REQUEST_INT_DATA, MISSION_REQUEST_LIST_DATA, MISSION_SET_CURRENT_DATA, MavCmd,
    MavFrame, MavMissionResult,
};

/// `MAV_MISSION_TYPE_MISSION`: the only list this vehicle keeps.
pub const MISSION_TYPE_MISSION: u8 = 0;

/// A mission item as the protocol carries it (`MISSION_ITEM_INT` without its addressing).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WireItem {
    /// `MAV_CMD`, as sent.
    pub command: u16,
    /// `MAV_FRAME`, as sent.
    pub frame: u8,
    /// `autocontinue`, as sent.
    pub autocontinue: u8,
    /// Parameters 1 to 4.
    pub params: [f32; 4],
    /// Latitude (global frames), 1e-7 degrees.
    pub x: i32,
    /// Longitude (global frames), 1e-7 degrees.
    pub y: i32,
    /// Altitude, m.
    pub z: f32,
}

/// Bytes of a stored item ([`WireItem::to_bytes`]).
pub const ITEM_BYTES: usize = 32;

impl WireItem {
    /// The item as bytes for storage.
    pub fn to_bytes(&self) -> [u8; ITEM_BYTES] {
        let mut b = [0u8; ITEM_BYTES];
        for (i, p) in self.params.iter().enumerate() {
            b[4 * i..4 * i + 4].copy_from_slice(&p.to_le_bytes());
        }
        b[16..20].copy_from_slice(&self.x.to_le_bytes());
        b[20..24].copy_from_slice(&self.y.to_le_bytes());
        b[24..28].copy_from_slice(&self.z.to_le_bytes());
        b[28..30].copy_from_slice(&self.command.to_le_bytes());
        b[30] = self.frame;
        b[31] = self.autocontinue;
        b
    }

    /// An item from its stored bytes.
    pub fn from_bytes(b: &[u8; ITEM_BYTES]) -> Self {
        let r = Reader(b);
        Self {
            params: [r.f32(0), r.f32(4), r.f32(8), r.f32(12)],
            x: r.i32(16),
            y: r.i32(20),
            z: r.f32(24),
            command: r.u16(28),
            frame: r.u8(30),
            autocontinue: r.u8(31),
        }
    }
}

/// A payload's bytes, read little-endian; past its end, zeros.
struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn u8(&self, at: usize) -> u8 {
        self.0.get(at).copied().unwrap_or(0)
    }
    fn bytes<const N: usize>(&self, at: usize) -> [u8; N] {
        core::array::from_fn(|i| self.u8(at + i))
    }
    fn u16(&self, at: usize) -> u16 {
        u16::from_le_bytes(self.bytes(at))
    }
    fn i32(&self, at: usize) -> i32 {
        i32::from_le_bytes(self.bytes(at))
    }
    fn f32(&self, at: usize) -> f32 {
        f32::from_le_bytes(self.bytes(at))
    }
}

/// A mission-protocol message addressed to a system and component, read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MissionMessage {
    /// `MISSION_COUNT`: an upload of `count` items begins.
    Count {
        /// Items to come.
        count: u16,
        /// Which list.
        mission_type: u8,
    },
    /// `MISSION_ITEM_INT`: one item of an upload.
    Item {
        /// Its place, from 0.
        seq: u16,
        /// The item.
        item: WireItem,
        /// Which list.
        mission_type: u8,
    },
    /// `MISSION_REQUEST_LIST`: a download begins.
    RequestList {
        /// Which list.
        mission_type: u8,
    },
    /// `MISSION_REQUEST_INT` (or the deprecated `MISSION_REQUEST`, answered the same way):
    /// one item of a download.
    RequestItem {
        /// Its place, from 0.
        seq: u16,
        /// Which list.
        mission_type: u8,
    },
    /// `MISSION_CLEAR_ALL`.
    ClearAll {
        /// Which list (255: all).
        mission_type: u8,
    },
    /// `MISSION_SET_CURRENT`: fly from this item.
    SetCurrent {
        /// The item, from 0.
        seq: u16,
    },
    /// `MISSION_ACK`: the end of a download (or the ground cancelling one).
    Ack {
        /// `MAV_MISSION_RESULT`, as sent.
        result: u8,
        /// Which list.
        mission_type: u8,
    },
}

/// The mission message in `frame` with its target system and component, if it is one.
pub fn read(frame: &Frame) -> Option<(MissionMessage, u8, u8)> {
    let p = Reader(frame.payload());
    let id = frame.message_id();
    let (message, target_at) = match id {
        MISSION_COUNT_DATA::ID => (
            MissionMessage::Count {
                count: p.u16(0),
                mission_type: p.u8(4),
            },
            2,
        ),
        MISSION_ITEM_INT_DATA::ID => (
            MissionMessage::Item {
                seq: p.u16(28),
                item: WireItem {
                    params: [p.f32(0), p.f32(4), p.f32(8), p.f32(12)],
                    x: p.i32(16),
                    y: p.i32(20),
                    z: p.f32(24),
                    command: p.u16(30),
                    frame: p.u8(34),
                    autocontinue: p.u8(36),
                },
                mission_type: p.u8(37),
            },
            32,
        ),
        MISSION_REQUEST_LIST_DATA::ID => (
            MissionMessage::RequestList {
                mission_type: p.u8(2),
            },
            0,
        ),
        MISSION_REQUEST_INT_DATA::ID | MISSION_REQUEST_DATA::ID => (
            MissionMessage::RequestItem {
                seq: p.u16(0),
                mission_type: p.u8(4),
            },
            2,
        ),
        MISSION_CLEAR_ALL_DATA::ID => (
            MissionMessage::ClearAll {
                mission_type: p.u8(2),
            },
            0,
        ),
        MISSION_SET_CURRENT_DATA::ID => (MissionMessage::SetCurrent { seq: p.u16(0) }, 2),
        MISSION_ACK_DATA::ID => (
            MissionMessage::Ack {
                result: p.u8(2),
                mission_type: p.u8(3),
            },
            0,
        ),
        _ => return None,
    };
    Some((message, p.u8(target_at), p.u8(target_at + 1)))
}

/// The ids of the messages [`read`] reads.
pub const READ_IDS: [u32; 8] = [
    MISSION_COUNT_DATA::ID,
    MISSION_ITEM_INT_DATA::ID,
    MISSION_REQUEST_LIST_DATA::ID,
    MISSION_REQUEST_INT_DATA::ID,
    MISSION_REQUEST_DATA::ID,
    MISSION_CLEAR_ALL_DATA::ID,
    MISSION_SET_CURRENT_DATA::ID,
    MISSION_ACK_DATA::ID,
];

/// What the vehicle sends in the mission protocol.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MissionReply {
    /// `MISSION_REQUEST_INT`: send item `seq`.
    Request {
        /// The item wanted.
        seq: u16,
        /// Which list.
        mission_type: u8,
    },
    /// `MISSION_ACK`.
    Ack {
        /// The result.
        result: MavMissionResult,
        /// Which list.
        mission_type: u8,
    },
    /// `MISSION_COUNT`: the answer to a download's start.
    Count {
        /// Items the vehicle has.
        count: u16,
        /// Which list.
        mission_type: u8,
    },
    /// `MISSION_ITEM_INT`: item `seq` of a download.
    Item {
        /// Its place.
        seq: u16,
        /// The item.
        item: WireItem,
        /// It is the current item.
        current: bool,
    },
}

/// The `MavCmd` of the commands the vehicle keeps (others never reach storage).
fn mav_cmd(command: u16) -> MavCmd {
    match command {
        22 => MavCmd::MAV_CMD_NAV_TAKEOFF,
        19 => MavCmd::MAV_CMD_NAV_LOITER_TIME,
        21 => MavCmd::MAV_CMD_NAV_LAND,
        _ => MavCmd::MAV_CMD_NAV_WAYPOINT,
    }
}

/// The `MavFrame` of the frames the vehicle keeps.
#[allow(deprecated)]
fn mav_frame(frame: u8) -> MavFrame {
    match frame {
        0 => MavFrame::MAV_FRAME_GLOBAL,
        2 => MavFrame::MAV_FRAME_MISSION,
        3 => MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT,
        5 => MavFrame::MAV_FRAME_GLOBAL_INT,
        _ => MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
    }
}

impl MissionReply {
    /// Encodes the reply to `to` (system, component) into `out`.
    pub fn encode(&self, to: (u8, u8), encoder: &mut Encoder, out: &mut Frame) {
        let (target_system, target_component) = to;
        match *self {
            Self::Request { seq, mission_type } => encoder.encode_extended(
                &MISSION_REQUEST_INT_DATA {
                    seq,
                    target_system,
                    target_component,
                },
                &[mission_type],
                out,
            ),
            Self::Ack {
                result,
                mission_type,
            } => encoder.encode_extended(
                &MISSION_ACK_DATA {
                    target_system,
                    target_component,
                    mavtype: result,
                },
                &[mission_type],
                out,
            ),
            Self::Count {
                count,
                mission_type,
            } => encoder.encode_extended(
                &MISSION_COUNT_DATA {
                    count,
                    target_system,
                    target_component,
                },
                &[mission_type],
                out,
            ),
            Self::Item { seq, item, current } => encoder.encode(
                &MISSION_ITEM_INT_DATA {
                    param1: item.params[0],
                    param2: item.params[1],
                    param3: item.params[2],
                    param4: item.params[3],
                    x: item.x,
                    y: item.y,
                    z: item.z,
                    seq,
                    command: mav_cmd(item.command),
                    target_system,
                    target_component,
                    frame: mav_frame(item.frame),
                    current: u8::from(current),
                    autocontinue: item.autocontinue,
                },
                out,
            ),
        }
    }
}

/// `MISSION_CURRENT`'s `mission_state`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum MissionProgress {
    /// No items.
    NoMission = 1,
    /// Items, not flown yet.
    NotStarted = 2,
    /// Being flown.
    Active = 3,
    /// Held in flight.
    Paused = 4,
    /// Flown to its end.
    Complete = 5,
}

/// `MISSION_CURRENT` (with its `total`, `mission_state` and `mission_mode` extensions).
pub fn encode_current(
    seq: u16,
    total: u16,
    progress: MissionProgress,
    in_mission_mode: bool,
    encoder: &mut Encoder,
    out: &mut Frame,
) {
    let t = total.to_le_bytes();
    let mode = if in_mission_mode { 1 } else { 2 };
    encoder.encode_extended(
        &MISSION_CURRENT_DATA { seq },
        &[t[0], t[1], progress as u8, mode],
        out,
    );
}

/// `MISSION_ITEM_REACHED`.
pub fn encode_reached(seq: u16, encoder: &mut Encoder, out: &mut Frame) {
    encoder.encode(&MISSION_ITEM_REACHED_DATA { seq }, out);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Parser;

    fn round_trip(reply: MissionReply) -> Frame {
        let mut enc = Encoder::new(crate::VEHICLE_SYSTEM_ID, crate::VEHICLE_COMPONENT_ID);
        let mut f = Frame::default();
        reply.encode((255, 190), &mut enc, &mut f);
        let mut p = Parser::new(crate::vehicle::crc_extra);
        let mut out = None;
        for &b in f.bytes() {
            if let Some((frame, _)) = p.push(b) {
                out = Some(frame.clone());
            }
        }
        out.expect("a frame")
    }

    #[test]
    fn an_item_reads_back_as_it_was_written() {
        let item = WireItem {
            command: 16,
            frame: 6,
            autocontinue: 1,
            params: [0.0, 0.5, 0.0, f32::NAN],
            x: 356_812_000,
            y: 1_397_671_000,
            z: 0.5,
        };
        let f = round_trip(MissionReply::Item {
            seq: 3,
            item,
            current: false,
        });
        let Some((
            MissionMessage::Item {
                seq, item: back, ..
            },
            ts,
            tc,
        )) = read(&f)
        else {
            panic!("not an item");
        };
        assert_eq!((seq, ts, tc), (3, 255, 190));
        assert_eq!(back.to_bytes(), item.to_bytes());
        assert_eq!(
            WireItem::from_bytes(&item.to_bytes()).to_bytes(),
            item.to_bytes()
        );
    }

    #[test]
    fn the_mission_type_extension_goes_out_and_comes_back() {
        let f = round_trip(MissionReply::Count {
            count: 0,
            mission_type: 2,
        });
        assert_eq!(
            read(&f).map(|r| r.0),
            Some(MissionMessage::Count {
                count: 0,
                mission_type: 2
            })
        );
        let f = round_trip(MissionReply::Ack {
            result: MavMissionResult::MAV_MISSION_UNSUPPORTED,
            mission_type: 1,
        });
        assert_eq!(
            read(&f).map(|r| r.0),
            Some(MissionMessage::Ack {
                result: 3,
                mission_type: 1
            })
        );
    }
}
