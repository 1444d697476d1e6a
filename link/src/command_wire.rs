//! `COMMAND_LONG`, `COMMAND_INT` and `COMMAND_ACK` with the command as its number (MAVLink's
//! `MAV_CMD`, any `u16`), for the vehicle's command service (every command gets its
//! `COMMAND_ACK`; docs/ground-link.md#commands-long-or-int).
//!
//! The `mavlink` crate decodes a command into its `MavCmd` enum: a command number the dialect
//! does not list fails to decode (so it could not be acknowledged), and the conversion is a
//! 2,000-entry jump table that cost the firmware 3.4 KiB of flash. These two types have the
//! crate's wire layout, `CRC_EXTRA` and MAVLink 2 zero truncation, checked against the crate's
//! own encoding in the tests; the ground side keeps using the crate's types.
//! (`COMMAND_INT`'s frame is a `MAV_FRAME` the crate's enum may not list either: kept as its
//! number.)

use mavlink::{MavlinkVersion, MessageData, error::ParserError};

use crate::msg::{
    COMMAND_ACK_DATA, COMMAND_INT_DATA, COMMAND_LONG_DATA, MavCmd, MavMessage, MavResult,
};

/// A MAVLink command number (`MAV_CMD`), as sent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CommandId(pub u16);

impl CommandId {
    /// The number of `command`.
    pub const fn of(command: MavCmd) -> Self {
        Self(command as u16)
    }

    /// Whether this is `command`.
    pub const fn is(self, command: MavCmd) -> bool {
        self.0 == command as u16
    }
}

/// `COMMAND_LONG` as the vehicle reads it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CommandLong {
    /// Parameters 1 to 7.
    pub params: [f32; 7],
    /// The command's number.
    pub command: u16,
    /// Target system.
    pub target_system: u8,
    /// Target component.
    pub target_component: u8,
    /// Transmission count (0 the first time).
    pub confirmation: u8,
}

impl MessageData for CommandLong {
    type Message = MavMessage;
    const ID: u32 = COMMAND_LONG_DATA::ID;
    const NAME: &'static str = COMMAND_LONG_DATA::NAME;
    const EXTRA_CRC: u8 = COMMAND_LONG_DATA::EXTRA_CRC;
    const ENCODED_LEN: usize = COMMAND_LONG_DATA::ENCODED_LEN;

    fn ser(&self, version: MavlinkVersion, payload: &mut [u8]) -> usize {
        let mut bytes = [0u8; Self::ENCODED_LEN];
        for (i, p) in self.params.iter().enumerate() {
            bytes[4 * i..4 * i + 4].copy_from_slice(&p.to_le_bytes());
        }
        bytes[28..30].copy_from_slice(&self.command.to_le_bytes());
        bytes[30] = self.target_system;
        bytes[31] = self.target_component;
        bytes[32] = self.confirmation;
        put(&bytes, version, payload)
    }

    fn deser(_version: MavlinkVersion, payload: &[u8]) -> Result<Self, ParserError> {
        // MAVLink 2 cuts a payload's trailing zeros: the missing bytes are zeros.
        let mut bytes = [0u8; Self::ENCODED_LEN];
        let n = payload.len().min(Self::ENCODED_LEN);
        bytes[..n].copy_from_slice(&payload[..n]);
        let mut params = [0.0; 7];
        for (i, p) in params.iter_mut().enumerate() {
            *p = f32::from_le_bytes([
                bytes[4 * i],
                bytes[4 * i + 1],
                bytes[4 * i + 2],
                bytes[4 * i + 3],
            ]);
        }
        Ok(Self {
            params,
            command: u16::from_le_bytes([bytes[28], bytes[29]]),
            target_system: bytes[30],
            target_component: bytes[31],
            confirmation: bytes[32],
        })
    }
}

/// `COMMAND_INT` as the vehicle reads it: parameters 1 to 4 as floats, 5 and 6 as integers
/// (`x`, `y`: latitude and longitude in 1e-7 degrees in a global frame), 7 a float (`z`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CommandInt {
    /// Parameters 1 to 4.
    pub params: [f32; 4],
    /// Parameter 5.
    pub x: i32,
    /// Parameter 6.
    pub y: i32,
    /// Parameter 7.
    pub z: f32,
    /// The command's number.
    pub command: u16,
    /// Target system.
    pub target_system: u8,
    /// Target component.
    pub target_component: u8,
    /// The coordinate frame of `x`, `y`, `z` (`MAV_FRAME`, as sent).
    pub frame: u8,
    /// Not used.
    pub current: u8,
    /// Not used.
    pub autocontinue: u8,
}

impl MessageData for CommandInt {
    type Message = MavMessage;
    const ID: u32 = COMMAND_INT_DATA::ID;
    const NAME: &'static str = COMMAND_INT_DATA::NAME;
    const EXTRA_CRC: u8 = COMMAND_INT_DATA::EXTRA_CRC;
    const ENCODED_LEN: usize = COMMAND_INT_DATA::ENCODED_LEN;

    fn ser(&self, version: MavlinkVersion, payload: &mut [u8]) -> usize {
        let mut bytes = [0u8; Self::ENCODED_LEN];
        for (i, p) in self.params.iter().enumerate() {
            bytes[4 * i..4 * i + 4].copy_from_slice(&p.to_le_bytes());
        }
        bytes[16..20].copy_from_slice(&self.x.to_le_bytes());
        bytes[20..24].copy_from_slice(&self.y.to_le_bytes());
        bytes[24..28].copy_from_slice(&self.z.to_le_bytes());
        bytes[28..30].copy_from_slice(&self.command.to_le_bytes());
        bytes[30] = self.target_system;
        bytes[31] = self.target_component;
        bytes[32] = self.frame;
        bytes[33] = self.current;
        bytes[34] = self.autocontinue;
        put(&bytes, version, payload)
    }

    fn deser(_version: MavlinkVersion, payload: &[u8]) -> Result<Self, ParserError> {
        // MAVLink 2 cuts a payload's trailing zeros: the missing bytes are zeros.
        let mut bytes = [0u8; Self::ENCODED_LEN];
        let n = payload.len().min(Self::ENCODED_LEN);
        bytes[..n].copy_from_slice(&payload[..n]);
        let word = |at: usize| [bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]];
        let mut params = [0.0; 4];
        for (i, p) in params.iter_mut().enumerate() {
            *p = f32::from_le_bytes(word(4 * i));
        }
        Ok(Self {
            params,
            x: i32::from_le_bytes(word(16)),
            y: i32::from_le_bytes(word(20)),
            z: f32::from_le_bytes(word(24)),
            command: u16::from_le_bytes([bytes[28], bytes[29]]),
            target_system: bytes[30],
            target_component: bytes[31],
            frame: bytes[32],
            current: bytes[33],
            autocontinue: bytes[34],
        })
    }
}

/// `COMMAND_ACK` of a command number (its extension fields, progress and target, left out: a
/// ground station matches acknowledgements by command).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CommandAck {
    /// The command acknowledged.
    pub command: CommandId,
    /// How it was taken.
    pub result: MavResult,
}

impl MessageData for CommandAck {
    type Message = MavMessage;
    const ID: u32 = COMMAND_ACK_DATA::ID;
    const NAME: &'static str = COMMAND_ACK_DATA::NAME;
    const EXTRA_CRC: u8 = COMMAND_ACK_DATA::EXTRA_CRC;
    const ENCODED_LEN: usize = COMMAND_ACK_DATA::ENCODED_LEN;

    fn ser(&self, version: MavlinkVersion, payload: &mut [u8]) -> usize {
        let c = self.command.0.to_le_bytes();
        put(&[c[0], c[1], self.result as u8], version, payload)
    }

    fn deser(version: MavlinkVersion, payload: &[u8]) -> Result<Self, ParserError> {
        // The result through the crate's decoder of a known command (the result is all it
        // reads of it), the command as sent.
        let mut known = [0u8; Self::ENCODED_LEN];
        let n = payload.len().min(Self::ENCODED_LEN);
        known[..n].copy_from_slice(&payload[..n]);
        let command = CommandId(u16::from_le_bytes([known[0], known[1]]));
        known[..2].copy_from_slice(&(MavCmd::MAV_CMD_NAV_WAYPOINT as u16).to_le_bytes());
        let ack = COMMAND_ACK_DATA::deser(version, &known)?;
        Ok(Self {
            command,
            result: ack.result,
        })
    }
}

/// Copies `bytes` into `payload` and returns the length to send: MAVLink 2 cuts trailing zeros
/// (keeping at least one byte), MAVLink 1 sends them all.
fn put(bytes: &[u8], version: MavlinkVersion, payload: &mut [u8]) -> usize {
    let n = bytes.len().min(payload.len());
    payload[..n].copy_from_slice(&bytes[..n]);
    match version {
        MavlinkVersion::V1 => n,
        MavlinkVersion::V2 => {
            let mut len = n;
            while len > 1 && payload[len - 1] == 0 {
                len -= 1;
            }
            len
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn crate_bytes<M: MessageData>(m: &M, version: MavlinkVersion) -> std::vec::Vec<u8> {
        let mut buf = [0u8; 255];
        let n = m.ser(version, &mut buf);
        buf[..n].to_vec()
    }

    #[test]
    fn command_long_reads_what_the_crate_writes_and_writes_it_back_the_same() {
        let sent = COMMAND_LONG_DATA {
            param1: 1.5,
            param2: -2.0,
            param3: 3.25,
            param4: 0.0,
            param5: 5.0,
            param6: 6.0,
            param7: 0.0,
            command: MavCmd::MAV_CMD_DO_FLIGHTTERMINATION,
            target_system: 1,
            target_component: 0,
            confirmation: 0,
        };
        for version in [MavlinkVersion::V1, MavlinkVersion::V2] {
            let bytes = crate_bytes(&sent, version);
            let read = CommandLong::deser(version, &bytes).expect("decodes");
            assert_eq!(read.params, [1.5, -2.0, 3.25, 0.0, 5.0, 6.0, 0.0]);
            assert!(CommandId(read.command).is(MavCmd::MAV_CMD_DO_FLIGHTTERMINATION));
            assert_eq!((read.target_system, read.target_component), (1, 0));
            assert_eq!(crate_bytes(&read, version), bytes);
        }
        // MAVLink 2 cut this one's zero target component and confirmation.
        assert_eq!(crate_bytes(&sent, MavlinkVersion::V2).len(), 31);
    }

    #[test]
    fn command_int_reads_what_the_crate_writes_and_writes_it_back_the_same() {
        let sent = COMMAND_INT_DATA {
            param1: 1.5,
            param2: f32::NAN,
            param3: -3.25,
            param4: 0.0,
            x: -338_688_123,
            y: 1_512_093_456,
            z: 58.5,
            command: MavCmd::MAV_CMD_DO_SET_GLOBAL_ORIGIN,
            target_system: 1,
            target_component: 1,
            frame: crate::msg::MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT,
            current: 0,
            autocontinue: 0,
        };
        for version in [MavlinkVersion::V1, MavlinkVersion::V2] {
            let bytes = crate_bytes(&sent, version);
            let read = CommandInt::deser(version, &bytes).expect("decodes");
            assert_eq!(read.params[0], 1.5);
            assert!(read.params[1].is_nan());
            assert_eq!(read.params[2..], [-3.25, 0.0]);
            assert_eq!(
                (read.x, read.y, read.z),
                (-338_688_123, 1_512_093_456, 58.5)
            );
            assert!(CommandId(read.command).is(MavCmd::MAV_CMD_DO_SET_GLOBAL_ORIGIN));
            assert_eq!((read.target_system, read.target_component), (1, 1));
            assert_eq!(
                read.frame,
                crate::msg::MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT as u8
            );
            assert_eq!(crate_bytes(&read, version), bytes);
        }
        // MAVLink 2 cut the zero `current` and `autocontinue`.
        assert_eq!(crate_bytes(&sent, MavlinkVersion::V2).len(), 33);
        // A frame and a command the dialect does not list keep their numbers.
        let mut bytes = crate_bytes(&sent, MavlinkVersion::V2);
        bytes[28..30].copy_from_slice(&0xfffe_u16.to_le_bytes());
        bytes[32] = 0xee;
        let read = CommandInt::deser(MavlinkVersion::V2, &bytes).expect("decodes");
        assert_eq!((read.command, read.frame), (0xfffe, 0xee));
        // Cut short (a hostile sender): the missing bytes are zeros.
        let short = CommandInt::deser(MavlinkVersion::V2, &bytes[..3]).expect("decodes");
        assert_eq!((short.command, short.target_system, short.x), (0, 0, 0));
    }

    #[test]
    fn a_command_the_dialect_does_not_list_still_decodes_with_its_number() {
        let mut bytes = [0u8; 33];
        bytes[28..30].copy_from_slice(&0xfffe_u16.to_le_bytes());
        bytes[30] = 1;
        assert!(COMMAND_LONG_DATA::deser(MavlinkVersion::V2, &bytes).is_err());
        let read = CommandLong::deser(MavlinkVersion::V2, &bytes[..31]).expect("decodes");
        assert_eq!(read.command, 0xfffe);
        assert_eq!(read.target_system, 1);
    }

    #[test]
    fn command_ack_writes_what_the_crate_writes() {
        let ours = CommandAck {
            command: CommandId::of(MavCmd::MAV_CMD_MISSION_START),
            result: MavResult::MAV_RESULT_DENIED,
        };
        let crates = COMMAND_ACK_DATA {
            command: MavCmd::MAV_CMD_MISSION_START,
            result: MavResult::MAV_RESULT_DENIED,
        };
        for version in [MavlinkVersion::V1, MavlinkVersion::V2] {
            let bytes = crate_bytes(&crates, version);
            assert_eq!(crate_bytes(&ours, version), bytes);
            assert_eq!(CommandAck::deser(version, &bytes).expect("decodes"), ours);
        }
        // An accepted command 0 is all zeros: MAVLink 2 keeps one byte.
        let zero = CommandAck {
            command: CommandId(0),
            result: MavResult::MAV_RESULT_ACCEPTED,
        };
        assert_eq!(crate_bytes(&zero, MavlinkVersion::V2), [0]);
    }

    #[test]
    fn an_unknown_commands_ack_keeps_its_number() {
        let ack = CommandAck {
            command: CommandId(0xfffe),
            result: MavResult::MAV_RESULT_UNSUPPORTED,
        };
        let bytes = crate_bytes(&ack, MavlinkVersion::V2);
        assert_eq!(bytes, [0xfe, 0xff, MavResult::MAV_RESULT_UNSUPPORTED as u8]);
        assert_eq!(
            CommandAck::deser(MavlinkVersion::V2, &bytes).expect("decodes"),
            ack
        );
    }
}
