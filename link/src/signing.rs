//! MAVLink 2 message signing (MAVLink's "Message signing" spec): once a secret key
//! is set, every frame the vehicle sends carries a signature, and received frames are checked
//! for theirs, so the vehicle knows which commands come from a ground station holding the key.
//!
//! A signed frame has the incompatibility flag `0x01` and 13 more bytes after its checksum:
//! the link id, a 48-bit timestamp (10 us units since 2015-01-01) and the first 6 bytes of
//! SHA-256(key, header, payload, checksum, link id, timestamp). A received signature holds
//! when it matches and its timestamp is newer than the last one of its stream (system,
//! component, link id); a new stream may not be more than a minute behind the vehicle's
//! timestamp. The vehicle has no calendar clock: its timestamp starts at the one the key came
//! with, advances with its own uptime and never falls behind the newest valid one received.

use sha2::{Digest, Sha256};

use crate::frame::Frame;

/// Bytes of a signature after a frame's checksum.
pub const SIGNATURE_LEN: usize = 13;
/// Bytes of a secret key.
pub const KEY_LEN: usize = 32;
/// The MAVLink 2 incompatibility flag of a signed frame.
pub const IFLAG_SIGNED: u8 = 0x01;
/// A new stream's timestamp may be this far behind the vehicle's (one minute), 10 us units.
pub const NEW_STREAM_WINDOW: u64 = 6_000_000;
/// Streams remembered for replay checks; the oldest is forgotten past this.
const STREAMS: usize = 8;
/// Timestamps are 48 bits.
const TIMESTAMP_MASK: u64 = (1 << 48) - 1;

/// What a received frame's signature says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// No key is set: nothing is checked.
    NotChecked,
    /// Signed with the key, newer than its stream's last frame.
    Valid,
    /// Not signed.
    Unsigned,
    /// Signed, but not with the key (or altered).
    BadSignature,
    /// Signed with the key, but not newer than its stream's last frame (a replay).
    Replayed,
}

impl Verdict {
    /// Whether the frame may change the vehicle (commands, parameter writes, uploads).
    pub fn trusted(self) -> bool {
        matches!(self, Self::NotChecked | Self::Valid)
    }

    /// Why a frame is not trusted, for people.
    pub fn reason(self) -> &'static str {
        match self {
            Self::NotChecked | Self::Valid => "signed",
            Self::Unsigned => "not signed",
            Self::BadSignature => "signature does not match the key",
            Self::Replayed => "signature replayed (timestamp not newer)",
        }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Stream {
    system: u8,
    component: u8,
    link_id: u8,
    last: u64,
}

/// The signing state of one vehicle: the key, its timestamp, the streams seen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Signing {
    key: Option<[u8; KEY_LEN]>,
    link_id: u8,
    /// The timestamp the key came with, less the uptime then (10 us units).
    base: u64,
    /// The last timestamp sent or accepted.
    last: u64,
    streams: [Stream; STREAMS],
    used: usize,
}

impl Default for Signing {
    fn default() -> Self {
        Self::new()
    }
}

impl Signing {
    /// No key: frames go unsigned and nothing is checked.
    pub const fn new() -> Self {
        Self {
            key: None,
            link_id: 0,
            base: 0,
            last: 0,
            streams: [Stream {
                system: 0,
                component: 0,
                link_id: 0,
                last: 0,
            }; STREAMS],
            used: 0,
        }
    }

    /// Signs from now on with `key` (an all-zero key switches signing off, as the spec has it),
    /// its timestamp `timestamp` at uptime `uptime_us`, on link `link_id`. Streams seen before
    /// are forgotten.
    pub fn set_key(&mut self, key: [u8; KEY_LEN], timestamp: u64, uptime_us: u64, link_id: u8) {
        *self = Self::new();
        if key != [0; KEY_LEN] {
            self.key = Some(key);
            self.link_id = link_id;
            let timestamp = timestamp.min(TIMESTAMP_MASK);
            self.base = timestamp.saturating_sub(uptime_us / 10);
            self.last = timestamp;
        }
    }

    /// Whether a key is set.
    pub fn enabled(&self) -> bool {
        self.key.is_some()
    }

    /// The key (for storage).
    pub fn key(&self) -> Option<[u8; KEY_LEN]> {
        self.key
    }

    /// The vehicle's timestamp at uptime `uptime_us` (for storage and the next signature).
    /// At the end of the 48 bits it stays there: wrapping to 0 would make every later frame a
    /// replay to the ground, and every captured frame a new stream to the vehicle.
    pub fn timestamp(&self, uptime_us: u64) -> u64 {
        self.base
            .saturating_add(uptime_us / 10)
            .min(TIMESTAMP_MASK)
            .max(self.last)
    }

    /// Checks a received frame at uptime `uptime_us`.
    pub fn check(&mut self, frame: &Frame, uptime_us: u64) -> Verdict {
        let Some(key) = self.key else {
            return Verdict::NotChecked;
        };
        let bytes = frame.bytes();
        let signed = bytes.first() == Some(&crate::frame::STX_V2)
            && bytes.get(2).is_some_and(|f| f & IFLAG_SIGNED != 0)
            && bytes.len() >= 12 + SIGNATURE_LEN;
        if !signed {
            return Verdict::Unsigned;
        }
        let (body, signature) = bytes.split_at(bytes.len() - SIGNATURE_LEN);
        let link_id = signature[0];
        let mut stamp = [0u8; 8];
        stamp[..6].copy_from_slice(&signature[1..7]);
        let timestamp = u64::from_le_bytes(stamp);
        if digest(&key, body, link_id, timestamp) != signature[7..13] {
            return Verdict::BadSignature;
        }
        let (system, component) = (bytes[5], bytes[6]);
        let now = self.timestamp(uptime_us);
        let known = self.streams[..self.used]
            .iter()
            .position(|s| (s.system, s.component, s.link_id) == (system, component, link_id));
        match known {
            Some(i) if timestamp <= self.streams[i].last => return Verdict::Replayed,
            Some(i) => self.streams[i].last = timestamp,
            None if timestamp + NEW_STREAM_WINDOW < now => return Verdict::Replayed,
            None => {
                let stream = Stream {
                    system,
                    component,
                    link_id,
                    last: timestamp,
                };
                if self.used < STREAMS {
                    self.streams[self.used] = stream;
                    self.used += 1;
                } else {
                    // Forget the stream heard from longest ago.
                    let oldest = (0..STREAMS)
                        .min_by_key(|&i| self.streams[i].last)
                        .unwrap_or(0);
                    self.streams[oldest] = stream;
                }
            }
        }
        self.last = self.last.max(timestamp);
        Verdict::Valid
    }

    /// Signs `frame` (encoded unsigned) at uptime `uptime_us`, when a key is set: sets the
    /// incompatibility flag, recomputes the checksum with `crc_extra` and appends the
    /// signature. A frame too long for the buffer is left as it is.
    pub fn sign(&mut self, frame: &mut Frame, crc_extra: u8, uptime_us: u64) {
        let Some(key) = self.key else {
            return;
        };
        let timestamp = (self.timestamp(uptime_us) + 1).min(TIMESTAMP_MASK);
        if frame.append_signature(crc_extra, |body| {
            let mut signature = [0u8; SIGNATURE_LEN];
            signature[0] = self.link_id;
            signature[1..7].copy_from_slice(&timestamp.to_le_bytes()[..6]);
            signature[7..].copy_from_slice(&digest(&key, body, self.link_id, timestamp));
            signature
        }) {
            self.last = timestamp;
        }
    }
}

/// The first 6 bytes of SHA-256(key, body, link id, timestamp as 6 bytes).
fn digest(key: &[u8; KEY_LEN], body: &[u8], link_id: u8, timestamp: u64) -> [u8; 6] {
    let mut hash = Sha256::new();
    hash.update(key);
    hash.update(body);
    hash.update([link_id]);
    hash.update(&timestamp.to_le_bytes()[..6]);
    let full = hash.finalize();
    let mut out = [0u8; 6];
    out.copy_from_slice(&full[..6]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{Encoder, Parser};
    use crate::msg::{COMMAND_LONG_DATA, HEARTBEAT_DATA, MavCmd};
    use crate::vehicle::crc_extra;
    use mavlink::MessageData;

    const KEY: [u8; KEY_LEN] = [7; KEY_LEN];

    fn signed_by(signing: &mut Signing, system: u8, uptime_us: u64) -> Frame {
        let mut f = Frame::default();
        let m = COMMAND_LONG_DATA {
            command: MavCmd::MAV_CMD_MISSION_START,
            target_system: 1,
            ..Default::default()
        };
        Encoder::new(system, 190).encode(&m, &mut f);
        signing.sign(&mut f, COMMAND_LONG_DATA::EXTRA_CRC, uptime_us);
        f
    }

    /// The frame through a parser (its checksum must hold).
    fn received(f: &Frame) -> Frame {
        let mut p = Parser::new(crc_extra);
        let mut out = None;
        for &b in f.bytes() {
            if let Some((frame, _)) = p.push(b) {
                out = Some(frame.clone());
            }
        }
        out.expect("a frame whose checksum holds")
    }

    fn vehicle() -> Signing {
        let mut v = Signing::new();
        v.set_key(KEY, 1_000_000_000, 0, 0);
        v
    }

    /// pymavlink 2.4 (MAVLink's reference implementation), key 32 x 7, link 3, timestamp
    /// 1e9: a GCS `HEARTBEAT` from 255/190.
    const PYMAVLINK_SIGNED_HEARTBEAT: [u8; 34] = [
        253, 9, 1, 0, 0, 255, 190, 0, 0, 0, 0, 0, 0, 0, 6, 8, 0, 0, 3, 187, 211, 3, 0, 202, 154,
        59, 0, 0, 152, 89, 182, 112, 44, 39,
    ];

    #[test]
    fn signatures_match_the_reference_implementation() {
        let heartbeat = HEARTBEAT_DATA {
            mavtype: crate::msg::MavType::MAV_TYPE_GCS,
            autopilot: crate::msg::MavAutopilot::MAV_AUTOPILOT_INVALID,
            base_mode: crate::msg::MavModeFlag::empty(),
            mavlink_version: 3,
            ..Default::default()
        };
        let mut ours = Signing::new();
        ours.set_key(KEY, 1_000_000_000 - 1, 0, 3);
        let mut f = Frame::default();
        Encoder::new(255, 190).encode(&heartbeat, &mut f);
        ours.sign(&mut f, HEARTBEAT_DATA::EXTRA_CRC, 0);
        assert_eq!(f.bytes(), PYMAVLINK_SIGNED_HEARTBEAT);
        let mut p = Parser::new(crc_extra);
        let theirs = PYMAVLINK_SIGNED_HEARTBEAT
            .iter()
            .find_map(|&b| p.push(b).map(|(f, _)| f.clone()))
            .expect("a frame");
        assert_eq!(vehicle().check(&theirs, 0), Verdict::Valid);
    }

    #[test]
    fn a_frame_signed_with_the_key_is_valid_once() {
        let mut ground = Signing::new();
        ground.set_key(KEY, 1_000_000_000, 0, 3);
        let f = received(&signed_by(&mut ground, 255, 1_000));
        assert_eq!(f.bytes()[2] & IFLAG_SIGNED, IFLAG_SIGNED);
        let mut v = vehicle();
        assert_eq!(v.check(&f, 0), Verdict::Valid);
        assert_eq!(v.check(&f, 0), Verdict::Replayed);
        let next = received(&signed_by(&mut ground, 255, 2_000));
        assert_eq!(v.check(&next, 0), Verdict::Valid);
    }

    #[test]
    fn unsigned_altered_and_foreign_frames_are_not_trusted() {
        let mut v = vehicle();
        let mut plain = Frame::default();
        Encoder::new(255, 190).encode(&HEARTBEAT_DATA::default(), &mut plain);
        assert_eq!(v.check(&plain, 0), Verdict::Unsigned);
        let mut other = Signing::new();
        other.set_key([9; KEY_LEN], 1_000_000_000, 0, 0);
        assert_eq!(
            v.check(&received(&signed_by(&mut other, 255, 0)), 0),
            Verdict::BadSignature
        );
        let mut ground = vehicle();
        let good = signed_by(&mut ground, 255, 0);
        let mut bytes = good.bytes().to_vec();
        let n = bytes.len();
        bytes[n - 1] ^= 1; // the signature's last byte
        let mut p = Parser::new(crc_extra);
        let altered = bytes
            .iter()
            .find_map(|&b| p.push(b).map(|(f, _)| f.clone()));
        let altered = altered.expect("the checksum does not cover the signature");
        assert_eq!(v.check(&altered, 0), Verdict::BadSignature);
        for verdict in [Verdict::Unsigned, Verdict::BadSignature, Verdict::Replayed] {
            assert!(!verdict.trusted());
        }
    }

    #[test]
    fn without_a_key_nothing_is_signed_or_checked() {
        let mut v = Signing::new();
        let f = signed_by(&mut v, 255, 0);
        assert_eq!(f.bytes()[2] & IFLAG_SIGNED, 0);
        assert_eq!(v.check(&f, 0), Verdict::NotChecked);
        // An all-zero key switches signing off.
        let mut on = vehicle();
        on.set_key([0; KEY_LEN], 5, 0, 0);
        assert!(!on.enabled());
    }

    #[test]
    fn a_new_stream_more_than_a_minute_behind_is_a_replay() {
        let mut v = Signing::new();
        v.set_key(KEY, 2_000_000_000, 0, 0);
        let mut late = Signing::new();
        late.set_key(KEY, 2_000_000_000 - NEW_STREAM_WINDOW - 10, 0, 0);
        assert_eq!(
            v.check(&received(&signed_by(&mut late, 200, 0)), 0),
            Verdict::Replayed
        );
        let mut recent = Signing::new();
        recent.set_key(KEY, 2_000_000_000 - NEW_STREAM_WINDOW / 2, 0, 0);
        assert_eq!(
            v.check(&received(&signed_by(&mut recent, 201, 0)), 0),
            Verdict::Valid
        );
    }

    #[test]
    fn the_vehicles_timestamp_advances_and_follows_newer_ones() {
        let mut v = vehicle();
        assert_eq!(v.timestamp(1_000_000), 1_000_100_000);
        let mut ahead = Signing::new();
        ahead.set_key(KEY, 5_000_000_000, 0, 0);
        assert_eq!(
            v.check(&received(&signed_by(&mut ahead, 255, 0)), 1_000_000),
            Verdict::Valid
        );
        assert!(v.timestamp(1_000_000) > 5_000_000_000);
        // What it signs is newer each time, even within one 10 us tick.
        let a = signed_by(&mut v, 1, 1_000_000);
        let b = signed_by(&mut v, 1, 1_000_000);
        let stamp = |f: &Frame| {
            let s = &f.bytes()[f.bytes().len() - 12..f.bytes().len() - 6];
            u64::from_le_bytes([s[0], s[1], s[2], s[3], s[4], s[5], 0, 0])
        };
        assert!(stamp(&b) > stamp(&a));
    }

    /// Found by the `link_input` fuzz target: a `SETUP_SIGNING` whose timestamp
    /// is near the end of the 48 bits made the vehicle's timestamp wrap to 0, so the ground
    /// took every later frame of the vehicle for a replay, and the vehicle took a frame signed
    /// long ago, from a stream it had not heard, for a new one.
    #[test]
    fn the_timestamp_stops_at_the_end_of_its_48_bits_instead_of_wrapping() {
        let mut v = Signing::new();
        v.set_key(KEY, TIMESTAMP_MASK - 100, 0, 0);
        // 10 s later: 1,000,000 units past the end.
        let f = signed_by(&mut v, 1, 10_000_000);
        let signature = &f.bytes()[f.bytes().len() - SIGNATURE_LEN..];
        let mut stamp = [0u8; 8];
        stamp[..6].copy_from_slice(&signature[1..7]);
        assert_eq!(u64::from_le_bytes(stamp), TIMESTAMP_MASK, "not wrapped");
        assert_eq!(v.timestamp(20_000_000), TIMESTAMP_MASK);
        // A frame signed at timestamp 1000, replayed from a stream never heard: refused.
        let mut old = Signing::new();
        old.set_key(KEY, 1000, 0, 7);
        let captured = signed_by(&mut old, 42, 0);
        assert_eq!(v.check(&received(&captured), 20_000_000), Verdict::Replayed);
        // A timestamp past 48 bits is the end, not its low bits.
        let mut far = Signing::new();
        far.set_key(KEY, u64::MAX, 0, 0);
        assert_eq!(far.timestamp(0), TIMESTAMP_MASK);
    }

    #[test]
    fn a_full_table_forgets_the_stream_heard_from_longest_ago() {
        let mut v = vehicle();
        let mut ground = vehicle();
        for system in 10..10 + STREAMS as u8 + 1 {
            let f = received(&signed_by(&mut ground, system, u64::from(system) * 1000));
            assert_eq!(v.check(&f, 0), Verdict::Valid);
        }
        assert_eq!(v.used, STREAMS);
        assert!(!v.streams.iter().any(|s| s.system == 10));
    }
}
