//! The safety pilot's radio over CRSF, the serial protocol of ExpressLRS and TBS Crossfire
//! receivers: a byte-stream parser that turns what the receiver sends the flight controller
//! into channel frames ([`crate::rc::RcFrame`]) and link statistics ([`LinkStatistics`]).
//! The receiver is wired to a full UART at 420,000 baud 8N1, TELEM3 or GPS2 (docs/hardware.md,
//! "RC receivers"); this core only sees its bytes.
//!
//! The protocol, from the CRSF working group's wiki (github.com/crsf-wg/crsf, pages "Message
//! Format", `CRSF_FRAMETYPE_RC_CHANNELS_PACKED` and `CRSF_FRAMETYPE_LINK_STATISTICS`):
//! - A frame is `[sync] [len] [type] [payload] [crc]`, at most 64 bytes. The sync byte is
//!   0xC8 (EdgeTX's outgoing frames use 0xEE, which new code should accept too); `len` counts
//!   type, payload and CRC, so 2..=62; the CRC is CRC-8 DVB-S2 (polynomial 0xD5, initial 0, no
//!   reflection) over type and payload.
//! - `RC_CHANNELS_PACKED` (0x16): 16 channels of 11 bits in 22 bytes
//!   ([`crate::rc::unpack_channels`]); 172, 992 and 1811 are 988, 1500 and 2012 us.
//! - `LINK_STATISTICS` (0x14): 10 bytes, the uplink's RSSI at each antenna (dBm with the sign
//!   dropped), link quality (%), SNR, active antenna, RF mode and transmit power, then the
//!   downlink's RSSI, link quality and SNR. An uplink link quality of 0 marks the link down.
//!
//! How the parser holds to "a frame that did not check never moves a stick":
//! - Only a frame whose CRC checks is decoded; a channel frame must also have its 22 bytes
//!   exactly, link statistics their 10 ([`CrsfStats::bad_payload`] otherwise).
//! - It resynchronises on every rejection by dropping only the rejected frame's first byte and
//!   searching the bytes it already holds for the next sync byte: noise that looks like a
//!   frame start never swallows the real frame behind it.
//! - [`CrsfParser::idle`] (the glue calls it when the UART reports an idle line) drops a
//!   partial frame there: no frame spans a gap, so a truncated frame cannot borrow the next
//!   frame's bytes and pass its CRC by chance (1 in 256) without one.
//! - CRSF channel frames carry no failsafe flag: an ExpressLRS receiver stops sending them when
//!   the link is lost, and the consumer times them out. A receiver that kept sending channels
//!   (failsafe positions) would say the link is down in its link statistics (the wiki: an
//!   uplink link quality of 0 may mark a disconnected link), so channel frames after link
//!   statistics with a link quality of 0 are reported as failsafe until link statistics say
//!   it is back.
//! - What an 8-bit CRC cannot do: a corrupted frame whose CRC checks by chance (1 in 256 of the
//!   corrupted frames that still start with a sync byte and a plausible length) is
//!   indistinguishable from a real one, here as in every CRSF receiver. The property test
//!   measured 16 to 39 such frames in 10,000 corrupted streams (20 runs) of up to seven frames
//!   and up to four faults each (bytes inserted or lost inside a frame, several flipped bits).
//!
//! Written by hand rather than with a crate: `crsf` 2.0.1, its crates.io release, takes 64
//! bytes off its buffer for every frame whatever the frame's length, so of three frames pushed
//! back to back it returns one (tried), and it pulls `bitfield` and `snafu`. `uf-crsf` 0.7
//! resynchronises well (it drops only a rejected start byte, as this parser does), but it is a
//! 0.x crate whose parser API changed with its recent releases (a byte state machine in 0.2, a
//! slice cursor in 0.7), brings `num_enum`'s proc macro and some forty frame decoders for the
//! two needed here, and knows no idle line; the wrapper it would need (idle lines, counts,
//! failsafe, microseconds) is most of this module.

use crate::rc::{self, PACKED_LEN, RcFrame};

/// The sync byte of every frame sent to the flight controller (its CRSF address).
pub const SYNC: u8 = 0xC8;
/// The sync byte EdgeTX's outgoing frames use, accepted as the spec asks.
pub const SYNC_EDGETX: u8 = 0xEE;
/// The longest frame, sync to CRC.
pub const MAX_FRAME_LEN: usize = 64;
/// The smallest length byte (type and CRC, no payload).
pub const MIN_LEN_BYTE: u8 = 2;
/// The largest length byte (a 64-byte frame).
pub const MAX_LEN_BYTE: u8 = (MAX_FRAME_LEN - 2) as u8;

/// The frame types this parser decodes.
pub mod frame_type {
    /// Link statistics: RSSI, link quality, SNR, RF mode, transmit power.
    pub const LINK_STATISTICS: u8 = 0x14;
    /// 16 channels of 11 bits.
    pub const RC_CHANNELS_PACKED: u8 = 0x16;
}

/// Payload bytes of a link statistics frame.
pub const LINK_STATISTICS_LEN: usize = 10;

/// Each byte's CRC-8 DVB-S2 remainder (polynomial x^8 + x^7 + x^6 + x^4 + x^2 + 1, 0xD5).
const CRC_TABLE: [u8; 256] = {
    let mut table = [0u8; 256];
    let mut byte = 0;
    while byte < 256 {
        let mut crc = byte as u8;
        let mut bit = 0;
        while bit < 8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ 0xD5
            } else {
                crc << 1
            };
            bit += 1;
        }
        table[byte] = crc;
        byte += 1;
    }
    table
};

/// The CRC-8 DVB-S2 of `bytes` (initial value 0, most significant bit first, no final XOR);
/// a frame's CRC is this over its type and payload.
pub fn crc8(bytes: &[u8]) -> u8 {
    bytes
        .iter()
        .fold(0, |crc, &byte| CRC_TABLE[usize::from(crc ^ byte)])
}

/// Bytes of an `RC_CHANNELS_PACKED` frame, sync to CRC.
pub const CHANNELS_FRAME_LEN: usize = 4 + PACKED_LEN;

/// The `RC_CHANNELS_PACKED` frame a receiver sends the flight controller for `channels_us`
/// (pulse widths, us; each taken to 880..=2159 and to the 11-bit value [`rc::from_us`] gives,
/// so the parser gives back exactly `channels_us` within that range): what the HIL plant
/// writes into the emulated board's receiver UART (docs/hil.md).
pub fn encode_channels(channels_us: &[u16; rc::CHANNELS]) -> [u8; CHANNELS_FRAME_LEN] {
    let packed = rc::pack_channels(&channels_us.map(rc::from_us));
    let mut frame = [0u8; CHANNELS_FRAME_LEN];
    frame[0] = SYNC;
    frame[1] = (CHANNELS_FRAME_LEN - 2) as u8;
    frame[2] = frame_type::RC_CHANNELS_PACKED;
    frame[3..3 + PACKED_LEN].copy_from_slice(&packed);
    frame[CHANNELS_FRAME_LEN - 1] = crc8(&frame[2..CHANNELS_FRAME_LEN - 1]);
    frame
}

/// What a `LINK_STATISTICS` frame says about the radio link. Uplink is the pilot's radio to
/// the receiver, downlink the receiver back to the radio.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LinkStatistics {
    /// The uplink's RSSI at the receiver's first antenna, dBm (the frame carries it with the
    /// sign dropped).
    pub uplink_rssi_ant1_dbm: i16,
    /// The uplink's RSSI at the receiver's second antenna, dBm.
    pub uplink_rssi_ant2_dbm: i16,
    /// The uplink's link quality: radio frames received, percent; 0 when the link is down.
    pub uplink_link_quality: u8,
    /// The uplink's signal-to-noise ratio, dB.
    pub uplink_snr_db: i8,
    /// The antenna in use (0 the first, 1 the second).
    pub active_antenna: u8,
    /// The RF mode (packet rate; the values depend on the system and band).
    pub rf_mode: u8,
    /// The radio's transmit power as the protocol's index ([`Self::uplink_tx_power_mw`]).
    pub uplink_tx_power: u8,
    /// The downlink's RSSI at the radio, dBm.
    pub downlink_rssi_dbm: i16,
    /// The downlink's link quality, percent.
    pub downlink_link_quality: u8,
    /// The downlink's signal-to-noise ratio, dB.
    pub downlink_snr_db: i8,
}

/// Transmit power, mW, by the protocol's index (Betaflight's `uplinkTXPowerStatesMw`, which
/// ExpressLRS follows: 250 mW and 50 mW were added after 2000 mW).
const TX_POWER_MW: [u16; 9] = [0, 10, 25, 100, 500, 1000, 2000, 250, 50];

impl LinkStatistics {
    /// The statistics in a 10-byte payload.
    pub fn from_payload(payload: &[u8; LINK_STATISTICS_LEN]) -> Self {
        let dbm = |byte: u8| -i16::from(byte);
        Self {
            uplink_rssi_ant1_dbm: dbm(payload[0]),
            uplink_rssi_ant2_dbm: dbm(payload[1]),
            uplink_link_quality: payload[2],
            uplink_snr_db: payload[3] as i8,
            active_antenna: payload[4],
            rf_mode: payload[5],
            uplink_tx_power: payload[6],
            downlink_rssi_dbm: dbm(payload[7]),
            downlink_link_quality: payload[8],
            downlink_snr_db: payload[9] as i8,
        }
    }

    /// The radio's transmit power, mW, or `None` for an index the protocol does not define.
    pub fn uplink_tx_power_mw(&self) -> Option<u16> {
        TX_POWER_MW.get(usize::from(self.uplink_tx_power)).copied()
    }

    /// The link is down: the receiver has had no radio frame for its whole link-quality window.
    pub fn link_down(&self) -> bool {
        self.uplink_link_quality == 0
    }
}

/// What a frame that checked says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CrsfEvent {
    /// The channels (`RC_CHANNELS_PACKED`).
    Channels(RcFrame),
    /// The link's statistics (`LINK_STATISTICS`).
    LinkStatistics(LinkStatistics),
}

/// What the parser has seen and dropped since it started (each count saturates).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CrsfStats {
    /// Channel frames decoded.
    pub channel_frames: u32,
    /// Link statistics decoded.
    pub link_statistics: u32,
    /// Frames whose CRC checked, of types not decoded here (telemetry, parameters, ...).
    pub other_frames: u32,
    /// Channel frames reported as failsafe (decoded while the link statistics said down).
    pub failsafe_frames: u32,
    /// Bytes dropped while looking for a sync byte.
    pub noise_bytes: u32,
    /// Frame starts dropped for a length byte below 2 or above 62.
    pub bad_length: u32,
    /// Frame starts dropped because the CRC did not check (a corrupted frame, or a sync byte
    /// in noise or in another frame's payload).
    pub bad_crc: u32,
    /// Frames whose CRC checked but whose payload is the wrong size for their type.
    pub bad_payload: u32,
    /// Frame starts dropped because an idle line cut them short.
    pub truncated: u32,
}

/// CRSF's byte-stream parser: push the receiver's bytes one at a time.
#[derive(Clone, Debug)]
pub struct CrsfParser {
    /// Bytes held: `buf[start..end]`, a candidate frame at `start`.
    buf: [u8; MAX_FRAME_LEN],
    start: usize,
    end: usize,
    /// How many of the held bytes came before the last idle line (no frame spans it).
    before_idle: usize,
    /// The last link statistics said the link is down.
    link_down: bool,
    stats: CrsfStats,
}

impl Default for CrsfParser {
    fn default() -> Self {
        Self::new()
    }
}

impl CrsfParser {
    /// A parser that holds nothing and takes the link as up.
    pub const fn new() -> Self {
        Self {
            buf: [0; MAX_FRAME_LEN],
            start: 0,
            end: 0,
            before_idle: 0,
            link_down: false,
            stats: CrsfStats {
                channel_frames: 0,
                link_statistics: 0,
                other_frames: 0,
                failsafe_frames: 0,
                noise_bytes: 0,
                bad_length: 0,
                bad_crc: 0,
                bad_payload: 0,
                truncated: 0,
            },
        }
    }

    /// What the parser has seen and dropped.
    pub fn stats(&self) -> &CrsfStats {
        &self.stats
    }

    /// The next byte from the receiver; the event of the frame it completes, if any. A byte
    /// can also complete a frame held behind a rejected one: [`Self::poll`] gives those.
    pub fn push(&mut self, byte: u8) -> Option<CrsfEvent> {
        if self.end == MAX_FRAME_LEN {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        if self.end == MAX_FRAME_LEN {
            // Never with a frame of at most 64 bytes at `start`, which `poll` keeps.
            self.skip(1);
            count(&mut self.stats.noise_bytes);
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        if let Some(slot) = self.buf.get_mut(self.end) {
            *slot = byte;
            self.end += 1;
        }
        self.poll()
    }

    /// The UART saw the line go idle: a partial frame held now is cut short and dropped. Gives
    /// the event of a frame found behind it, if any ([`Self::poll`] for more).
    pub fn idle(&mut self) -> Option<CrsfEvent> {
        self.before_idle = self.end - self.start;
        self.poll()
    }

    /// The next event among the bytes already held, without a new byte: after a rejected
    /// frame, more than one frame can be complete. Call until `None` after each read.
    pub fn poll(&mut self) -> Option<CrsfEvent> {
        loop {
            let held = self.buf.get(self.start..self.end).unwrap_or(&[]);
            let Some(&sync) = held.first() else {
                self.before_idle = 0;
                return None;
            };
            if sync != SYNC && sync != SYNC_EDGETX {
                count(&mut self.stats.noise_bytes);
                self.skip(1);
                continue;
            }
            let cut = self.before_idle > 0;
            let Some(&len) = held.get(1) else {
                if cut {
                    count(&mut self.stats.truncated);
                    self.skip(1);
                    continue;
                }
                return None;
            };
            if !(MIN_LEN_BYTE..=MAX_LEN_BYTE).contains(&len) {
                count(&mut self.stats.bad_length);
                self.skip(1);
                continue;
            }
            let frame_len = usize::from(len) + 2;
            if cut && frame_len > self.before_idle {
                count(&mut self.stats.truncated);
                self.skip(1);
                continue;
            }
            // Not all in yet: wait for the rest.
            let (&crc, body) = held.get(..frame_len)?.split_last()?;
            let checked = body.get(2..).unwrap_or(&[]);
            if crc8(checked) != crc {
                count(&mut self.stats.bad_crc);
                self.skip(1);
                continue;
            }
            let event = decode(&mut self.stats, &mut self.link_down, checked);
            self.skip(frame_len);
            if event.is_some() {
                return event;
            }
        }
    }

    /// Drops `n` held bytes from the front.
    fn skip(&mut self, n: usize) {
        let n = n.min(self.end - self.start);
        self.start += n;
        self.before_idle = self.before_idle.saturating_sub(n);
        if self.start == self.end {
            self.start = 0;
            self.end = 0;
        }
    }
}

/// The event of a frame whose CRC checked: `checked` is its type and payload. Channel frames
/// take their failsafe from `link_down`, which link statistics set.
fn decode(stats: &mut CrsfStats, link_down: &mut bool, checked: &[u8]) -> Option<CrsfEvent> {
    let (&kind, payload) = checked.split_first()?;
    match kind {
        frame_type::RC_CHANNELS_PACKED => {
            let Ok(packed) = <&[u8; PACKED_LEN]>::try_from(payload) else {
                count(&mut stats.bad_payload);
                return None;
            };
            count(&mut stats.channel_frames);
            if *link_down {
                count(&mut stats.failsafe_frames);
            }
            Some(CrsfEvent::Channels(rc::frame_from_packed(
                packed, *link_down, false,
            )))
        }
        frame_type::LINK_STATISTICS => {
            let Ok(payload) = <&[u8; LINK_STATISTICS_LEN]>::try_from(payload) else {
                count(&mut stats.bad_payload);
                return None;
            };
            let statistics = LinkStatistics::from_payload(payload);
            count(&mut stats.link_statistics);
            *link_down = statistics.link_down();
            Some(CrsfEvent::LinkStatistics(statistics))
        }
        _ => {
            count(&mut stats.other_frames);
            None
        }
    }
}

fn count(counter: &mut u32) {
    *counter = counter.saturating_add(1);
}

#[cfg(test)]
mod tests;
