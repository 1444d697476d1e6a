//! The payload description as a compact binary file: what a ground station (or the HIL plant)
//! writes to the flight controller over MAVLink FTP before the mission starts
//! (docs/formats.md#payload-description-wire-format).
//!
//! It carries the sections the vehicle needs: `payload`, `robots`, `estimation`, `formation`
//! and, when present, `flight` (the target). Never the `truth`: the vehicle must find the
//! payload's COM and mass itself. The values travel unchecked, exactly as a [`ScenarioInput`];
//! the receiver decodes them with [`decode`] and checks them with the same
//! [`Scenario::from_input`] the host uses, so both refuse the same scenarios naming the same
//! key.
//!
//! Layout (little-endian; `f32` as IEEE 754 bits; a list is a `u8` count and its items):
//!
//! | field | encoding |
//! |---|---|
//! | magic | `b"RTSC"` |
//! | format version | `u8` = [`FORMAT_VERSION`] |
//! | name | `u8` length, UTF-8 bytes (at most [`MAX_NAME_LEN`]) |
//! | `payload.footprint`, `payload.rail` | list of `(f32 x, f32 y)` |
//! | `payload.candidates` | list of `f32` |
//! | `robots.count` | `u8` |
//! | `robots.mass`, `robots.max_thrust`, `robots.torque_per_thrust` | `f32` each |
//! | `robots.spin` | list of `i8` |
//! | `robots.min_spacing` | `f32` |
//! | `robots.pair_size` | `u8` |
//! | `robots.initial` | `u8` 0 (absent: even start) or 1, then a list of `f32` |
//! | `estimation.grid_min`, `grid_max`, `resolution` | 3 `f32` each |
//! | `estimation.threshold`, `noise_sigma` | `f32` each |
//! | `estimation.max_measurements` | `u32` |
//! | `formation.balance_eps` | `f32` |
//! | `flight` | `u8` 0 (absent) or 1, then `target` 3 `f32`, `disturbance_torque` `f32` |
//! | checksum | `u32` CRC-32 (ISO-HDLC, as zlib) of every byte before it |
//!
//! Decoding never panics: a short, corrupt or oversized file is an error naming the field.

use heapless::{String, Vec};

use crate::geometry::{MAX_VERTICES, PolygonError, Vec2};
use crate::mission::drives::{BoardDrives, TooManyRobots};
// The file's CRC-32 (zlib's), shared with the other files the vehicle checks.
use crate::mission::params::metadata::crc32;
use crate::scenario::{
    EstimationSetup, FlightSetup, FormationSetup, MAX_CANDIDATES, MAX_ROBOTS, Problem, RobotsInput,
    Scenario, ScenarioError, ScenarioInput,
};

/// First bytes of every encoded scenario.
pub const MAGIC: [u8; 4] = *b"RTSC";
/// Version of the layout above.
pub const FORMAT_VERSION: u8 = 1;
/// Longest scenario name carried, bytes.
pub const MAX_NAME_LEN: usize = 32;
/// Largest encoded scenario, bytes (every list at its capacity, flight present).
pub const MAX_ENCODED_LEN: usize = 4
    + 1
    + (1 + MAX_NAME_LEN)
    + 2 * (1 + 8 * MAX_VERTICES)
    + (1 + 4 * MAX_CANDIDATES)
    + 1
    + 12
    + (1 + MAX_ROBOTS)
    + 4
    + 1
    + (2 + 4 * MAX_ROBOTS)
    + 9 * 4
    + 8
    + 4
    + 4
    + (1 + 16)
    + 4;

/// Why bytes are not an encoded scenario.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WireError {
    /// The file does not start with [`MAGIC`].
    NotAScenario,
    /// Written in a layout version this build does not read.
    UnsupportedVersion(u8),
    /// The file ends inside this field.
    Truncated {
        /// The field being read.
        field: &'static str,
    },
    /// A list longer than this build holds (the key and its problem).
    Oversized(ScenarioError),
    /// A presence flag other than 0 or 1.
    BadFlag {
        /// The field whose flag it is.
        field: &'static str,
        /// The value found.
        value: u8,
    },
    /// The name is not UTF-8.
    NameNotText,
    /// The checksum does not match the contents: the file was damaged on the way.
    ChecksumMismatch {
        /// Checksum stored in the file.
        stored: u32,
        /// Checksum of the contents received.
        computed: u32,
    },
    /// Bytes after the checksum.
    TrailingBytes {
        /// How many.
        count: usize,
    },
}

impl core::fmt::Display for WireError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::NotAScenario => write!(f, "not a scenario file (bad magic bytes)"),
            Self::UnsupportedVersion(v) => write!(
                f,
                "scenario file format {v} is not supported (this build reads {FORMAT_VERSION})"
            ),
            Self::Truncated { field } => write!(f, "scenario file ends inside {field}"),
            Self::Oversized(e) => write!(f, "{e}"),
            Self::BadFlag { field, value } => {
                write!(f, "{field}: presence flag is {value}, must be 0 or 1")
            }
            Self::NameNotText => write!(f, "name: not UTF-8 text"),
            Self::ChecksumMismatch { stored, computed } => write!(
                f,
                "scenario file damaged: checksum {computed:#010x} does not match the stored {stored:#010x}"
            ),
            Self::TrailingBytes { count } => {
                write!(f, "scenario file has {count} bytes after its checksum")
            }
        }
    }
}

impl core::error::Error for WireError {}

/// Why a scenario could not be encoded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EncodeError {
    /// The output buffer is too small (at most [`MAX_ENCODED_LEN`] is needed).
    BufferTooSmall,
    /// A list or count does not fit the layout's one-byte count (the key and its problem).
    TooLong(ScenarioError),
}

impl core::fmt::Display for EncodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BufferTooSmall => write!(f, "output buffer too small for the scenario"),
            Self::TooLong(e) => write!(f, "{e}"),
        }
    }
}

impl core::error::Error for EncodeError {}

/// Why a received payload description was refused: damaged in transit, a value that breaks
/// a rule of [`Scenario::from_input`], or more robots than the board drives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PayloadError {
    /// Not a well-formed file.
    Wire(WireError),
    /// Well-formed, but a value breaks a rule (names the key).
    Invalid(ScenarioError),
    /// Valid, but the board does not drive all its robots.
    Board(TooManyRobots),
}

impl core::fmt::Display for PayloadError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Wire(e) => write!(f, "{e}"),
            Self::Invalid(e) => write!(f, "{e}"),
            Self::Board(e) => write!(f, "{e}"),
        }
    }
}

impl core::error::Error for PayloadError {}

/// A decoded scenario: owned copies of the values, unchecked.
#[derive(Clone, Debug, PartialEq)]
pub struct WireScenario {
    /// The scenario's `name`.
    pub name: String<MAX_NAME_LEN>,
    /// `payload.footprint`.
    pub footprint: Vec<Vec2, MAX_VERTICES>,
    /// `payload.rail`.
    pub rail: Vec<Vec2, MAX_VERTICES>,
    /// `payload.candidates`.
    pub candidates: Vec<f32, MAX_CANDIDATES>,
    /// `robots.count`.
    pub robot_count: u8,
    /// `robots.mass`.
    pub robot_mass: f32,
    /// `robots.max_thrust`.
    pub max_thrust: f32,
    /// `robots.torque_per_thrust`.
    pub torque_per_thrust: f32,
    /// `robots.spin`, widened to the input's type.
    pub spin: Vec<i64, MAX_ROBOTS>,
    /// `robots.min_spacing`.
    pub min_spacing: f32,
    /// `robots.pair_size`.
    pub pair_size: u8,
    /// `robots.initial`, if given.
    pub initial: Option<Vec<f32, MAX_ROBOTS>>,
    /// `estimation.*`.
    pub estimation: EstimationSetup,
    /// `formation.*`.
    pub formation: FormationSetup,
    /// `flight.*`, if given.
    pub flight: Option<FlightSetup>,
}

impl WireScenario {
    /// The values as [`Scenario::from_input`] takes them (no truth: the vehicle never has it).
    pub fn input(&self) -> ScenarioInput<'_> {
        ScenarioInput {
            footprint: &self.footprint,
            rail: &self.rail,
            candidates: &self.candidates,
            robots: RobotsInput {
                count: usize::from(self.robot_count),
                mass: self.robot_mass,
                max_thrust: self.max_thrust,
                torque_per_thrust: self.torque_per_thrust,
                spin: &self.spin,
                min_spacing: self.min_spacing,
                pair_size: usize::from(self.pair_size),
                initial: self.initial.as_deref(),
            },
            estimation: self.estimation,
            formation: self.formation,
            truth: None,
            flight: self.flight,
        }
    }

    /// Checks the values with the host's rules.
    pub fn check(&self) -> Result<Scenario, ScenarioError> {
        Scenario::from_input(&self.input())
    }
}

/// Decodes `bytes` and checks the scenario: whether a stored file is still a description.
pub fn decode_and_check(bytes: &[u8]) -> Result<(WireScenario, Scenario), PayloadError> {
    let wire = decode(bytes).map_err(PayloadError::Wire)?;
    let scenario = wire.check().map_err(PayloadError::Invalid)?;
    Ok((wire, scenario))
}

/// [`decode_and_check`], and the board `drives` all its robots with ESC protocol
/// `esc_protocol`: what the vehicle does with a received file before it takes it.
pub fn decode_for_board(
    bytes: &[u8],
    drives: &BoardDrives,
    esc_protocol: u8,
) -> Result<(WireScenario, Scenario), PayloadError> {
    let (wire, scenario) = decode_and_check(bytes)?;
    drives
        .check(scenario.robots.count(), esc_protocol)
        .map_err(PayloadError::Board)?;
    Ok((wire, scenario))
}

struct Writer<'a> {
    out: &'a mut [u8],
    len: usize,
}

impl Writer<'_> {
    fn bytes(&mut self, b: &[u8]) -> Result<(), EncodeError> {
        let end = self.len + b.len();
        let slot = self
            .out
            .get_mut(self.len..end)
            .ok_or(EncodeError::BufferTooSmall)?;
        slot.copy_from_slice(b);
        self.len = end;
        Ok(())
    }

    fn u8(&mut self, v: u8) -> Result<(), EncodeError> {
        self.bytes(&[v])
    }

    fn f32(&mut self, v: f32) -> Result<(), EncodeError> {
        self.bytes(&v.to_le_bytes())
    }

    fn f32s(&mut self, v: &[f32]) -> Result<(), EncodeError> {
        v.iter().try_for_each(|&x| self.f32(x))
    }

    fn count(&mut self, key: &'static str, n: usize, max: usize) -> Result<(), EncodeError> {
        let byte = u8::try_from(n).ok().filter(|_| n <= max).ok_or({
            EncodeError::TooLong(ScenarioError {
                key,
                problem: Problem::TooMany { found: n, max },
            })
        })?;
        self.u8(byte)
    }

    fn points(&mut self, key: &'static str, points: &[Vec2]) -> Result<(), EncodeError> {
        self.count(key, points.len(), MAX_VERTICES)?;
        points.iter().try_for_each(|p| {
            self.f32(p.x)?;
            self.f32(p.y)
        })
    }
}

/// Encodes `input` (its `truth` is left out) with `name` (cut to [`MAX_NAME_LEN`] bytes at a
/// character boundary) into `out`; returns the length written.
pub fn encode(name: &str, input: &ScenarioInput<'_>, out: &mut [u8]) -> Result<usize, EncodeError> {
    let mut w = Writer { out, len: 0 };
    w.bytes(&MAGIC)?;
    w.u8(FORMAT_VERSION)?;
    let mut cut = name.len().min(MAX_NAME_LEN);
    while !name.is_char_boundary(cut) {
        cut -= 1;
    }
    w.count("name", cut, MAX_NAME_LEN)?;
    w.bytes(&name.as_bytes()[..cut])?;
    w.points("payload.footprint", input.footprint)?;
    w.points("payload.rail", input.rail)?;
    w.count("payload.candidates", input.candidates.len(), MAX_CANDIDATES)?;
    w.f32s(input.candidates)?;
    let r = &input.robots;
    w.count("robots.count", r.count, MAX_ROBOTS)?;
    w.f32(r.mass)?;
    w.f32(r.max_thrust)?;
    w.f32(r.torque_per_thrust)?;
    w.count("robots.spin", r.spin.len(), MAX_ROBOTS)?;
    for &s in r.spin {
        // A spin outside i8 is refused by the checks anyway; keep it refusable (not 1 or -1).
        let byte = i8::try_from(s).unwrap_or(0);
        w.u8(byte.to_le_bytes()[0])?;
    }
    w.f32(r.min_spacing)?;
    w.count("robots.pair_size", r.pair_size, usize::from(u8::MAX))?;
    match r.initial {
        None => w.u8(0)?,
        Some(initial) => {
            w.u8(1)?;
            w.count("robots.initial", initial.len(), MAX_ROBOTS)?;
            w.f32s(initial)?;
        }
    }
    let e = &input.estimation;
    w.f32s(&e.grid_min)?;
    w.f32s(&e.grid_max)?;
    w.f32s(&e.resolution)?;
    w.f32(e.threshold)?;
    w.f32(e.noise_sigma)?;
    w.bytes(&e.max_measurements.to_le_bytes())?;
    w.f32(input.formation.balance_eps)?;
    match input.flight {
        None => w.u8(0)?,
        Some(flight) => {
            w.u8(1)?;
            w.f32s(&flight.target)?;
            w.f32(flight.disturbance_torque)?;
        }
    }
    let crc = crc32(&w.out[..w.len]);
    w.bytes(&crc.to_le_bytes())?;
    Ok(w.len)
}

/// Encodes a checked scenario (the host's, after reading its file) into `out`.
pub fn encode_scenario(
    name: &str,
    scenario: &Scenario,
    out: &mut [u8],
) -> Result<usize, EncodeError> {
    let spin: Vec<i64, MAX_ROBOTS> = scenario.robots.spin.iter().map(|&s| i64::from(s)).collect();
    let input = ScenarioInput {
        footprint: &scenario.payload.footprint,
        rail: scenario.payload.rail.vertices(),
        candidates: &scenario.payload.candidates,
        robots: RobotsInput {
            count: scenario.robots.count(),
            mass: scenario.robots.mass,
            max_thrust: scenario.robots.max_thrust,
            torque_per_thrust: scenario.robots.torque_per_thrust,
            spin: &spin,
            min_spacing: scenario.robots.min_spacing,
            pair_size: scenario.robots.pair_size,
            initial: Some(&scenario.robots.initial),
        },
        estimation: scenario.estimation,
        formation: scenario.formation,
        truth: None,
        flight: scenario.flight,
    };
    encode(name, &input, out)
}

struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, field: &'static str, n: usize) -> Result<&'a [u8], WireError> {
        let end = self
            .pos
            .checked_add(n)
            .ok_or(WireError::Truncated { field })?;
        let slice = self
            .bytes
            .get(self.pos..end)
            .ok_or(WireError::Truncated { field })?;
        self.pos = end;
        Ok(slice)
    }

    fn u8(&mut self, field: &'static str) -> Result<u8, WireError> {
        Ok(self.take(field, 1)?[0])
    }

    fn array<const N: usize>(&mut self, field: &'static str) -> Result<[u8; N], WireError> {
        let mut a = [0; N];
        a.copy_from_slice(self.take(field, N)?);
        Ok(a)
    }

    fn f32(&mut self, field: &'static str) -> Result<f32, WireError> {
        Ok(f32::from_le_bytes(self.array(field)?))
    }

    fn f32x3(&mut self, field: &'static str) -> Result<[f32; 3], WireError> {
        Ok([self.f32(field)?, self.f32(field)?, self.f32(field)?])
    }

    fn flag(&mut self, field: &'static str) -> Result<bool, WireError> {
        match self.u8(field)? {
            0 => Ok(false),
            1 => Ok(true),
            value => Err(WireError::BadFlag { field, value }),
        }
    }

    /// A list count, refused over `max` with the same problem the checks would name.
    fn count(&mut self, field: &'static str, max: usize) -> Result<usize, WireError> {
        let n = usize::from(self.u8(field)?);
        if n > max {
            let problem = if max == MAX_VERTICES {
                Problem::Polygon(PolygonError::TooManyVertices)
            } else {
                Problem::TooMany { found: n, max }
            };
            return Err(WireError::Oversized(ScenarioError {
                key: field,
                problem,
            }));
        }
        Ok(n)
    }

    fn points(&mut self, field: &'static str) -> Result<Vec<Vec2, MAX_VERTICES>, WireError> {
        let n = self.count(field, MAX_VERTICES)?;
        let mut out = Vec::new();
        for _ in 0..n {
            let p = Vec2::new(self.f32(field)?, self.f32(field)?);
            // n <= MAX_VERTICES was checked.
            let _ = out.push(p);
        }
        Ok(out)
    }

    fn f32_list<const N: usize>(&mut self, field: &'static str) -> Result<Vec<f32, N>, WireError> {
        let n = self.count(field, N)?;
        let mut out = Vec::new();
        for _ in 0..n {
            let v = self.f32(field)?;
            let _ = out.push(v);
        }
        Ok(out)
    }
}

/// Decodes an encoded scenario. The values are not checked yet: call
/// [`WireScenario::check`] (or use [`decode_and_check`]).
pub fn decode(bytes: &[u8]) -> Result<WireScenario, WireError> {
    let mut r = Reader { bytes, pos: 0 };
    if r.take("magic", 4).ok() != Some(&MAGIC[..]) {
        return Err(WireError::NotAScenario);
    }
    let version = r.u8("format version")?;
    if version != FORMAT_VERSION {
        return Err(WireError::UnsupportedVersion(version));
    }
    // Check the whole file before trusting any count in it.
    if bytes.len() < r.pos + 4 {
        return Err(WireError::Truncated { field: "checksum" });
    }
    let body_len = bytes.len() - 4;
    let mut stored = [0; 4];
    stored.copy_from_slice(&bytes[body_len..]);
    let stored = u32::from_le_bytes(stored);
    let computed = crc32(&bytes[..body_len]);
    if stored != computed {
        return Err(WireError::ChecksumMismatch { stored, computed });
    }
    let mut r = Reader {
        bytes: &bytes[..body_len],
        pos: r.pos,
    };

    let name_len = r.count("name", MAX_NAME_LEN)?;
    let name_bytes = r.take("name", name_len)?;
    let name_text = core::str::from_utf8(name_bytes).map_err(|_| WireError::NameNotText)?;
    let mut name = String::new();
    // name_len <= MAX_NAME_LEN was checked.
    let _ = name.push_str(name_text);

    let footprint = r.points("payload.footprint")?;
    let rail = r.points("payload.rail")?;
    let candidates = r.f32_list::<MAX_CANDIDATES>("payload.candidates")?;
    let robot_count = r.u8("robots.count")?;
    let robot_mass = r.f32("robots.mass")?;
    let max_thrust = r.f32("robots.max_thrust")?;
    let torque_per_thrust = r.f32("robots.torque_per_thrust")?;
    let spin_count = r.count("robots.spin", MAX_ROBOTS)?;
    let mut spin = Vec::new();
    for _ in 0..spin_count {
        let s = i8::from_le_bytes([r.u8("robots.spin")?]);
        let _ = spin.push(i64::from(s));
    }
    let min_spacing = r.f32("robots.min_spacing")?;
    let pair_size = r.u8("robots.pair_size")?;
    let initial = if r.flag("robots.initial")? {
        Some(r.f32_list::<MAX_ROBOTS>("robots.initial")?)
    } else {
        None
    };
    let estimation = EstimationSetup {
        grid_min: r.f32x3("estimation.grid_min")?,
        grid_max: r.f32x3("estimation.grid_max")?,
        resolution: r.f32x3("estimation.resolution")?,
        threshold: r.f32("estimation.threshold")?,
        noise_sigma: r.f32("estimation.noise_sigma")?,
        max_measurements: u32::from_le_bytes(r.array("estimation.max_measurements")?),
    };
    let formation = FormationSetup {
        balance_eps: r.f32("formation.balance_eps")?,
    };
    let flight = if r.flag("flight")? {
        Some(FlightSetup {
            target: r.f32x3("flight.target")?,
            disturbance_torque: r.f32("flight.disturbance_torque")?,
        })
    } else {
        None
    };
    let rest = body_len - r.pos;
    if rest != 0 {
        return Err(WireError::TrailingBytes { count: rest });
    }
    Ok(WireScenario {
        name,
        footprint,
        rail,
        candidates,
        robot_count,
        robot_mass,
        max_thrust,
        torque_per_thrust,
        spin,
        min_spacing,
        pair_size,
        initial,
        estimation,
        formation,
        flight,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper::{l_sim1, rect_sim1};

    fn encoded(name: &str, input: &ScenarioInput<'_>) -> ([u8; MAX_ENCODED_LEN], usize) {
        let mut buf = [0u8; MAX_ENCODED_LEN];
        let n = encode(name, input, &mut buf).expect("fits");
        (buf, n)
    }

    #[test]
    fn round_trip_gives_the_same_checked_scenario_without_the_truth() {
        for (name, input) in [("rect-sim1", rect_sim1()), ("L-sim1", l_sim1())] {
            let (buf, n) = encoded(name, &input);
            let (wire, scenario) = decode_and_check(&buf[..n]).expect("valid");
            assert_eq!(wire.name.as_str(), name);
            let mut expected = Scenario::from_input(&input).expect("valid");
            expected.truth = None;
            assert_eq!(scenario, expected);
        }
    }

    #[test]
    fn encoding_a_checked_scenario_round_trips_with_its_flight_target() {
        let mut input = rect_sim1();
        input.flight = Some(FlightSetup {
            target: [0.3, 1.98, 0.5],
            disturbance_torque: 0.3,
        });
        let checked = Scenario::from_input(&input).expect("valid");
        let mut buf = [0u8; MAX_ENCODED_LEN];
        let n = encode_scenario("rect-ex1", &checked, &mut buf).expect("fits");
        let (_, back) = decode_and_check(&buf[..n]).expect("valid");
        assert_eq!(back.flight, checked.flight);
        assert_eq!(back.robots, checked.robots);
        assert_eq!(back.payload, checked.payload);
        assert_eq!(back.truth, None);
    }

    #[test]
    fn a_bad_value_survives_the_wire_and_is_refused_naming_its_key() {
        let mut bad = rect_sim1();
        bad.estimation.resolution[1] = 0.0;
        let (buf, n) = encoded("bad", &bad);
        match decode_and_check(&buf[..n]) {
            Err(PayloadError::Invalid(e)) => assert_eq!(e.key, "estimation.resolution"),
            other => panic!("expected a refusal naming the key, got {other:?}"),
        }
    }

    #[test]
    fn a_description_with_more_robots_than_the_board_drives_is_refused_saying_both() {
        let (buf, n) = encoded("rect-sim1", &rect_sim1());
        let board = crate::mission::drives::PIXHAWK_6C;
        assert!(
            decode_for_board(&buf[..n], &board, 0).is_ok(),
            "8 robots on 8 outputs"
        );
        let six = board.at_most(6);
        match decode_for_board(&buf[..n], &six, 1) {
            Err(PayloadError::Board(e)) => {
                assert_eq!(
                    (e.robots, e.rotors, e.steppers, e.esc_protocol),
                    (8, 6, 6, 1)
                );
            }
            other => panic!("expected the board's refusal, got {other:?}"),
        }
    }

    #[test]
    fn every_truncation_is_an_error_not_a_panic() {
        let (buf, n) = encoded("rect-sim1", &rect_sim1());
        for len in 0..n {
            assert!(decode(&buf[..len]).is_err(), "length {len} accepted");
        }
    }

    #[test]
    fn every_single_bit_flip_is_detected() {
        let (buf, n) = encoded("rect-sim1", &rect_sim1());
        for byte in 0..n {
            for bit in 0..8 {
                let mut damaged = buf;
                damaged[byte] ^= 1 << bit;
                assert!(
                    decode(&damaged[..n]).is_err(),
                    "flip of bit {bit} in byte {byte} accepted"
                );
            }
        }
    }

    #[test]
    fn oversized_counts_name_their_key() {
        // Rebuild a file whose candidate count exceeds the capacity, with a valid checksum.
        let (buf, n) = encoded("x", &rect_sim1());
        let mut file = [0u8; MAX_ENCODED_LEN];
        file[..n].copy_from_slice(&buf[..n]);
        // magic 4, version 1, name 1 + 1, footprint 1 + 32, rail 1 + 32: candidates count next.
        let at = 4 + 1 + 2 + 33 + 33;
        assert_eq!(file[at], 12);
        file[at] = 200;
        let crc = crc32(&file[..n - 4]);
        file[n - 4..n].copy_from_slice(&crc.to_le_bytes());
        match decode(&file[..n]) {
            Err(WireError::Oversized(e)) => {
                assert_eq!(e.key, "payload.candidates");
                assert_eq!(
                    e.problem,
                    Problem::TooMany {
                        found: 200,
                        max: MAX_CANDIDATES
                    }
                );
            }
            other => panic!("expected an oversized count, got {other:?}"),
        }
    }

    #[test]
    fn wrong_magic_version_and_trailing_bytes_are_named() {
        let (buf, n) = encoded("x", &rect_sim1());
        let mut other = buf;
        other[0] = b'X';
        assert_eq!(decode(&other[..n]), Err(WireError::NotAScenario));
        let mut other = buf;
        other[4] = 9;
        assert_eq!(decode(&other[..n]), Err(WireError::UnsupportedVersion(9)));
        // One extra byte before a recomputed checksum.
        let mut longer = [0u8; MAX_ENCODED_LEN + 1];
        longer[..n - 4].copy_from_slice(&buf[..n - 4]);
        let crc = crc32(&longer[..n - 3]);
        longer[n - 3..n + 1].copy_from_slice(&crc.to_le_bytes());
        assert_eq!(
            decode(&longer[..n + 1]),
            Err(WireError::TrailingBytes { count: 1 })
        );
    }

    #[test]
    fn too_small_a_buffer_and_too_many_robots_are_encode_errors() {
        let mut small = [0u8; 16];
        assert_eq!(
            encode("x", &rect_sim1(), &mut small),
            Err(EncodeError::BufferTooSmall)
        );
        let spins = [1i64; 20];
        let mut many = rect_sim1();
        many.robots.spin = &spins;
        let mut buf = [0u8; MAX_ENCODED_LEN];
        match encode("x", &many, &mut buf) {
            Err(EncodeError::TooLong(e)) => assert_eq!(e.key, "robots.spin"),
            other => panic!("expected too long, got {other:?}"),
        }
    }

    #[test]
    fn names_are_cut_at_a_character_boundary() {
        let long = "é".repeat(40);
        let (buf, n) = encoded(&long, &rect_sim1());
        let wire = decode(&buf[..n]).expect("valid");
        assert_eq!(wire.name.len(), MAX_NAME_LEN);
        assert!(wire.name.chars().all(|c| c == 'é'));
    }
}

#[cfg(test)]
mod fuzz {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..1200)) {
            let _ = decode_and_check(&bytes);
        }

        #[test]
        fn arbitrary_bytes_behind_a_valid_header_never_panic(
            body in proptest::collection::vec(any::<u8>(), 0..1000)
        ) {
            // A valid checksum over random contents reaches every field reader.
            let mut file = std::vec::Vec::from(&b"RTSC\x01"[..]);
            file.extend_from_slice(&body);
            let crc = crc32(&file);
            file.extend_from_slice(&crc.to_le_bytes());
            let _ = decode_and_check(&file);
        }
    }
}
