//! The safety pilot's radio over SBUS, the serial bus of Futaba's and FrSky's receivers and
//! many others: a byte-stream parser that turns the receiver's 25-byte frames into channel
//! frames ([`crate::rc::RcFrame`]). The receiver is wired to a UART at 100,000 baud 8E2 with
//! its receive line inverted (SBUS idles low); on the Pixhawk 6C that is TELEM3 or GPS2 with the
//! UART's own inversion, as docs/hardware.md ("RC receivers") says. This core sees the bytes
//! after the UART has inverted them.
//!
//! The frame, as PX4's `src/lib/rc/sbus.cpp` and Betaflight's `src/main/rx/sbus.c` decode it:
//! - byte 0: the header, 0x0F;
//! - bytes 1..=22: 16 channels of 11 bits, least significant bit first
//!   ([`crate::rc::unpack_channels`], as in CRSF);
//! - byte 23: flags: bit 0 channel 17, bit 1 channel 18 (digital), bit 2 frame lost (the
//!   receiver missed a radio frame and repeats the last), bit 3 failsafe; bits 4-7 unused, 0;
//! - byte 24: the footer, 0x00, or in SBUS2 0x04, 0x14, 0x24 or 0x34 (the telemetry slot that
//!   follows; PX4 accepts the same five).
//!
//! Frames take 3 ms and come every 6 to 14 ms (Betaflight's observations of FrSky and Futaba
//! receivers): the line idles between them. Values 172..1811
//! are 988..2012 us ([`crate::rc::to_us`], Betaflight's scale, the same as CRSF's); channels 17
//! and 18 are not carried ([`RcFrame`] has 16).
//!
//! SBUS has no checksum, so what stands between line noise and a stick is the frame's
//! structure, the UART's parity bit and the gaps between frames:
//! - [`Framing::IdleLine`] (use it): the glue calls [`SbusParser::idle`] when the UART reports
//!   an idle line, and a frame is exactly the 25 bytes between two idle lines. A chunk that is
//!   shorter (bytes lost, or the parser started mid-frame) or longer (noise) is dropped, as is
//!   one with a byte the UART flagged ([`SbusParser::line_error`]: parity, framing, noise);
//!   the parity bit finds any single flipped bit of a byte. Any one such fault never gives a
//!   frame that was not sent (a property test of 10,000 streams). What still passes, as it
//!   would any SBUS receiver: two flipped bits in one byte; noise and a lost byte in the same
//!   frame; an idle line missed with exactly a frame's worth of bytes around it. PX4's decoder
//!   relies on the gaps in the same way (its comment: "the S.BUS protocol doesn't provide
//!   reliable framing, so we detect frame boundaries by the inter-frame delay").
//! - [`Framing::HeaderFooter`], for a UART that cannot report the idle line: frames are found
//!   by header and footer alone, and after a rejected frame the search resumes at the next
//!   0x0F inside it (PX4's offset recovery). A 0x0F in the channel data with flags- and
//!   footer-like bytes where they would fall can be taken for a header, and then the frames
//!   after it too, for as long as the data stays so (the tests show one): only the flags'
//!   unused bits and the footer guard against it. Idle lines, if reported, still drop partial
//!   frames, which keeps a false header from reaching into the next frame.
//!
//! Written by hand rather than with a crate: the byte-at-a-time parser of `sbus-rs` 0.1.3
//! (`StreamingParser`) accepts only the 0x00 footer, so it drops every SBUS2 frame, and it has
//! neither idle-line framing nor a way to hear of the UART's parity errors; `sbus` 0.2.2 was
//! last released in 2020.

use crate::rc::{self, PACKED_LEN, RcFrame};

/// Bytes in a frame.
pub const FRAME_LEN: usize = 25;
/// The first byte of every frame.
pub const HEADER: u8 = 0x0F;
/// The last byte of a frame: 0x00 in SBUS, the next telemetry slot's number in SBUS2.
pub const FOOTERS: [u8; 5] = [0x00, 0x04, 0x14, 0x24, 0x34];

/// The flags byte's bits (byte 23).
pub mod flag {
    /// Digital channel 17.
    pub const CH17: u8 = 0x01;
    /// Digital channel 18.
    pub const CH18: u8 = 0x02;
    /// The receiver missed a radio frame; the channels are the last it had.
    pub const FRAME_LOST: u8 = 0x04;
    /// The receiver is in failsafe; the channels are its failsafe positions.
    pub const FAILSAFE: u8 = 0x08;
    /// Bits no receiver sets.
    pub const UNUSED: u8 = 0xF0;
}

/// How frames are told apart in the byte stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Framing {
    /// A frame is exactly the bytes between two idle lines (the glue calls
    /// [`SbusParser::idle`]); the frame comes out at the idle line after it.
    IdleLine,
    /// Frames are found by header and footer; the frame comes out at its last byte.
    HeaderFooter,
}

/// Why 25 bytes are no frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameError {
    /// The first byte is not 0x0F.
    Header(u8),
    /// The last byte is not one of [`FOOTERS`].
    Footer(u8),
    /// The flags byte has one of its unused bits set.
    Flags(u8),
}

/// The channel frame in 25 bytes, if header, flags and footer are a frame's.
pub fn decode(frame: &[u8; FRAME_LEN]) -> Result<RcFrame, FrameError> {
    let [header, data @ .., flags, footer] = *frame;
    if header != HEADER {
        return Err(FrameError::Header(header));
    }
    if !FOOTERS.contains(&footer) {
        return Err(FrameError::Footer(footer));
    }
    if flags & flag::UNUSED != 0 {
        return Err(FrameError::Flags(flags));
    }
    let packed: [u8; PACKED_LEN] = data;
    Ok(rc::frame_from_packed(
        &packed,
        flags & flag::FAILSAFE != 0,
        flags & flag::FRAME_LOST != 0,
    ))
}

/// What the parser has seen and dropped since it started (each count saturates).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SbusStats {
    /// Frames decoded (failsafe ones included).
    pub frames: u32,
    /// Frames with the failsafe flag.
    pub failsafe: u32,
    /// Frames with the frame-lost flag: radio frames the receiver missed.
    pub frame_lost: u32,
    /// Bytes dropped while looking for a header ([`Framing::HeaderFooter`]).
    pub noise_bytes: u32,
    /// Chunks of 25 bytes between idle lines that do not start with the header
    /// ([`Framing::IdleLine`]).
    pub bad_header: u32,
    /// Frames dropped for a footer that is none of [`FOOTERS`].
    pub bad_footer: u32,
    /// Frames dropped for unused flag bits set.
    pub bad_flags: u32,
    /// Partial frames dropped: cut short by an idle line.
    pub truncated: u32,
    /// Chunks longer than a frame between two idle lines ([`Framing::IdleLine`]).
    pub overlong: u32,
    /// Bytes the UART flagged (parity, framing, noise); the frame they were in is dropped.
    pub line_errors: u32,
}

/// SBUS's byte-stream parser: push the receiver's bytes one at a time.
#[derive(Clone, Debug)]
pub struct SbusParser {
    framing: Framing,
    buf: [u8; FRAME_LEN],
    len: usize,
    /// More than a frame's bytes since the last idle line ([`Framing::IdleLine`]).
    overlong: bool,
    /// A flagged byte since the last idle line ([`Framing::IdleLine`]).
    errored: bool,
    stats: SbusStats,
}

impl SbusParser {
    /// A parser that holds nothing. Started in the middle of a frame, it drops the rest of it
    /// (with [`Framing::IdleLine`], fewer than 25 bytes before the first idle line).
    pub const fn new(framing: Framing) -> Self {
        Self {
            framing,
            buf: [0; FRAME_LEN],
            len: 0,
            overlong: false,
            errored: false,
            stats: SbusStats {
                frames: 0,
                failsafe: 0,
                frame_lost: 0,
                noise_bytes: 0,
                bad_header: 0,
                bad_footer: 0,
                bad_flags: 0,
                truncated: 0,
                overlong: 0,
                line_errors: 0,
            },
        }
    }

    /// What the parser has seen and dropped.
    pub fn stats(&self) -> &SbusStats {
        &self.stats
    }

    /// The next byte from the receiver (after the UART's inversion); with
    /// [`Framing::HeaderFooter`], the frame it completes.
    pub fn push(&mut self, byte: u8) -> Option<RcFrame> {
        match self.framing {
            Framing::IdleLine => {
                if let Some(slot) = self.buf.get_mut(self.len) {
                    *slot = byte;
                    self.len += 1;
                } else {
                    self.overlong = true;
                }
                None
            }
            Framing::HeaderFooter => {
                if self.len == 0 && byte != HEADER {
                    count(&mut self.stats.noise_bytes);
                    return None;
                }
                let slot = self.buf.get_mut(self.len)?;
                *slot = byte;
                self.len += 1;
                if self.len < FRAME_LEN {
                    return None;
                }
                let frame = self.take();
                if frame.is_none() {
                    // Search the rejected frame for the next header.
                    let next = self.buf.iter().skip(1).position(|&b| b == HEADER);
                    if let Some(i) = next {
                        self.buf.copy_within(i + 1.., 0);
                        self.len = FRAME_LEN - (i + 1);
                    }
                }
                frame
            }
        }
    }

    /// The UART saw the line go idle: with [`Framing::IdleLine`], the frame the bytes since the
    /// last idle line make, if they make one; a partial frame is dropped in either framing.
    pub fn idle(&mut self) -> Option<RcFrame> {
        let (overlong, errored) = (self.overlong, self.errored);
        self.overlong = false;
        self.errored = false;
        let frame = match self.framing {
            Framing::IdleLine if errored => None,
            Framing::IdleLine if overlong => {
                count(&mut self.stats.overlong);
                None
            }
            Framing::IdleLine if self.len == FRAME_LEN => self.take(),
            Framing::IdleLine | Framing::HeaderFooter => {
                if self.len > 0 {
                    count(&mut self.stats.truncated);
                }
                None
            }
        };
        self.len = 0;
        frame
    }

    /// The UART flagged a byte (parity, framing or noise error) instead of handing it over:
    /// the frame it was in is dropped.
    pub fn line_error(&mut self) {
        count(&mut self.stats.line_errors);
        match self.framing {
            Framing::IdleLine => self.errored = true,
            Framing::HeaderFooter => self.len = 0,
        }
    }

    /// The frame the full buffer holds, counted; the reason counted if none. Empties the
    /// buffer.
    fn take(&mut self) -> Option<RcFrame> {
        self.len = 0;
        match decode(&self.buf) {
            Ok(frame) => {
                count(&mut self.stats.frames);
                if frame.failsafe {
                    count(&mut self.stats.failsafe);
                }
                if frame.frame_lost {
                    count(&mut self.stats.frame_lost);
                }
                Some(frame)
            }
            Err(FrameError::Header(_)) => {
                count(&mut self.stats.bad_header);
                None
            }
            Err(FrameError::Footer(_)) => {
                count(&mut self.stats.bad_footer);
                None
            }
            Err(FrameError::Flags(_)) => {
                count(&mut self.stats.bad_flags);
                None
            }
        }
    }
}

fn count(counter: &mut u32) {
    *counter = counter.saturating_add(1);
}

#[cfg(test)]
mod tests;
