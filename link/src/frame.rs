//! MAVLink framing (MAVLink serialization spec, "Packet format"): a parser that takes bytes one
//! at a time from any stream and hands back whole frames whose checksum holds, and an encoder
//! for MAVLink 2 frames.
//!
//! The payload encoding, the CRC-16/MCRF4XX checksum and each message's `CRC_EXTRA` are the
//! `mavlink` crate's; only the byte-stream state machine is here, because the crate's readers
//! need `std::io` or `embedded-io`, and this crate is used under both.
//!
//! Frames of messages whose `CRC_EXTRA` the caller does not know cannot be verified: they come
//! back marked [`Integrity::Unverified`] (a bridge forwards them as they are; the vehicle drops
//! them). Frames with a bad checksum, unsupported incompatibility flags or a truncated body are
//! dropped and counted; the parser then looks for the next start byte.

use mavlink::{MavlinkVersion, MessageData, calculate_crc};

/// Largest MAVLink frame, bytes (MAVLink 2 with signature).
pub const MAX_FRAME_LEN: usize = 280;
/// MAVLink 2 start byte.
pub const STX_V2: u8 = 0xFD;
/// MAVLink 1 start byte.
pub const STX_V1: u8 = 0xFE;
use crate::signing::{IFLAG_SIGNED, SIGNATURE_LEN};
/// MAVLink 2 header after the start byte: len, incompat, compat, seq, sysid, compid, msgid[3].
const V2_HEADER: usize = 9;
/// MAVLink 1 header after the start byte: len, seq, sysid, compid, msgid.
const V1_HEADER: usize = 5;

/// One whole MAVLink frame, as received or as encoded.
#[derive(Clone)]
pub struct Frame {
    bytes: [u8; MAX_FRAME_LEN],
    len: usize,
}

impl Default for Frame {
    fn default() -> Self {
        Self {
            bytes: [0; MAX_FRAME_LEN],
            len: 0,
        }
    }
}

impl core::fmt::Debug for Frame {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Frame")
            .field("msgid", &self.message_id())
            .field("len", &self.len)
            .finish()
    }
}

impl Frame {
    /// The frame's bytes, start byte to checksum (and signature).
    pub fn bytes(&self) -> &[u8] {
        &self.bytes[..self.len]
    }

    /// MAVLink version of the frame.
    pub fn version(&self) -> MavlinkVersion {
        if self.bytes[0] == STX_V1 {
            MavlinkVersion::V1
        } else {
            MavlinkVersion::V2
        }
    }

    fn header_len(&self) -> usize {
        1 + if self.bytes[0] == STX_V1 {
            V1_HEADER
        } else {
            V2_HEADER
        }
    }

    /// Payload length, bytes.
    pub fn payload_len(&self) -> usize {
        usize::from(self.bytes[1])
    }

    /// The payload (MAVLink 2 truncates trailing zeros; the decoders put them back).
    pub fn payload(&self) -> &[u8] {
        let start = self.header_len();
        &self.bytes[start..start + self.payload_len()]
    }

    /// Sequence number.
    pub fn sequence(&self) -> u8 {
        match self.version() {
            MavlinkVersion::V1 => self.bytes[2],
            MavlinkVersion::V2 => self.bytes[4],
        }
    }

    /// Sender's system id.
    pub fn system_id(&self) -> u8 {
        match self.version() {
            MavlinkVersion::V1 => self.bytes[3],
            MavlinkVersion::V2 => self.bytes[5],
        }
    }

    /// Sender's component id.
    pub fn component_id(&self) -> u8 {
        match self.version() {
            MavlinkVersion::V1 => self.bytes[4],
            MavlinkVersion::V2 => self.bytes[6],
        }
    }

    /// Message id.
    pub fn message_id(&self) -> u32 {
        if self.len == 0 {
            return 0;
        }
        match self.version() {
            MavlinkVersion::V1 => u32::from(self.bytes[5]),
            MavlinkVersion::V2 => {
                u32::from_le_bytes([self.bytes[7], self.bytes[8], self.bytes[9], 0])
            }
        }
    }

    /// Signs this MAVLink 2 frame (unsigned, as encoded or received): sets the signed flag,
    /// recomputes the checksum with `crc_extra`, and appends what `signature` makes of the
    /// frame so far (start byte to checksum). `false`, and the frame unchanged, for a MAVLink 1
    /// or already signed frame.
    pub fn append_signature(
        &mut self,
        crc_extra: u8,
        signature: impl FnOnce(&[u8]) -> [u8; SIGNATURE_LEN],
    ) -> bool {
        let header = 1 + V2_HEADER;
        if self.len < header + 2
            || self.bytes[0] != STX_V2
            || self.bytes[2] & IFLAG_SIGNED != 0
            || self.len + SIGNATURE_LEN > MAX_FRAME_LEN
        {
            return false;
        }
        self.bytes[2] |= IFLAG_SIGNED;
        let crc_end = self.len - 2;
        let crc = calculate_crc(&self.bytes[1..crc_end], crc_extra);
        self.bytes[crc_end..self.len].copy_from_slice(&crc.to_le_bytes());
        let tail = signature(&self.bytes[..self.len]);
        self.bytes[self.len..self.len + SIGNATURE_LEN].copy_from_slice(&tail);
        self.len += SIGNATURE_LEN;
        true
    }

    /// The message, if this frame carries an `M` that decodes.
    pub fn decode<M: MessageData>(&self) -> Option<M> {
        if self.message_id() != M::ID {
            return None;
        }
        M::deser(self.version(), self.payload()).ok()
    }
}

/// Whether a received frame's checksum was verified.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrity {
    /// The checksum, with the message's `CRC_EXTRA`, holds.
    Verified,
    /// The message is unknown to the caller, so its checksum could not be checked.
    Unverified,
}

/// Counters of what the parser threw away.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ParserStats {
    /// Frames handed back.
    pub frames: u32,
    /// Frames dropped for a wrong checksum.
    pub bad_checksums: u32,
    /// Frames dropped for incompatibility flags this parser does not support.
    pub unsupported: u32,
    /// Bytes skipped while looking for a start byte.
    pub skipped_bytes: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// Looking for a start byte.
    Idle,
    /// Collecting the frame; `need` is its total length once the header is in (0 before).
    Collecting { need: usize },
}

/// Byte-stream parser of MAVLink 1 and 2 frames.
pub struct Parser {
    crc_extra: fn(u32) -> Option<u8>,
    state: State,
    frame: Frame,
    stats: ParserStats,
}

impl Parser {
    /// A parser that verifies frames with `crc_extra` (the `CRC_EXTRA` of each message id the
    /// caller knows, `None` for the others).
    pub fn new(crc_extra: fn(u32) -> Option<u8>) -> Self {
        Self {
            crc_extra,
            state: State::Idle,
            frame: Frame::default(),
            stats: ParserStats::default(),
        }
    }

    /// What was dropped so far.
    pub fn stats(&self) -> ParserStats {
        self.stats
    }

    /// Takes one byte; returns a frame when this byte completes one.
    pub fn push(&mut self, byte: u8) -> Option<(&Frame, Integrity)> {
        match self.state {
            State::Idle => {
                if byte == STX_V2 || byte == STX_V1 {
                    self.frame.bytes[0] = byte;
                    self.frame.len = 1;
                    self.state = State::Collecting { need: 0 };
                } else {
                    self.stats.skipped_bytes = self.stats.skipped_bytes.wrapping_add(1);
                }
                None
            }
            State::Collecting { need } => {
                let f = &mut self.frame;
                f.bytes[f.len] = byte;
                f.len += 1;
                let v1 = f.bytes[0] == STX_V1;
                let header = 1 + if v1 { V1_HEADER } else { V2_HEADER };
                if need == 0 {
                    if f.len < header {
                        return None;
                    }
                    let payload = usize::from(f.bytes[1]);
                    let mut total = header + payload + 2;
                    if !v1 {
                        let incompat = f.bytes[2];
                        if incompat & !IFLAG_SIGNED != 0 {
                            self.stats.unsupported = self.stats.unsupported.wrapping_add(1);
                            self.state = State::Idle;
                            return None;
                        }
                        if incompat & IFLAG_SIGNED != 0 {
                            total += SIGNATURE_LEN;
                        }
                    }
                    self.state = State::Collecting { need: total };
                    return None;
                }
                if f.len < need {
                    return None;
                }
                self.state = State::Idle;
                let payload = usize::from(f.bytes[1]);
                let crc_end = header + payload;
                let stored = u16::from_le_bytes([f.bytes[crc_end], f.bytes[crc_end + 1]]);
                let integrity = match (self.crc_extra)(f.message_id()) {
                    None => Integrity::Unverified,
                    Some(extra) => {
                        if calculate_crc(&f.bytes[1..crc_end], extra) != stored {
                            self.stats.bad_checksums = self.stats.bad_checksums.wrapping_add(1);
                            return None;
                        }
                        Integrity::Verified
                    }
                };
                self.stats.frames = self.stats.frames.wrapping_add(1);
                Some((&self.frame, integrity))
            }
        }
    }
}

/// Encodes MAVLink 2 frames from one sender, numbering them.
#[derive(Clone, Debug)]
pub struct Encoder {
    system_id: u8,
    component_id: u8,
    sequence: u8,
}

impl Encoder {
    /// An encoder for frames from `system_id`/`component_id`.
    pub const fn new(system_id: u8, component_id: u8) -> Self {
        Self {
            system_id,
            component_id,
            sequence: 0,
        }
    }

    /// Encodes `message` into `out` (unsigned MAVLink 2, trailing zeros of the payload cut).
    pub fn encode<M: MessageData>(&mut self, message: &M, out: &mut Frame) {
        self.encode_extended(message, &[], out);
    }

    /// Encodes `message` followed by the raw bytes of its MAVLink 2 extension fields
    /// (`extensions`, in the message definition's order), as the spec lays them out after the
    /// base fields.
    pub fn encode_extended<M: MessageData>(
        &mut self,
        message: &M,
        extensions: &[u8],
        out: &mut Frame,
    ) {
        let header = 1 + V2_HEADER;
        // A payload is at most 255 bytes and the frame buffer holds 255 after the header.
        let payload = &mut out.bytes[header..header + 255];
        // The base fields whole, as MAVLink 1 lays them out: the crate's `ser` differs between
        // the versions only in cutting MAVLink 2's trailing zeros (there are no extension
        // fields without its `mav2-message-extensions` feature, which the workspace leaves
        // off). The cut is made once, in `finish`, rather than by a copy of the loop in every
        // message type's `ser`; so is everything else that does not depend on the type.
        let len = message.ser(MavlinkVersion::V1, payload).min(255);
        self.finish(M::ID, M::EXTRA_CRC, len, extensions, out);
    }

    /// Appends `extensions` to the `len` bytes of base fields in `out`'s payload, cuts the
    /// trailing zeros and writes the header and the checksum around it.
    #[inline(never)]
    fn finish(&mut self, id: u32, crc_extra: u8, len: usize, extensions: &[u8], out: &mut Frame) {
        let header = 1 + V2_HEADER;
        let payload = &mut out.bytes[header..header + 255];
        let mut len = len;
        if !extensions.is_empty() {
            let end = (len + extensions.len()).min(255);
            payload[len..end].copy_from_slice(&extensions[..end - len]);
            len = end;
        }
        while len > 1 && payload[len - 1] == 0 {
            len -= 1;
        }
        let id = id.to_le_bytes();
        out.bytes[..header].copy_from_slice(&[
            STX_V2,
            len as u8,
            0,
            0,
            self.sequence,
            self.system_id,
            self.component_id,
            id[0],
            id[1],
            id[2],
        ]);
        let crc = calculate_crc(&out.bytes[1..header + len], crc_extra);
        out.bytes[header + len..header + len + 2].copy_from_slice(&crc.to_le_bytes());
        out.len = header + len + 2;
        self.sequence = self.sequence.wrapping_add(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msg::{HEARTBEAT_DATA, HIL_SENSOR_DATA, STATUSTEXT_DATA};
    use crate::vehicle::crc_extra;
    use std::vec;
    use std::vec::Vec;

    fn encoded<M: MessageData>(m: &M, enc: &mut Encoder) -> Vec<u8> {
        let mut f = Frame::default();
        enc.encode(m, &mut f);
        f.bytes().to_vec()
    }

    fn parse_all(bytes: &[u8]) -> (Vec<(u32, Integrity, Vec<u8>)>, ParserStats) {
        let mut p = Parser::new(crc_extra);
        let mut out = Vec::new();
        for &b in bytes {
            if let Some((f, i)) = p.push(b) {
                out.push((f.message_id(), i, f.bytes().to_vec()));
            }
        }
        (out, p.stats())
    }

    #[test]
    fn encoded_frames_parse_back_with_their_header_and_message() {
        let mut enc = Encoder::new(7, 9);
        let sensor = HIL_SENSOR_DATA {
            time_usec: 1_234_567,
            zacc: -9.81,
            xgyro: 0.25,
            ..Default::default()
        };
        let mut stream = encoded(&sensor, &mut enc);
        stream.extend(encoded(&HEARTBEAT_DATA::default(), &mut enc));
        let mut p = Parser::new(crc_extra);
        let mut seen = Vec::new();
        for &b in &stream {
            if let Some((f, integrity)) = p.push(b) {
                assert_eq!(integrity, Integrity::Verified);
                assert_eq!((f.system_id(), f.component_id()), (7, 9));
                seen.push(f.sequence());
                if let Some(s) = f.decode::<HIL_SENSOR_DATA>() {
                    assert_eq!(s, sensor);
                }
            }
        }
        assert_eq!(seen, [0, 1]);
    }

    #[test]
    fn payloads_are_the_crates_mavlink_2_payloads() {
        // The encoder cuts the trailing zeros itself (`Encoder::finish`); the bytes must be
        // the crate's MAVLink 2 `ser`, whatever the payload ends with.
        fn check<M: MessageData>(m: &M) {
            let mut crate_bytes = [0u8; 255];
            let n = m.ser(MavlinkVersion::V2, &mut crate_bytes);
            let frame = encoded(m, &mut Encoder::new(1, 1));
            let header = 1 + V2_HEADER;
            assert_eq!(frame[1] as usize, n);
            assert_eq!(&frame[header..header + n], &crate_bytes[..n]);
        }
        check(&HEARTBEAT_DATA::default());
        check(&HIL_SENSOR_DATA {
            time_usec: 1,
            ..Default::default()
        });
        check(&STATUSTEXT_DATA {
            text: "hello".into(),
            ..Default::default()
        });
    }

    #[test]
    fn a_corrupted_frame_is_dropped_and_the_next_one_still_parses() {
        let mut enc = Encoder::new(1, 1);
        let text = STATUSTEXT_DATA {
            text: "hello".into(),
            ..Default::default()
        };
        let mut first = encoded(&text, &mut enc);
        let last = first.len() - 3;
        first[last] ^= 0x40;
        let mut stream = first;
        stream.extend(encoded(&text, &mut enc));
        let (frames, stats) = parse_all(&stream);
        assert_eq!(frames.len(), 1);
        assert_eq!(stats.bad_checksums, 1);
    }

    #[test]
    fn unknown_messages_come_back_unverified_and_whole() {
        // A frame of message id 0x1234 (unknown here) built by hand.
        let body = [3u8, 0, 0, 5, 200, 1, 0x34, 0x12, 0x00, 10, 20, 30];
        let mut frame = vec![STX_V2];
        frame.extend_from_slice(&body);
        frame.extend_from_slice(&[0xAA, 0xBB]);
        let (frames, _) = parse_all(&frame);
        assert_eq!(frames.len(), 1);
        assert_eq!(frames[0].0, 0x1234);
        assert_eq!(frames[0].1, Integrity::Unverified);
        assert_eq!(frames[0].2, frame);
    }

    #[test]
    fn garbage_between_frames_is_skipped() {
        let mut enc = Encoder::new(1, 1);
        let mut stream = vec![0x00, 0x13, 0x55];
        stream.extend(encoded(&HEARTBEAT_DATA::default(), &mut enc));
        stream.extend([0x42; 7]);
        stream.extend(encoded(&HEARTBEAT_DATA::default(), &mut enc));
        let (frames, stats) = parse_all(&stream);
        assert_eq!(frames.len(), 2);
        assert_eq!(stats.skipped_bytes, 10);
    }

    #[test]
    fn unsupported_incompatibility_flags_are_refused() {
        let mut enc = Encoder::new(1, 1);
        let mut frame = encoded(&HEARTBEAT_DATA::default(), &mut enc);
        frame[2] = 0x02;
        let (frames, stats) = parse_all(&frame);
        assert!(frames.is_empty());
        assert_eq!(stats.unsupported, 1);
    }

    proptest::proptest! {
        #[test]
        fn any_byte_stream_is_survived(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..2000)) {
            let mut p = Parser::new(crc_extra);
            for b in bytes {
                if let Some((f, _)) = p.push(b) {
                    let _ = f.payload();
                    let _ = f.message_id();
                }
            }
        }
    }
}
