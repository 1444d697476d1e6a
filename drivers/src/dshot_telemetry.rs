//! Bidirectional DShot's answer: each ESC's electrical RPM, decoded from the edges its line
//! shows after a bidirectional frame ([`crate::dshot::bidirectional_frame`]).
//!
//! The protocol as its public descriptions give it ("DShot and Bidirectional DShot",
//! brushlesswhoop.com, section "eRPM Telemetry"; the behaviour of Betaflight's
//! `dshot_bitbang_decode.c` and of PX4's STM32 `dshot.c`):
//! - About 30 us after the frame the ESC drives the line (idle high) for 21 bits at 5/4 of the
//!   frame's bit rate (DShot600: 750 kbit/s, 1.333 us a bit), then lets it go back high.
//! - The first bit is a start bit, always low. Each of the other 20 says whether the line
//!   changes level at its start (1) or not (0): they are `l ^ (l >> 1)` of the 21 levels `l`.
//! - The 20 bits are four 5-bit GCR quintets, one nibble each ([`GCR`]), the most significant
//!   first. A GCR code has at most two zeros in a row, so the line holds a level one to three
//!   bits.
//! - The 16 bits are `eee mmmmmmmmm cccc`: the time between the motor's electrical revolutions,
//!   `m << e` microseconds, and a checksum that makes the XOR of the four nibbles 0xF.
//!   eRPM = 60,000,000 / period; the longest period (0xFFF: 65,408 us) says the motor stands.
//! - Extended DShot telemetry (EDT, sent only when an ESC was asked for it): a nonzero exponent
//!   with the mantissa's top bit clear, which no eRPM has (the ESC normalises it), carries a
//!   temperature, voltage, current or status byte instead; it is recognised, not an RPM.
//!
//! [`decode`] works from the timestamps of the line's edges (a timer's input capture on both
//! edges, in timer counts), the first being the start bit's falling edge. Each interval
//! between edges is rounded to whole bits, so an interval may be off by anything under half a
//! bit without changing the answer: an edge up to a quarter bit from its place, or the ESC's
//! clock a few percent off (the two together only while their sum stays under half a bit).

use core::fmt;

/// Bits of an answer: the start bit and the 20 GCR bits.
pub const ANSWER_BITS: u32 = 21;
/// The fewest edges a well-formed answer has (each GCR code has at least two ones, and the
/// line ends high).
pub const MIN_EDGES: usize = 10;
/// The most edges a well-formed answer has (four ones in a GCR code at most, the start edge and
/// the return to idle).
pub const MAX_EDGES: usize = 18;
/// The longest period an answer gives, us (`0xFFF`): the motor stands still.
pub const STOPPED_PERIOD_US: u32 = 0x1FF << 7;

/// Each nibble's GCR quintet (the nibble is the index).
pub const GCR: [u8; 16] = [
    0x19, 0x1B, 0x12, 0x13, 0x1D, 0x15, 0x16, 0x17, 0x1A, 0x09, 0x0A, 0x0B, 0x1E, 0x0D, 0x0E, 0x0F,
];

/// Each quintet's nibble ([`GCR`] inverted), 0xFF for the 16 quintets that are no code.
const NIBBLE: [u8; 32] = {
    let mut table = [0xFF; 32];
    let mut nibble = 0;
    while nibble < 16 {
        table[GCR[nibble] as usize] = nibble as u8;
        nibble += 1;
    }
    table
};

/// What an ESC's answer says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Answer {
    /// The motor's electrical RPM (0: standing still).
    Erpm(u32),
    /// An extended-telemetry frame, not an RPM: its kind (the top nibble: 2 temperature,
    /// 4 voltage, 6 current, 8 and 10 debug, 12 stress, 14 status) and its byte.
    Extended {
        /// The frame's kind.
        kind: u8,
        /// Its value.
        value: u8,
    },
}

/// Why the edges seen after a frame are no answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnswerError {
    /// No edge at all.
    NoAnswer,
    /// The answer's bit period was given as zero counts.
    NoBitPeriod,
    /// Fewer edges than any answer has.
    TooFewEdges {
        /// Edges seen.
        edges: usize,
    },
    /// More edges than any answer has.
    TooManyEdges {
        /// Edges seen.
        edges: usize,
    },
    /// An odd number of edges: the line was left low.
    LeftLow {
        /// Edges seen.
        edges: usize,
    },
    /// The interval after edge `edge` is not one to three bits long.
    BadInterval {
        /// The interval's first edge (0: the start bit's).
        edge: usize,
        /// Its length, timer counts.
        counts: u16,
    },
    /// The intervals add up to more bits than an answer's 21.
    TooLong {
        /// Bits counted.
        bits: u32,
    },
    /// A quintet that is no GCR code.
    InvalidQuintet {
        /// Which (0: the first sent).
        index: u8,
        /// Its five bits.
        code: u8,
    },
    /// The four nibbles' XOR is not 0xF.
    Checksum {
        /// The 16 bits decoded.
        value: u16,
    },
    /// An eRPM answer with a period of zero.
    ZeroPeriod,
}

impl fmt::Display for AnswerError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::NoAnswer => write!(f, "no DShot answer: the line showed no edge"),
            Self::NoBitPeriod => write!(f, "DShot answer decoded with a bit period of 0 counts"),
            Self::TooFewEdges { edges } => write!(
                f,
                "DShot answer has {edges} edges, fewer than any answer's {MIN_EDGES}"
            ),
            Self::TooManyEdges { edges } => write!(
                f,
                "DShot answer has {edges} edges, more than any answer's {MAX_EDGES}"
            ),
            Self::LeftLow { edges } => write!(
                f,
                "DShot answer left the line low after {edges} edges (cut short or a glitch)"
            ),
            Self::BadInterval { edge, counts } => write!(
                f,
                "DShot answer's interval after edge {edge} ({counts} counts) is not 1 to 3 bits"
            ),
            Self::TooLong { bits } => {
                write!(
                    f,
                    "DShot answer runs {bits} bits, longer than {ANSWER_BITS}"
                )
            }
            Self::InvalidQuintet { index, code } => write!(
                f,
                "DShot answer's quintet {index} ({code:#07b}) is no GCR code"
            ),
            Self::Checksum { value } => write!(
                f,
                "DShot answer {value:#06x} fails its checksum (nibbles' XOR not 0xF)"
            ),
            Self::ZeroPeriod => write!(f, "DShot answer gives an eRPM period of 0 us"),
        }
    }
}

/// The answer's bit period in timer counts for the frame's `frame_bit_counts` (4/5 of it).
pub fn answer_bit_counts(frame_bit_counts: u16) -> u16 {
    (u32::from(frame_bit_counts) * 4 / 5) as u16
}

/// Decodes an answer from the timestamps of its line's edges, in timer counts (a 16-bit
/// counter: they may wrap), the first being the start bit's falling edge; `counts_per_bit` is
/// the answer's bit period ([`answer_bit_counts`]).
pub fn decode(edges: &[u16], counts_per_bit: u16) -> Result<Answer, AnswerError> {
    let n = edges.len();
    if n == 0 {
        return Err(AnswerError::NoAnswer);
    }
    if counts_per_bit == 0 {
        return Err(AnswerError::NoBitPeriod);
    }
    if n < MIN_EDGES {
        return Err(AnswerError::TooFewEdges { edges: n });
    }
    if n > MAX_EDGES {
        return Err(AnswerError::TooManyEdges { edges: n });
    }
    if !n.is_multiple_of(2) {
        return Err(AnswerError::LeftLow { edges: n });
    }
    let bit = u32::from(counts_per_bit);
    // The line's levels, the first bit highest; the start bit is low.
    let (mut levels, mut bits, mut level) = (0u32, 0u32, 0u32);
    for (edge, pair) in edges.windows(2).enumerate() {
        let counts = pair[1].wrapping_sub(pair[0]);
        let run = (2 * u32::from(counts) + bit) / (2 * bit);
        if !(1..=3).contains(&run) {
            return Err(AnswerError::BadInterval { edge, counts });
        }
        bits += run;
        if bits > ANSWER_BITS {
            return Err(AnswerError::TooLong { bits });
        }
        levels = (levels << run) | (level * ((1 << run) - 1));
        level ^= 1;
    }
    // After the last edge (a rising one) the line stays high to the end.
    let rest = ANSWER_BITS - bits;
    levels = (levels << rest) | ((1 << rest) - 1);
    let gcr = (levels ^ (levels >> 1)) & 0xF_FFFF;
    let mut value = 0u16;
    for index in 0..4u8 {
        let code = ((gcr >> (15 - 5 * u32::from(index))) & 0x1F) as u8;
        let nibble = NIBBLE[usize::from(code)];
        if nibble > 0xF {
            return Err(AnswerError::InvalidQuintet { index, code });
        }
        value = (value << 4) | u16::from(nibble);
    }
    if (value ^ (value >> 4) ^ (value >> 8) ^ (value >> 12)) & 0xF != 0xF {
        return Err(AnswerError::Checksum { value });
    }
    let data = value >> 4;
    let (exponent, mantissa) = (data >> 9, data & 0x1FF);
    if exponent != 0 && mantissa & 0x100 == 0 {
        return Ok(Answer::Extended {
            kind: (data >> 8) as u8,
            value: data as u8,
        });
    }
    match u32::from(mantissa) << exponent {
        0 => Err(AnswerError::ZeroPeriod),
        STOPPED_PERIOD_US => Ok(Answer::Erpm(0)),
        period => Ok(Answer::Erpm((60_000_000 + period / 2) / period)),
    }
}

/// The motor's (mechanical) RPM for an eRPM and its magnet poles: eRPM / (poles / 2).
pub fn rpm(erpm: u32, poles: u8) -> f32 {
    erpm as f32 / f32::from((poles / 2).max(1))
}

/// The 16 bits an ESC sends for the 12-bit `data` (`eee mmmmmmmmm`): `data` and its
/// checksum.
pub fn answer_value(data: u16) -> u16 {
    let data = data & 0xFFF;
    (data << 4) | (!(data ^ (data >> 4) ^ (data >> 8)) & 0xF)
}

/// The 16 bits an ESC sends for an eRPM: the period, 60,000,000 / eRPM us, as `m << e` with
/// the mantissa `m` in 9 bits (truncated), and the checksum; 0 and eRPMs too slow to time
/// give the standing motor's 0xFFF.
pub fn encode_erpm(erpm: u32) -> u16 {
    let mut mantissa = match erpm {
        0 => u32::MAX,
        e => (60_000_000 + e / 2) / e,
    };
    let mut exponent = 0;
    while mantissa > 0x1FF && exponent < 7 {
        mantissa >>= 1;
        exponent += 1;
    }
    let data = if mantissa > 0x1FF {
        0xFFF
    } else {
        (exponent << 9) | mantissa as u16
    };
    answer_value(data)
}

/// The 20 GCR bits of an answer's 16 (the first nibble's quintet highest).
pub fn gcr_of(value: u16) -> u32 {
    (0..4).fold(0, |gcr, i| {
        (gcr << 5) | u32::from(GCR[usize::from((value >> (12 - 4 * i)) & 0xF)])
    })
}

/// The edges (timer counts from `start`, wrapping) the line shows for the 20 bits `gcr` at
/// `counts_per_bit`, as an ESC sends them: the start bit's falling edge, one per 1 in `gcr`,
/// and the return to high if the last bit is low. Returns them and how many there are.
pub fn edges_of(gcr: u32, counts_per_bit: u16, start: u16) -> ([u16; 22], usize) {
    let mut edges = [0u16; 22];
    let mut n = 1;
    edges[0] = start;
    let mut low = true;
    for bit in 1..=20u16 {
        if (gcr >> (20 - bit)) & 1 != 0 {
            edges[n] = start.wrapping_add(bit.wrapping_mul(counts_per_bit));
            n += 1;
            low = !low;
        }
    }
    if low {
        edges[n] = start.wrapping_add(21u16.wrapping_mul(counts_per_bit));
        n += 1;
    }
    (edges, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The board's timers count 400 per DShot600 bit: 320 per answer bit.
    const BIT: u16 = 320;

    fn edges(value: u16, start: u16) -> std::vec::Vec<u16> {
        let (e, n) = edges_of(gcr_of(value), BIT, start);
        e[..n].to_vec()
    }

    /// A small deterministic generator for the jitter and random-edge tests.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 16) as u32
        }
    }

    /// By hand: 20,000 eRPM is a 3,000 us period, 375 << 3: data 0x777, checksum
    /// !(7 ^ 7 ^ 7) = 8, value 0x7778; GCR 10111 10111 10111 11010.
    #[test]
    fn a_known_erpm_by_hand_and_back() {
        assert_eq!(answer_bit_counts(400), BIT);
        assert_eq!(encode_erpm(20_000), 0x7778);
        assert_eq!(gcr_of(0x7778), 0b10111_10111_10111_11010);
        let e = edges(0x7778, 1000);
        // Start edge, then one per 1 (16), the last bit high: no return edge.
        assert_eq!(e.len(), 16);
        assert_eq!(&e[..3], &[1000, 1000 + BIT, 1000 + 3 * BIT]);
        assert_eq!(decode(&e, BIT), Ok(Answer::Erpm(20_000)));
        // 14 poles: 7 pole pairs.
        assert_eq!(rpm(20_000, 14), 20_000.0 / 7.0);
        assert_eq!(rpm(700, 0), 700.0, "no pole pairs read as one");
    }

    /// Every 12-bit value survives encoding to edges and decoding, with a start that makes
    /// the counter wrap; each has 10 to 18 edges.
    #[test]
    fn every_value_round_trips() {
        for data in 0..=0xFFFu16 {
            let value = answer_value(data);
            let e = edges(value, 65_000);
            assert!((MIN_EDGES..=MAX_EDGES).contains(&e.len()), "{data:#x}");
            let (exponent, mantissa) = (data >> 9, data & 0x1FF);
            let expected = if exponent != 0 && mantissa & 0x100 == 0 {
                Ok(Answer::Extended {
                    kind: (data >> 8) as u8,
                    value: data as u8,
                })
            } else {
                match u32::from(mantissa) << exponent {
                    0 => Err(AnswerError::ZeroPeriod),
                    STOPPED_PERIOD_US => Ok(Answer::Erpm(0)),
                    p => Ok(Answer::Erpm((60_000_000 + p / 2) / p)),
                }
            };
            assert_eq!(decode(&e, BIT), expected, "{data:#x}");
        }
    }

    #[test]
    fn erpms_encode_within_their_mantissas_resolution() {
        for erpm in [1_000, 7_777, 20_000, 123_456, 400_000] {
            let Ok(Answer::Erpm(back)) = decode(&edges(encode_erpm(erpm), 0), BIT) else {
                panic!("{erpm} did not decode");
            };
            // Nine bits of mantissa: within 1/256 (truncated), and never above.
            assert!(
                back >= erpm && back - erpm <= erpm / 256 + 1,
                "{erpm} -> {back}"
            );
        }
    }

    #[test]
    fn a_standing_motor_reads_zero() {
        assert_eq!(encode_erpm(0), 0xFFF0);
        assert_eq!(encode_erpm(900), 0xFFF0, "slower than 65,408 us a turn");
        assert_eq!(decode(&edges(0xFFF0, 7), BIT), Ok(Answer::Erpm(0)));
    }

    #[test]
    fn a_wrong_checksum_is_refused() {
        // 0x7779: valid GCR throughout, but 7 ^ 7 ^ 7 ^ 9 = 0xE.
        assert_eq!(
            decode(&edges(0x7779, 0), BIT),
            Err(AnswerError::Checksum { value: 0x7779 })
        );
    }

    #[test]
    fn an_invalid_quintet_is_refused() {
        // 11111 is no GCR code (five transitions in a row).
        let gcr = (0x17 << 15) | (0x1F << 10) | (0x17 << 5) | 0x1A;
        let (e, n) = edges_of(gcr, BIT, 0);
        assert_eq!(
            decode(&e[..n], BIT),
            Err(AnswerError::InvalidQuintet {
                index: 1,
                code: 0x1F
            })
        );
    }

    /// Extended telemetry: temperature (kind 2) of 30 degrees.
    #[test]
    fn extended_telemetry_is_recognised() {
        let value = answer_value(0x21E);
        assert_eq!(
            decode(&edges(value, 0), BIT),
            Ok(Answer::Extended { kind: 2, value: 30 })
        );
    }

    /// Each edge moved by up to just under a quarter bit either way, the ESC's clock 3 % off,
    /// rising edges late by a fifth of a bit (a slow pull-up): the same answers.
    #[test]
    fn jitter_up_to_a_quarter_bit_is_tolerated() {
        let mut rng = Rng(0x1234_5678_9abc_def0);
        for data in (0..=0xFFFu16).step_by(7) {
            let value = answer_value(data);
            let clean = decode(&edges(value, 0), BIT);
            for _ in 0..8 {
                let e: std::vec::Vec<u16> = edges(value, 30_000)
                    .iter()
                    .map(|&t| {
                        let jitter = (rng.next() % 159) as i32 - 79;
                        t.wrapping_add(jitter as u16)
                    })
                    .collect();
                assert_eq!(decode(&e, BIT), clean, "{data:#x} {e:?}");
            }
            for rate in [97, 103] {
                let e: std::vec::Vec<u16> = edges(value, 0)
                    .iter()
                    .map(|&t| (u32::from(t) * rate / 100) as u16)
                    .collect();
                assert_eq!(decode(&e, BIT), clean, "{data:#x} at {rate} %");
            }
            let late: std::vec::Vec<u16> = edges(value, 0)
                .iter()
                .enumerate()
                .map(|(i, &t)| if i % 2 == 1 { t + BIT / 5 } else { t })
                .collect();
            assert_eq!(decode(&late, BIT), clean, "{data:#x} late rising edges");
        }
    }

    #[test]
    fn malformed_edges_are_named() {
        let good = edges(0x7778, 0);
        assert_eq!(decode(&[], BIT), Err(AnswerError::NoAnswer));
        assert_eq!(decode(&good, 0), Err(AnswerError::NoBitPeriod));
        assert_eq!(
            decode(&good[..5], BIT),
            Err(AnswerError::TooFewEdges { edges: 5 })
        );
        assert_eq!(
            decode(&[0; 19], BIT),
            Err(AnswerError::TooManyEdges { edges: 19 })
        );
        assert_eq!(
            decode(&good[..11], BIT),
            Err(AnswerError::LeftLow { edges: 11 })
        );
        // A glitch: two edges a fifth of a bit apart.
        let mut glitch = good.clone();
        glitch[3] = glitch[2] + BIT / 5;
        assert_eq!(
            decode(&glitch, BIT),
            Err(AnswerError::BadInterval {
                edge: 2,
                counts: BIT / 5
            })
        );
        // A lost pair of edges makes a run of four bits or more.
        let mut lost = good.clone();
        lost.drain(1..3);
        assert!(matches!(
            decode(&lost, BIT),
            Err(AnswerError::BadInterval { edge: 0, .. })
        ));
        // Twice the bit rate: every run doubles, the answer overruns 21 bits.
        let slow: std::vec::Vec<u16> = good.iter().map(|&t| t * 2).collect();
        assert!(matches!(
            decode(&slow, BIT),
            Err(AnswerError::BadInterval { .. } | AnswerError::TooLong { .. })
        ));
        let zero: std::vec::Vec<u16> = {
            let (e, n) = edges_of(gcr_of(answer_value(0)), BIT, 0);
            e[..n].to_vec()
        };
        assert_eq!(decode(&zero, BIT), Err(AnswerError::ZeroPeriod));
    }

    #[test]
    fn every_error_says_what_is_wrong() {
        let cases = [
            (AnswerError::NoAnswer, "no edge"),
            (AnswerError::NoBitPeriod, "bit period of 0"),
            (AnswerError::TooFewEdges { edges: 4 }, "4 edges, fewer"),
            (AnswerError::TooManyEdges { edges: 30 }, "30 edges, more"),
            (AnswerError::LeftLow { edges: 11 }, "left the line low"),
            (
                AnswerError::BadInterval {
                    edge: 3,
                    counts: 1500,
                },
                "after edge 3 (1500 counts)",
            ),
            (AnswerError::TooLong { bits: 23 }, "23 bits"),
            (
                AnswerError::InvalidQuintet {
                    index: 1,
                    code: 0x1F,
                },
                "quintet 1 (0b11111) is no GCR code",
            ),
            (AnswerError::Checksum { value: 0x7779 }, "0x7779 fails"),
            (AnswerError::ZeroPeriod, "period of 0 us"),
        ];
        for (error, text) in cases {
            let shown = std::format!("{error}");
            assert!(shown.contains(text), "{shown}");
        }
    }

    /// Random edge lists and bit periods: an answer or an error, never a panic.
    #[test]
    fn no_input_panics() {
        let mut rng = Rng(0xdead_beef_cafe_f00d);
        let mut answers = 0;
        for _ in 0..200_000 {
            let n = (rng.next() % 24) as usize;
            let mut t = rng.next() as u16;
            let step = 1 + rng.next() % 1200;
            let e: std::vec::Vec<u16> = (0..n)
                .map(|_| {
                    t = t.wrapping_add((rng.next() % step) as u16);
                    t
                })
                .collect();
            let bit = match rng.next() % 4 {
                0 => 0,
                1 => u16::MAX,
                _ => BIT,
            };
            if decode(&e, bit).is_ok() {
                answers += 1;
            }
        }
        // Random edges rarely make a valid answer.
        assert!(answers < 2_000, "{answers}");
    }
}
