//! How much of the CAN bus the ESCs' traffic takes: each frame's length on the wire, bit
//! stuffing included (ISO 11898-1, CAN 2.0B), and the share of the bit rate a set of frames
//! sent at their rates needs.
//!
//! An extended data frame is SOF, the identifier's 11 high bits, SRR, IDE, its 18 low bits,
//! RTR, two reserved bits, the 4-bit data length, the data, the 15-bit CRC (polynomial 0x4599
//! over everything before it), then 13 bits never stuffed: CRC and ACK delimiters, the ACK
//! slot, 7 bits of end of frame and 3 of interframe space. From SOF to the CRC's last bit, the
//! sender inserts the opposite bit after every five equal ones (the inserted bit counting in
//! the next run). So 67 + 8 n bits and the stuff bits the frame's own bits call for.

use super::esc::{
    EscStatus, MAX_COMMANDS, RAW_COMMAND_ID, RAW_COMMAND_SIGNATURE, encode_raw_command,
};
use super::node_status::{Health, Mode, NODE_STATUS_ID, NODE_STATUS_SIGNATURE, NodeStatus};
use super::transfer::{CanFrame, MAX_PAYLOAD, MessageId, frames};

/// The CAN bus's bit rate on the Pixhawk 6C's CAN1, bit/s (DroneCAN's usual 1 Mbit/s).
pub const BIT_RATE: u32 = 1_000_000;

/// Bits after the CRC that are never stuffed.
const UNSTUFFED_TAIL: u32 = 13;

/// The bits of one extended data frame from SOF to the end of its CRC, before stuffing.
struct FrameBits {
    bits: [bool; 160],
    len: usize,
}

impl FrameBits {
    fn push(&mut self, value: u64, width: u32) {
        for k in (0..width).rev() {
            self.bits[self.len] = value >> k & 1 == 1;
            self.len += 1;
        }
    }
}

/// CRC-15/CAN of a bit sequence.
fn crc15(bits: &[bool]) -> u16 {
    let mut crc: u16 = 0;
    for &bit in bits {
        let feedback = bit ^ (crc >> 14 & 1 == 1);
        crc = (crc << 1) & 0x7fff;
        if feedback {
            crc ^= 0x4599;
        }
    }
    crc
}

/// The stuff bits a sender inserts into `bits`.
fn stuff_bits(bits: &[bool]) -> u32 {
    let (mut stuffed, mut run, mut last) = (0, 0, None);
    for &bit in bits {
        if Some(bit) == last {
            run += 1;
        } else {
            (run, last) = (1, Some(bit));
        }
        if run == 5 {
            stuffed += 1;
            (run, last) = (1, Some(!bit));
        }
    }
    stuffed
}

/// The frame's length on the wire, bits: its fields, its stuff bits, and the interframe
/// space after it.
pub fn wire_bits(frame: &CanFrame) -> u32 {
    let len = u64::from(frame.len.min(8));
    let id = u64::from(frame.id & 0x1fff_ffff);
    let mut f = FrameBits {
        bits: [false; 160],
        len: 0,
    };
    f.push(0, 1); // SOF
    f.push(id >> 18, 11);
    f.push(0b11, 2); // SRR, IDE
    f.push(id & 0x3_ffff, 18);
    f.push(0, 3); // RTR (data), r1, r0
    f.push(len, 4);
    for &byte in frame.bytes() {
        f.push(u64::from(byte), 8);
    }
    let crc = crc15(&f.bits[..f.len]);
    f.push(u64::from(crc), 15);
    f.len as u32 + stuff_bits(&f.bits[..f.len]) + UNSTUFFED_TAIL
}

/// A bus's traffic: frames and their bits, over a time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BusLoad {
    /// Frames counted.
    pub frames: u64,
    /// Their bits on the wire.
    pub bits: u64,
}

impl BusLoad {
    /// Counts `frame`, sent `times` times.
    pub fn add(&mut self, frame: &CanFrame, times: u64) {
        self.frames += times;
        self.bits += times * u64::from(wire_bits(frame));
    }

    /// Frames a second, when the counted frames took `seconds`.
    pub fn frames_per_second(&self, seconds: f32) -> f32 {
        self.frames as f32 / seconds
    }

    /// The share of [`BIT_RATE`] the counted frames took over `seconds` (0 to 1 fits).
    pub fn share(&self, seconds: f32) -> f32 {
        self.bits as f32 / (seconds * BIT_RATE as f32)
    }
}

/// `RawCommand`s a second: one per control step, PX4's `UavcanEscController::MAX_RATE_HZ`.
pub const COMMAND_HZ: u32 = 400;

/// `Status` messages a second from each ESC, the rate the ESCs are set to send at: at 100 Hz
/// sixteen ESCs and the commands would take 85 % of the bus, at 50 Hz 55 % (the bus-load
/// test prints the table).
pub const STATUS_HZ: u32 = 50;

/// The traffic of one second with `escs` ESCs (at most [`MAX_COMMANDS`]): a `RawCommand` at
/// `command_hz` from the flight controller, a `Status` at `status_hz` and a `NodeStatus` at
/// 1 Hz from each ESC and the flight controller. The frames carry a hover's values (commands
/// near 45 %, 7,400 RPM at 15.8 V), since a frame's stuff bits depend on its bits.
pub fn esc_traffic(escs: usize, command_hz: u32, status_hz: u32) -> BusLoad {
    let escs = escs.min(MAX_COMMANDS);
    let mut load = BusLoad::default();
    let mut buffer = [0u8; MAX_PAYLOAD];
    let mut commands = [0i16; MAX_COMMANDS];
    for (k, c) in commands.iter_mut().enumerate().take(escs) {
        *c = 3500 + 37 * k as i16;
    }
    let Ok(len) = encode_raw_command(&commands[..escs], &mut buffer) else {
        return load;
    };
    let fc = |priority, data_type| MessageId {
        priority,
        data_type,
        source: 1,
    };
    for tick in 0..command_hz {
        for frame in frames(
            fc(5, RAW_COMMAND_ID),
            RAW_COMMAND_SIGNATURE,
            tick as u8,
            &buffer[..len],
        ) {
            load.add(&frame, 1);
        }
    }
    for k in 0..=escs {
        let node = (10 + k) as u8;
        let heartbeat = NodeStatus {
            uptime_sec: 600 + k as u32,
            health: Health::Ok,
            mode: Mode::Operational,
            sub_mode: 0,
            vendor_specific_status_code: 0,
        };
        if let Ok(len) = heartbeat.encode(&mut buffer) {
            let id = MessageId {
                source: if k == escs { 1 } else { node },
                ..fc(16, NODE_STATUS_ID)
            };
            for frame in frames(id, NODE_STATUS_SIGNATURE, 0, &buffer[..len]) {
                load.add(&frame, 1);
            }
        }
        if k == escs {
            break;
        }
        let status = EscStatus {
            error_count: 0,
            voltage: 15.8 - 0.01 * k as f32,
            current: 6.2 + 0.1 * k as f32,
            temperature: 310.0,
            rpm: 7400 + 13 * k as i32,
            power_rating_pct: 38,
            esc_index: k as u8,
        };
        for transfer in 0..status_hz {
            status.send(node, transfer as u8, |frame| load.add(&frame, 1));
        }
    }
    load
}

#[cfg(test)]
mod tests {
    use super::*;
    use crc::{CRC_15_CAN, Crc};

    fn bits_of(bytes: &[u8]) -> std::vec::Vec<bool> {
        bytes
            .iter()
            .flat_map(|b| (0..8).rev().map(move |k| b >> k & 1 == 1))
            .collect()
    }

    #[test]
    fn sixteen_escs_take_at_most_60_percent_of_the_bus() {
        std::println!("DroneCAN ESC traffic on a {} bit/s bus:", BIT_RATE);
        for escs in [8, 12, 16] {
            for status_hz in [25, STATUS_HZ, 100] {
                let load = esc_traffic(escs, COMMAND_HZ, status_hz);
                std::println!(
                    "  {escs} ESCs, commands at {COMMAND_HZ} Hz, Status at {status_hz} Hz: \
                     {} frames/s, {:.1} % of the bus",
                    load.frames,
                    100.0 * load.share(1.0)
                );
            }
        }
        let sixteen = esc_traffic(16, COMMAND_HZ, STATUS_HZ);
        // 400 RawCommands of 5 frames, 16 x 50 Statuses of 3, 17 NodeStatuses of 1.
        assert_eq!(sixteen.frames, 400 * 5 + 16 * 50 * 3 + 17);
        assert!(sixteen.share(1.0) <= 0.60, "{}", sixteen.share(1.0));
        let twice = esc_traffic(16, COMMAND_HZ, 2 * STATUS_HZ);
        assert!(twice.share(1.0) > 0.60, "Status at 100 Hz does not fit");
        assert!(esc_traffic(8, COMMAND_HZ, STATUS_HZ).share(1.0) < sixteen.share(1.0));
    }

    #[test]
    fn the_frame_crc_is_crc15_can() {
        let check = Crc::<u16>::new(&CRC_15_CAN);
        assert_eq!(
            crc15(&bits_of(b"123456789")),
            0x059e,
            "CRC-15/CAN's check value"
        );
        for data in [&b"DroneCAN"[..], &[0u8; 8], &[0xff; 3]] {
            assert_eq!(crc15(&bits_of(data)), check.checksum(data));
        }
    }

    #[test]
    fn a_stuff_bit_follows_five_equal_bits_and_starts_the_next_run() {
        let b = |s: &str| s.chars().map(|c| c == '1').collect::<std::vec::Vec<_>>();
        assert_eq!(stuff_bits(&b("0000")), 0);
        assert_eq!(stuff_bits(&b("00000")), 1);
        assert_eq!(stuff_bits(&b("0000000000")), 2);
        // The stuffed 1 after five zeros runs on with the four ones after it: another stuff.
        assert_eq!(stuff_bits(&b("000001111")), 2);
        assert_eq!(stuff_bits(&b("0101010101")), 0);
    }
}
