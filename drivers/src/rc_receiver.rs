//! The RC receiver's serial port as the firmware's receiver task runs it (docs/hardware.md,
//! "RC receivers"): which protocol the parameters ask for and the line settings it needs
//! ([`RcProtocol`]), which port the receiver is wired to and whether the board can give it
//! ([`RcPort`]), and the bytes the port reads turned into channel frames with the frames
//! counted good and bad ([`RcReceiver`]). The task is glue around this: it reads the UART, hands
//! each read here and passes the frames on.
//!
//! What comes out is what the parsers let through ([`crate::crsf`], [`crate::sbus`]): a frame
//! that failed its checks or was cut short never comes out, and a frame in failsafe comes out
//! marked so ([`RcFrame::sticks`] gives none, [`manual_input`] none).

use crate::crsf::{CrsfEvent, CrsfParser};
use crate::rc::RcFrame;
use crate::sbus::{Framing, SbusParser};
use shared::manual::ManualInput;
use shared::manual::rc_map::RcMap;

/// The receiver's protocol (`RC_INPUT_PROTO`, PX4's numbers).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RcProtocol {
    /// No receiver (0, or a number this firmware does not read).
    None,
    /// SBUS (2): 100,000 baud 8E2, inverted.
    Sbus,
    /// CRSF (6): 420,000 baud 8N1.
    Crsf,
}

/// A UART's settings for a receiver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LineSettings {
    /// Bits a second.
    pub baud: u32,
    /// Even parity (otherwise none).
    pub even_parity: bool,
    /// Two stop bits (otherwise one).
    pub two_stop_bits: bool,
    /// The receive line idles low (the UART inverts its RX pin).
    pub inverted: bool,
}

/// CRSF's line: 420,000 baud 8N1, not inverted.
pub const CRSF_LINE: LineSettings = LineSettings {
    baud: 420_000,
    even_parity: false,
    two_stop_bits: false,
    inverted: false,
};

/// SBUS's line: 100,000 baud 8E2, inverted (idles low).
pub const SBUS_LINE: LineSettings = LineSettings {
    baud: 100_000,
    even_parity: true,
    two_stop_bits: true,
    inverted: true,
};

impl RcProtocol {
    /// The protocol of an `RC_INPUT_PROTO` value: 2 SBUS, 6 CRSF, anything else none.
    pub fn from_param(value: u8) -> Self {
        match value {
            2 => Self::Sbus,
            6 => Self::Crsf,
            _ => Self::None,
        }
    }

    /// The UART's settings for the protocol (`None`: no receiver).
    pub fn line(self) -> Option<LineSettings> {
        match self {
            Self::None => None,
            Self::Crsf => Some(CRSF_LINE),
            Self::Sbus => Some(SBUS_LINE),
        }
    }

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Sbus => "SBUS",
            Self::Crsf => "CRSF",
        }
    }
}

/// The FMU port the receiver is wired to (`RC_PORT_CONFIG`, PX4's numbers).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RcPort {
    /// None (0, or a number this firmware does not know).
    None,
    /// TELEM3 (103): the Pixhawk 6C's USART2, whose TX also drives robots 5-8's steppers.
    Telem3,
    /// GPS2 (202): the Pixhawk 6C's UART8, free.
    Gps2,
}

/// Robots whose steppers are on TELEM2; robots past them have theirs on TELEM3.
pub const ROBOTS_ON_TELEM2: u8 = 4;

/// Why the receiver's port cannot be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PortRefusal {
    /// TELEM3 drives the steppers of robots past the fourth: one UART has one baud rate.
    Telem3DrivesSteppers {
        /// Robots of the payload description loaded.
        robots: u8,
    },
}

impl core::fmt::Display for PortRefusal {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Telem3DrivesSteppers { robots } => write!(
                f,
                "RC on TELEM3 refused: its USART2 drives the steppers of robots 5-{robots}; wire the receiver to GPS2 (RC_PORT_CONFIG 202)"
            ),
        }
    }
}

impl RcPort {
    /// The port of an `RC_PORT_CONFIG` value.
    pub fn from_param(value: u16) -> Self {
        match value {
            103 => Self::Telem3,
            202 => Self::Gps2,
            _ => Self::None,
        }
    }

    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Telem3 => "TELEM3",
            Self::Gps2 => "GPS2",
        }
    }

    /// Whether the receiver may take the port with `robots` robots on the rail (0: no payload
    /// description yet): TELEM3 only while no robot past the fourth needs its stepper bus.
    pub fn check(self, robots: u8) -> Result<Self, PortRefusal> {
        if self == Self::Telem3 && robots > ROBOTS_ON_TELEM2 {
            return Err(PortRefusal::Telem3DrivesSteppers { robots });
        }
        Ok(self)
    }
}

/// Frames that checked and frames dropped, since the receiver (re)started; each saturates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RcCounts {
    /// Frames whose checks passed (channels, failsafe ones included, and CRSF's link
    /// statistics and other frame types).
    pub good: u32,
    /// Frames dropped: CRSF's bad length, CRC, payload size or a frame cut short; SBUS's bad
    /// header, footer or flags, a frame cut short or overlong, or a byte the UART flagged.
    pub bad: u32,
}

#[derive(Clone, Debug)]
enum Parser {
    Off,
    Crsf(CrsfParser),
    Sbus(SbusParser),
}

/// The receiver behind the port: the protocol's parser, the link quality last reported.
#[derive(Clone, Debug)]
pub struct RcReceiver {
    parser: Parser,
    /// The uplink's link quality (percent) from CRSF's last link statistics.
    link_quality: Option<u8>,
}

impl RcReceiver {
    /// A receiver of `protocol` that has seen nothing.
    pub const fn new(protocol: RcProtocol) -> Self {
        Self {
            parser: match protocol {
                RcProtocol::None => Parser::Off,
                RcProtocol::Crsf => Parser::Crsf(CrsfParser::new()),
                RcProtocol::Sbus => Parser::Sbus(SbusParser::new(Framing::IdleLine)),
            },
            link_quality: None,
        }
    }

    /// The protocol it parses.
    pub fn protocol(&self) -> RcProtocol {
        match self.parser {
            Parser::Off => RcProtocol::None,
            Parser::Crsf(_) => RcProtocol::Crsf,
            Parser::Sbus(_) => RcProtocol::Sbus,
        }
    }

    /// One read of the UART: `bytes` received, then whether the UART flagged a byte among them
    /// (parity, framing, noise: `line_error`) and whether the line went idle after them
    /// (`idle`; a UART that cannot tell says `false`). Calls `on_frame` with each channel frame
    /// that comes out, in order.
    pub fn receive(
        &mut self,
        bytes: &[u8],
        line_error: bool,
        idle: bool,
        mut on_frame: impl FnMut(&RcFrame),
    ) {
        match &mut self.parser {
            Parser::Off => {}
            Parser::Crsf(parser) => {
                let mut event =
                    |event: Option<CrsfEvent>, link_quality: &mut Option<u8>| match event {
                        Some(CrsfEvent::Channels(frame)) => on_frame(&frame),
                        Some(CrsfEvent::LinkStatistics(s)) => {
                            *link_quality = Some(s.uplink_link_quality)
                        }
                        None => {}
                    };
                for &byte in bytes {
                    let first = parser.push(byte);
                    event(first, &mut self.link_quality);
                    while let Some(next) = parser.poll() {
                        event(Some(next), &mut self.link_quality);
                    }
                }
                // CRSF has no parity: a flagged byte is just a wrong byte the CRC finds.
                if idle {
                    let first = parser.idle();
                    event(first, &mut self.link_quality);
                    while let Some(next) = parser.poll() {
                        event(Some(next), &mut self.link_quality);
                    }
                }
            }
            Parser::Sbus(parser) => {
                for &byte in bytes {
                    if let Some(frame) = parser.push(byte) {
                        on_frame(&frame);
                    }
                }
                if line_error {
                    parser.line_error();
                }
                if idle && let Some(frame) = parser.idle() {
                    on_frame(&frame);
                }
            }
        }
    }

    /// Frames good and bad so far.
    pub fn counts(&self) -> RcCounts {
        match &self.parser {
            Parser::Off => RcCounts::default(),
            Parser::Crsf(p) => {
                let s = p.stats();
                RcCounts {
                    good: s
                        .channel_frames
                        .saturating_add(s.link_statistics)
                        .saturating_add(s.other_frames),
                    bad: s
                        .bad_length
                        .saturating_add(s.bad_crc)
                        .saturating_add(s.bad_payload)
                        .saturating_add(s.truncated),
                }
            }
            Parser::Sbus(p) => {
                let s = p.stats();
                RcCounts {
                    good: s.frames,
                    bad: s
                        .bad_header
                        .saturating_add(s.bad_footer)
                        .saturating_add(s.bad_flags)
                        .saturating_add(s.truncated)
                        .saturating_add(s.overlong)
                        .saturating_add(s.line_errors),
                }
            }
        }
    }

    /// The signal's strength as MAVLink's `RC_CHANNELS` carries it: CRSF's uplink link quality
    /// (0 to 100 %) as 0 to 254, or 255 (unknown) before any link statistics and for SBUS.
    pub fn rssi(&self) -> u8 {
        match (&self.parser, self.link_quality) {
            (Parser::Crsf(_), Some(lq)) => (u16::from(lq.min(100)) * 254 / 100) as u8,
            _ => u8::MAX,
        }
    }
}

/// The manual input of a channel frame through `map` (`RC_MAP_*`): none for a frame in
/// failsafe, or when a stick's channel is not in the frame.
pub fn manual_input(frame: &RcFrame, map: &RcMap) -> Option<ManualInput> {
    map.input(frame.sticks()?)
}

#[cfg(test)]
mod tests;
