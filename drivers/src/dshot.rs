//! DShot600 frames for the ESCs: the 16-bit frame (11-bit value, telemetry request
//! bit, 4-bit checksum), the timer compare values that draw its bits, and the interleaved
//! buffer a timer's update-event DMA burst writes to its compare registers, one row per bit.
//!
//! The DShot frame: `value << 5 | telemetry << 4 | crc`, with `crc` the XOR of the three
//! nibbles of `value << 1 | telemetry`, sent most significant bit first. Values 1..=47 are
//! commands, 48..=2047 throttle, 0 stops the motor. DShot600 bits last 1.667 us; a one is high
//! for 75 % of it, a zero for 37.5 %.
//!
//! Bidirectional DShot (PX4's `DSHOT_BIDIR_EN`): the frame's checksum is inverted
//! ([`bidirectional_frame`]), which asks the ESC to answer with its RPM
//! ([`crate::dshot_telemetry`]), and the line is inverted: it idles high and each bit starts
//! with a falling edge, low for the bit's high time above. The timer draws it with the same
//! compare values ([`fill_burst`]) and the channel's output polarity set active low: a bit's
//! compare value is then its low time, and the burst's closing zeros leave the line high.

/// The value that stops the motor (the only one sent while disarmed).
pub const STOP: u16 = 0;
/// The smallest throttle value (values below it are commands).
pub const MIN_THROTTLE: u16 = 48;
/// The largest throttle value (11 bits).
pub const MAX_THROTTLE: u16 = 2047;
/// DShot600's bit rate, bits per second.
pub const DSHOT600_BIT_HZ: u32 = 600_000;
/// Slots of a frame in the burst buffer: 16 bits and two low slots after them, so the line
/// rests low between frames whatever the timer does after the last transfer.
pub const SLOTS: usize = 18;

/// The 16-bit frame for `value` (0..=2047; larger values saturate at [`MAX_THROTTLE`]),
/// asking for telemetry if `telemetry`.
pub fn frame(value: u16, telemetry: bool) -> u16 {
    let packet = (value.min(MAX_THROTTLE) << 1) | u16::from(telemetry);
    let crc = (packet ^ (packet >> 4) ^ (packet >> 8)) & 0x0F;
    (packet << 4) | crc
}

/// The bidirectional DShot frame for `value`: [`frame`]'s bits with the checksum inverted
/// (`!(p ^ p >> 4 ^ p >> 8) & 0xF` of the 12-bit packet `p`), which an ESC takes as the
/// request to answer each frame with its RPM.
pub fn bidirectional_frame(value: u16, telemetry: bool) -> u16 {
    frame(value, telemetry) ^ 0x000F
}

/// The throttle value for a command fraction in `[0, 1]`: 0 (stop) at or below zero and for
/// a non-finite fraction, otherwise 48..=2047 in proportion.
pub fn throttle_value(fraction: f32) -> u16 {
    if fraction.is_nan() || fraction <= 0.0 {
        return STOP;
    }
    let span = f32::from(MAX_THROTTLE - MIN_THROTTLE);
    let scaled = shared::math::round(fraction.min(1.0) * span) as u16;
    MIN_THROTTLE + scaled.min(MAX_THROTTLE - MIN_THROTTLE)
}

/// The timer's counts for one DShot bit at the timer's counting clock.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BitTiming {
    /// Counts per bit: the auto-reload value plus one.
    pub period: u16,
    /// Compare value (high time) of a one.
    pub one: u16,
    /// Compare value (high time) of a zero.
    pub zero: u16,
}

/// A timer clock too slow for DShot600: fewer than 20 counts per bit make the high times too
/// coarse. (Any `u32` clock fits a 16-bit timer: 2^32 Hz gives 7,158 counts per bit.)
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClockTooSlow {
    /// The timer clock, Hz.
    pub timer_hz: u32,
}

impl core::fmt::Display for ClockTooSlow {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "a {} Hz timer clock is too slow for DShot600 (at least 12 MHz)",
            self.timer_hz
        )
    }
}

impl BitTiming {
    /// DShot600 at a timer counting at `timer_hz` (no prescaler).
    pub fn dshot600(timer_hz: u32) -> Result<Self, ClockTooSlow> {
        let period = timer_hz / DSHOT600_BIT_HZ;
        if period < 20 {
            return Err(ClockTooSlow { timer_hz });
        }
        // At most 7,158 counts.
        Ok(Self::from_period(period as u16))
    }

    /// The timing of a timer already running at DShot600's bit rate with `period` counts per
    /// bit: 75 % and 37.5 % of the bit, rounded to the nearest count.
    pub fn from_period(period: u16) -> Self {
        let p = u32::from(period);
        Self {
            period,
            one: ((p * 3 + 2) / 4) as u16,
            zero: ((p * 3 + 4) / 8) as u16,
        }
    }
}

/// Fills `burst` with the compare values that send `frames[c]` on channel `c` of one timer:
/// row `bit` holds the channels' values for that bit (the order a DMA burst writes CCR1..CCRn
/// at each update event), [`SLOTS`] rows, the last two low. Returns the number of values
/// written, or `None` if `burst` is shorter than `SLOTS * frames.len()`.
pub fn fill_burst(frames: &[u16], timing: BitTiming, burst: &mut [u16]) -> Option<usize> {
    let channels = frames.len();
    let len = SLOTS * channels;
    let burst = burst.get_mut(..len)?;
    for (slot, row) in burst.chunks_exact_mut(channels.max(1)).enumerate() {
        for (value, frame) in row.iter_mut().zip(frames) {
            *value = if slot < 16 {
                if frame & (0x8000 >> slot) != 0 {
                    timing.one
                } else {
                    timing.zero
                }
            } else {
                0
            };
        }
    }
    Some(len)
}

/// Reads a frame back from one channel's column of a burst buffer (the inverse of
/// [`fill_burst`]): `None` if a slot is neither a one nor a zero.
pub fn decode_burst(
    burst: &[u16],
    channels: usize,
    channel: usize,
    timing: BitTiming,
) -> Option<u16> {
    let mut frame = 0u16;
    for slot in 0..16 {
        let value = *burst.get(slot * channels + channel)?;
        frame <<= 1;
        if value == timing.one {
            frame |= 1;
        } else if value != timing.zero {
            return None;
        }
    }
    Some(frame)
}

/// Whether a received frame's checksum matches its value (what an ESC checks).
pub fn checksum_ok(frame: u16) -> bool {
    frame == self::frame(frame >> 5, frame & 0x10 != 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The line a timer channel draws `count` counts into a bit of compare value `compare`
    /// (PWM mode 1: the reference is active below the compare value), active high or low.
    fn line_high(compare: u16, count: u16, active_low: bool) -> bool {
        (count < compare) != active_low
    }

    /// The inverted checksum by hand: throttle 1046 has checksum 0110, inverted 1001; an
    /// ordinary ESC's check fails on it, so no ESC mistakes one kind for the other.
    #[test]
    fn bidirectional_frames_invert_the_checksum_only() {
        assert_eq!(bidirectional_frame(1046, false), 0b1000_0010_1100_1001);
        for value in [0, 1, 47, 48, 1000, 2047] {
            for telemetry in [false, true] {
                let f = bidirectional_frame(value, telemetry);
                let p = f >> 4;
                assert_eq!(f & 0xF, !(p ^ (p >> 4) ^ (p >> 8)) & 0xF);
                assert_eq!(f >> 4, frame(value, telemetry) >> 4);
                assert!(!checksum_ok(f));
            }
        }
    }

    /// Active low, the same compare values draw the inverted line: high at rest (the burst's
    /// closing zeros), a one low for 75 % of the bit and a zero for 37.5 %, every bit starting
    /// with a falling edge.
    #[test]
    fn an_active_low_channel_draws_the_inverted_line() {
        let t = BitTiming::dshot600(240_000_000).unwrap();
        let low_time = |compare| {
            (0..t.period)
                .filter(|&c| !line_high(compare, c, true))
                .count()
        };
        assert_eq!(low_time(t.one), 300);
        assert_eq!(low_time(t.zero), 150);
        assert_eq!(low_time(0), 0, "idle high");
        assert!(!line_high(t.zero, 0, true) && line_high(t.zero, t.period - 1, true));
        assert!(
            line_high(t.one, 0, false) && !line_high(0, 0, false),
            "normal: idles low"
        );
    }

    /// The worked example of the DShot protocol's write-ups (throttle 1046, no telemetry):
    /// 1000001011000110 = 0x82C6, checksum 0110.
    #[test]
    fn the_worked_example_frame() {
        assert_eq!(frame(1046, false), 0b1000_0010_1100_0110);
        assert_eq!(frame(1046, false) & 0xF, 0b0110);
    }

    /// Hand-computed: value 48 with telemetry: packet 0x061, crc 1 ^ 6 ^ 0 = 7, frame 0x0617.
    #[test]
    fn telemetry_bit_and_checksum_by_hand() {
        assert_eq!(frame(48, true), 0x0617);
        assert_eq!(frame(STOP, false), 0x0000);
        assert_eq!(
            frame(MAX_THROTTLE, false),
            0xFFE0 | ((0xFFE >> 8 ^ 0xFFE >> 4 ^ 0xFFE) & 0xF)
        );
        for value in [0, 1, 47, 48, 1000, 2047] {
            for telemetry in [false, true] {
                assert!(checksum_ok(frame(value, telemetry)));
                assert!(
                    !checksum_ok(frame(value, telemetry) ^ 0x0100),
                    "a flipped bit"
                );
            }
        }
    }

    #[test]
    fn throttle_values_span_48_to_2047_and_stop_for_nothing() {
        assert_eq!(throttle_value(0.0), STOP);
        assert_eq!(throttle_value(-0.3), STOP);
        assert_eq!(throttle_value(f32::NAN), STOP);
        assert_eq!(throttle_value(1e-6), MIN_THROTTLE);
        assert_eq!(throttle_value(0.5), 48 + 1000);
        assert_eq!(throttle_value(1.0), MAX_THROTTLE);
        assert_eq!(throttle_value(7.0), MAX_THROTTLE);
        assert_eq!(throttle_value(f32::INFINITY), MAX_THROTTLE);
    }

    /// TIM1/TIM4/TIM5 count at 240 MHz on this board: 400 counts a bit, 300 for a one, 150
    /// for a zero (1.25 us and 0.625 us).
    #[test]
    fn timing_at_the_boards_timer_clock() {
        let t = BitTiming::dshot600(240_000_000).unwrap();
        assert_eq!(
            t,
            BitTiming {
                period: 400,
                one: 300,
                zero: 150
            }
        );
        assert_eq!(
            BitTiming::dshot600(8_000_000),
            Err(ClockTooSlow {
                timer_hz: 8_000_000
            })
        );
        let fastest = BitTiming::dshot600(u32::MAX).unwrap();
        assert_eq!(fastest.period, 7158);
    }

    #[test]
    fn burst_rows_interleave_the_channels_and_end_low() {
        let t = BitTiming::dshot600(240_000_000).unwrap();
        let frames = [
            frame(1046, false),
            frame(48, true),
            frame(STOP, false),
            frame(2047, true),
        ];
        let mut burst = [0xAAAA; SLOTS * 4];
        assert_eq!(fill_burst(&frames, t, &mut burst), Some(SLOTS * 4));
        // First bit of 0x82C6 is a one, of 0x0617 a zero.
        assert_eq!(&burst[..4], &[t.one, t.zero, t.zero, t.one]);
        assert!(burst[16 * 4..].iter().all(|&v| v == 0));
        for (c, f) in frames.iter().enumerate() {
            assert_eq!(decode_burst(&burst, 4, c, t), Some(*f));
        }
        assert_eq!(fill_burst(&frames, t, &mut [0; SLOTS * 4 - 1]), None);
    }
}
