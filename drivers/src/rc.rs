//! What the safety pilot's radio says, whatever carries it: the RC receiver's 16 channels in
//! microseconds and whether the receiver has given up on the radio link ([`RcFrame`]), as the
//! CRSF ([`crate::crsf`]) and SBUS ([`crate::sbus`]) parsers give it. Where the receiver is
//! wired on the Pixhawk 6C is in docs/hardware.md ("RC receivers").
//!
//! Both protocols carry the channels the same way: 16 values of 11 bits, packed least
//! significant bit first into 22 bytes ([`unpack_channels`]; the CRSF working group's
//! `CRSF_FRAMETYPE_RC_CHANNELS_PACKED` page, the layout PX4's `src/lib/rc/sbus.cpp` decodes for
//! SBUS). Both scale them alike ([`to_us`]): 172, 992 and 1811 are 988, 1500 and 2012 us.
//!
//! A frame that comes out of a parser passed every check its protocol has (CRSF: the CRC;
//! SBUS, which has none: header, flags, footer and the UART's parity); a frame that did not
//! never comes out. What the receiver says about the link is in the frame itself: a frame in
//! failsafe holds the receiver's own failsafe positions, not the pilot's sticks, and
//! [`RcFrame::sticks`] gives none. A receiver that stops sending (the usual failsafe of
//! ExpressLRS and of many SBUS receivers) produces no frame at all: the consumer must time the
//! frames out itself, the parsers have no clock.

/// Channels in a frame (both protocols carry 16 proportional channels).
pub const CHANNELS: usize = 16;
/// Bytes of 16 packed 11-bit channels.
pub const PACKED_LEN: usize = 22;
/// The largest 11-bit channel value.
pub const MAX_VALUE: u16 = 0x7FF;
/// The channel value of a centred stick (1500 us).
pub const CENTRE_VALUE: u16 = 992;

/// One frame of the receiver's channels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RcFrame {
    /// The channels, us ([`to_us`] of the 11-bit values: 880 to 2159, 988 to 2012 for a
    /// radio's normal travel); those past `count` are 0.
    pub channels: [u16; CHANNELS],
    /// How many channels the frame carries (16 for both protocols).
    pub count: u8,
    /// The receiver is in failsafe: the channels are its failsafe positions, not the pilot's
    /// sticks, and must not be flown (SBUS: flag bit 3; CRSF: the last link statistics said
    /// the uplink's link quality is 0).
    pub failsafe: bool,
    /// The receiver missed at least one radio frame and repeats the last channels it had
    /// (SBUS flag bit 2; CRSF has no such flag). The channels are still the pilot's.
    pub frame_lost: bool,
}

impl RcFrame {
    /// The channels the pilot commands, or `None` while the receiver is in failsafe: the one
    /// accessor a consumer should fly from.
    pub fn sticks(&self) -> Option<&[u16]> {
        if self.failsafe {
            return None;
        }
        self.channels.get(..usize::from(self.count))
    }
}

/// The pulse width, us, of an 11-bit channel value: `880 + 5 * value / 8`, rounded to the
/// nearest microsecond (halves up), so that 172, 992 and 1811 are 988, 1500 and 2012 us as
/// the CRSF working group's `CRSF_FRAMETYPE_RC_CHANNELS_PACKED` page states, and SBUS scales as
/// Betaflight's `src/main/rx/sbus_channels.c` does (`5 * value / 8 + 880`, its linear fit of a
/// FrSky X4R: 173, 993 and 1812 to 988, 1500 and 2012 us). Equal to `(value - 992) * 5 / 8 +
/// 1500` rounded. Only the low 11 bits of `value` count. PX4's `sbus.cpp` scales SBUS
/// differently (200..1800 to 1000..2000 us, so 992 is 1494 us); this keeps both protocols on
/// one scale with the centre at 1500.
pub const fn to_us(value: u16) -> u16 {
    let value = (value & MAX_VALUE) as u32;
    (880 + (5 * value + 4) / 8) as u16
}

/// The 11-bit channel value whose pulse width is `us` ([`to_us`]'s inverse): the smallest value
/// [`to_us`] takes to `us`, so that `to_us(from_us(us)) == us` for every `us` from 880 to 2159;
/// pulse widths outside that range are taken to its ends. What a transmitter (or the HIL plant,
/// docs/hil.md) puts on the wire for a channel in microseconds.
pub const fn from_us(us: u16) -> u16 {
    let us = if us < 880 {
        880
    } else if us > 2159 {
        2159
    } else {
        us
    };
    // The least `v` with `(5 v + 4) / 8 >= us - 880`: `ceil((8 (us - 880) - 4) / 5)`.
    let target = 8 * (us as u32 - 880);
    if target < 4 {
        return 0;
    }
    (target - 4).div_ceil(5) as u16
}

/// The 16 values' low 11 bits packed least significant bit first ([`unpack_channels`]'s
/// inverse).
pub fn pack_channels(values: &[u16; CHANNELS]) -> [u8; PACKED_LEN] {
    let mut packed = [0u8; PACKED_LEN];
    let mut bits = 0u32;
    let mut held = 0u32;
    let mut at = 0usize;
    for &value in values {
        bits |= u32::from(value & MAX_VALUE) << held;
        held += 11;
        while held >= 8 {
            if let Some(byte) = packed.get_mut(at) {
                *byte = bits as u8;
            }
            bits >>= 8;
            held -= 8;
            at += 1;
        }
    }
    packed
}

/// The 16 11-bit values packed least significant bit first in `packed`: channel 0 is bits
/// 0..=10 (byte 0 and the low three bits of byte 1), channel 1 the next 11, and so on.
pub fn unpack_channels(packed: &[u8; PACKED_LEN]) -> [u16; CHANNELS] {
    let mut values = [0u16; CHANNELS];
    let mut bits = 0u32;
    let mut held = 0u32;
    let mut channel = 0usize;
    for &byte in packed {
        bits |= u32::from(byte) << held;
        held += 8;
        while held >= 11 {
            if let Some(value) = values.get_mut(channel) {
                *value = (bits & u32::from(MAX_VALUE)) as u16;
            }
            bits >>= 11;
            held -= 11;
            channel += 1;
        }
    }
    values
}

/// The frame of 16 channels in `packed`, in us.
pub(crate) fn frame_from_packed(
    packed: &[u8; PACKED_LEN],
    failsafe: bool,
    frame_lost: bool,
) -> RcFrame {
    RcFrame {
        channels: unpack_channels(packed).map(to_us),
        count: CHANNELS as u8,
        failsafe,
        frame_lost,
    }
}

/// Helpers the parsers' tests share, written apart from the parsers so that they check them.
#[cfg(test)]
pub(crate) mod testing {
    use super::{CHANNELS, PACKED_LEN};

    /// The 16 values packed one bit at a time (bit `i` of channel `c` is bit `11 c + i` of the
    /// 176-bit little-endian field), not the parsers' shift-and-mask.
    pub fn pack_bitwise(values: &[u16; CHANNELS]) -> [u8; PACKED_LEN] {
        let mut packed = [0u8; PACKED_LEN];
        for (c, &value) in values.iter().enumerate() {
            for i in 0..11 {
                if value >> i & 1 == 1 {
                    let bit = 11 * c + i;
                    packed[bit / 8] |= 1 << (bit % 8);
                }
            }
        }
        packed
    }

    /// The 16 values read one bit at a time, the inverse of [`pack_bitwise`].
    pub fn unpack_bitwise(packed: &[u8; PACKED_LEN]) -> [u16; CHANNELS] {
        let mut values = [0u16; CHANNELS];
        for (c, value) in values.iter_mut().enumerate() {
            for i in 0..11 {
                let bit = 11 * c + i;
                if packed[bit / 8] >> (bit % 8) & 1 == 1 {
                    *value |= 1 << i;
                }
            }
        }
        values
    }

    /// The microseconds of a value by the spec's formula in floating point, rounded half up:
    /// `(v - 992) * 5 / 8 + 1500`.
    pub fn us_by_formula(value: u16) -> u16 {
        let us = (f64::from(value) - 992.0) * 5.0 / 8.0 + 1500.0;
        (us + 0.5).floor() as u16
    }

    /// What the UART hands the glue: a byte, the line going idle, or a byte received with a
    /// parity, framing or noise error (which the glue reports instead of the byte).
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum Tok {
        /// A byte received.
        Byte(u8),
        /// The line went idle.
        Idle,
        /// A byte received with an error.
        Error,
    }

    /// One way a stream is damaged; positions are taken modulo the stream's length.
    #[derive(Clone, Debug)]
    pub enum Corruption {
        /// One bit of a byte flipped (nothing if the token there is no byte).
        Flip { at: usize, bit: u8 },
        /// `n` tokens lost (bytes and idles alike).
        Cut { at: usize, n: usize },
        /// Up to `n` bytes lost from `at` on (a UART overrun), the idle lines among them kept.
        LoseBytes { at: usize, n: usize },
        /// Noise bytes inserted.
        Insert { at: usize, noise: Vec<u8> },
        /// An idle line inserted (a pause inside a frame).
        InsertIdle { at: usize },
    }

    /// Any one [`Corruption`].
    pub fn corruption() -> impl Strategy<Value = Corruption> {
        prop_oneof![
            3 => (any::<usize>(), 0u8..8).prop_map(|(at, bit)| Corruption::Flip { at, bit }),
            2 => (any::<usize>(), 1usize..30).prop_map(|(at, n)| Corruption::Cut { at, n }),
            2 => (any::<usize>(), vec(any::<u8>(), 1..12))
                .prop_map(|(at, noise)| Corruption::Insert { at, noise }),
            1 => any::<usize>().prop_map(|at| Corruption::InsertIdle { at }),
        ]
    }

    /// One [`Corruption`] of a UART's kind: a flipped bit, bytes lost to an overrun (the idle
    /// lines still seen), noise bytes, a pause.
    pub fn uart_corruption() -> impl Strategy<Value = Corruption> {
        prop_oneof![
            3 => (any::<usize>(), 0u8..8).prop_map(|(at, bit)| Corruption::Flip { at, bit }),
            2 => (any::<usize>(), 1usize..30).prop_map(|(at, n)| Corruption::LoseBytes { at, n }),
            2 => (any::<usize>(), vec(any::<u8>(), 1..12))
                .prop_map(|(at, noise)| Corruption::Insert { at, noise }),
            1 => any::<usize>().prop_map(|at| Corruption::InsertIdle { at }),
        ]
    }

    /// `tokens` damaged by `corruption`. A flipped bit becomes [`Tok::Error`] when
    /// `parity_catches_flips` (8E2: the UART's parity finds any one flipped bit of a byte),
    /// else a wrong byte (8N1).
    pub fn corrupt(tokens: &mut Vec<Tok>, corruption: &Corruption, parity_catches_flips: bool) {
        let len = tokens.len().max(1);
        match *corruption {
            Corruption::Flip { at, bit } => {
                if let Some(token) = tokens.get_mut(at % len)
                    && let Tok::Byte(byte) = *token
                {
                    *token = if parity_catches_flips {
                        Tok::Error
                    } else {
                        Tok::Byte(byte ^ (1 << bit))
                    };
                }
            }
            Corruption::Cut { at, n } => {
                let at = at % len;
                let end = (at + n).min(tokens.len());
                if at < end {
                    tokens.drain(at..end);
                }
            }
            Corruption::LoseBytes { at, n } => {
                let mut at = at % len;
                let mut lost = 0;
                while lost < n && at < tokens.len() {
                    if let Tok::Byte(_) = tokens[at] {
                        tokens.remove(at);
                        lost += 1;
                    } else {
                        at += 1;
                    }
                }
            }
            Corruption::Insert { at, ref noise } => {
                let at = (at % (tokens.len() + 1)).min(tokens.len());
                tokens.splice(at..at, noise.iter().map(|&b| Tok::Byte(b)));
            }
            Corruption::InsertIdle { at } => {
                let at = (at % (tokens.len() + 1)).min(tokens.len());
                tokens.insert(at, Tok::Idle);
            }
        }
    }

    /// The stream's runs of bytes between idles and errors: no frame spans either.
    pub fn chunks(tokens: &[Tok]) -> Vec<Vec<u8>> {
        let mut chunks = std::vec![Vec::new()];
        for token in tokens {
            match *token {
                Tok::Byte(byte) => chunks.last_mut().unwrap().push(byte),
                Tok::Idle | Tok::Error => chunks.push(Vec::new()),
            }
        }
        chunks
    }

    /// A test runner for `cases` cases that leaves no regression files behind.
    pub fn runner(cases: u32) -> proptest::test_runner::TestRunner {
        proptest::test_runner::TestRunner::new(proptest::test_runner::Config {
            cases,
            failure_persistence: None,
            ..proptest::test_runner::Config::default()
        })
    }

    use proptest::collection::vec;
    use proptest::prelude::*;
    use std::vec::Vec;
}

#[cfg(test)]
mod tests {
    use super::testing::*;
    use super::*;

    #[test]
    fn the_specs_three_points() {
        // The CRSF working group: 172 is 988 us, 992 is 1500 us, 1811 is 2012 us.
        assert_eq!(to_us(172), 988);
        assert_eq!(to_us(CENTRE_VALUE), 1500);
        assert_eq!(to_us(1811), 2012);
        // The whole 11-bit range, and the formula at every value.
        assert_eq!(to_us(0), 880);
        assert_eq!(to_us(MAX_VALUE), 2159);
        for value in 0..=MAX_VALUE {
            assert_eq!(to_us(value), us_by_formula(value), "value {value}");
        }
        // Bits above the 11 are not the channel's.
        assert_eq!(to_us(0x800 | 992), 1500);
    }

    #[test]
    fn unpacking_matches_the_bitwise_reading() {
        // Every channel at a distinct value, then each channel alone at its extremes.
        let distinct: [u16; CHANNELS] = core::array::from_fn(|c| (c as u16 * 131 + 7) & MAX_VALUE);
        let packed = pack_bitwise(&distinct);
        assert_eq!(unpack_channels(&packed), distinct);
        assert_eq!(unpack_bitwise(&packed), distinct);
        for c in 0..CHANNELS {
            for value in [0, 1, 172, 992, 1811, MAX_VALUE] {
                let mut values = [CENTRE_VALUE; CHANNELS];
                values[c] = value;
                assert_eq!(unpack_channels(&pack_bitwise(&values)), values);
            }
        }
    }

    #[test]
    fn from_us_inverts_to_us_over_the_whole_range() {
        for us in 880..=2159u16 {
            let value = from_us(us);
            assert_eq!(to_us(value), us, "{us} us");
            // The smallest such value.
            assert!(value == 0 || to_us(value - 1) < us, "{us} us");
        }
        assert_eq!(from_us(1500), CENTRE_VALUE);
        assert_eq!((from_us(988), from_us(2012)), (172, 1811));
        assert_eq!((from_us(0), from_us(u16::MAX)), (0, from_us(2159)));
        assert_eq!(to_us(from_us(u16::MAX)), 2159);
    }

    #[test]
    fn packing_is_the_bitwise_packing() {
        let distinct: [u16; CHANNELS] = core::array::from_fn(|c| (c as u16 * 131 + 7) & MAX_VALUE);
        assert_eq!(pack_channels(&distinct), pack_bitwise(&distinct));
        assert_eq!(unpack_channels(&pack_channels(&distinct)), distinct);
        // Bits above the 11 are dropped, not carried into the next channel.
        let mut high = [0u16; CHANNELS];
        high[0] = 0xF800 | 5;
        assert_eq!(unpack_channels(&pack_channels(&high))[..2], [5, 0]);
    }

    #[test]
    fn a_failsafe_frame_has_no_sticks() {
        let packed = pack_bitwise(&[CENTRE_VALUE; CHANNELS]);
        let live = frame_from_packed(&packed, false, true);
        assert_eq!(live.sticks(), Some(&[1500u16; CHANNELS][..]));
        let failsafe = frame_from_packed(&packed, true, false);
        assert_eq!(failsafe.sticks(), None);
    }
}
