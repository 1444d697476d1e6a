//! The log as a file: its start (header, definitions, subscriptions), written by the
//! storing side when a mission's log opens; the messages after it come from the control step
//! ([`super::stream`]).

use super::topics::Topic;
use crate::ulog::{Message, UlogError, file_header};
use shared::mission::MissionConfig;
use shared::mission::params::TABLE;

/// `sys_name` of the vehicle's logs, the firmware's and the simulator's alike.
pub const SYS_NAME: &str = "rail-transport";

/// What the log's information section says of the vehicle.
#[derive(Clone, Copy, Debug)]
pub struct LogInfo<'a> {
    /// `sys_name`: the flight stack's name.
    pub sys_name: &'a str,
    /// `ver_sw`: the software's version (a git hash where there is one).
    pub ver_sw: &'a str,
    /// `ver_hw`: the board.
    pub ver_hw: &'a str,
    /// When the log starts, us (the flight controller's clock).
    pub start_us: u64,
}

/// Writes the log's start to `out`: the file header, the flag bits, every topic's format,
/// the information, every parameter as `config` has it (PX4's types: `int32_t` for the
/// integer ones, `float` for the rest) and a subscription to every topic.
pub fn write_start(
    info: &LogInfo,
    config: &MissionConfig,
    out: &mut impl FnMut(&[u8]),
) -> Result<(), UlogError> {
    out(&file_header(info.start_us));
    out(Message::flag_bits().as_bytes());
    for topic in Topic::ALL {
        out(Message::format(topic.format())?.as_bytes());
    }
    out(Message::info_text("sys_name", info.sys_name)?.as_bytes());
    out(Message::info_text("ver_sw", info.ver_sw)?.as_bytes());
    out(Message::info_text("ver_hw", info.ver_hw)?.as_bytes());
    for spec in &TABLE {
        let value = (spec.get)(config);
        let message = if spec.integer {
            Message::parameter_i32(spec.name, value as i32)?
        } else {
            Message::parameter_f32(spec.name, value)?
        };
        out(message.as_bytes());
    }
    for topic in Topic::ALL {
        out(Message::add_subscription(0, topic.msg_id(), topic.name())?.as_bytes());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    #[test]
    fn the_start_holds_every_format_parameter_and_subscription() {
        let mut bytes = Vec::new();
        let info = LogInfo {
            sys_name: "rail-transport",
            ver_sw: "abc123",
            ver_hw: "PX4_FMU_V6C",
            start_us: 5,
        };
        write_start(&info, &MissionConfig::DEFAULT, &mut |b| {
            bytes.extend_from_slice(b)
        })
        .expect("fits");
        assert_eq!(&bytes[..4], b"ULog");
        // Walk the messages after the header: each one's size says where the next begins.
        let mut at = 16;
        let mut kinds = Vec::new();
        while at < bytes.len() {
            let size = u16::from_le_bytes([bytes[at], bytes[at + 1]]) as usize;
            kinds.push(bytes[at + 2]);
            at += 3 + size;
        }
        assert_eq!(at, bytes.len());
        assert_eq!(kinds[0], b'B');
        let count = |k: u8| kinds.iter().filter(|&&x| x == k).count();
        assert_eq!(count(b'F'), Topic::ALL.len());
        assert_eq!(count(b'A'), Topic::ALL.len());
        assert_eq!(count(b'P'), TABLE.len());
        assert_eq!(count(b'I'), 3);
        // Definitions before data: every 'A' after every 'F', 'I' and 'P'.
        let first_a = kinds.iter().position(|&k| k == b'A').expect("an A");
        assert!(kinds[first_a..].iter().all(|&k| k == b'A'));
    }
}
