//! The thrust map from a motor bench sweep: readings of a load cell at ESC commands become the
//! firmware's parameters `THR_MAP_20` .. `THR_MAP_80`, the thrust at 20, 40, 60 and 80 %
//! command as a fraction of full thrust (`drivers::thrust_map`;
//! docs/commands.md#calibrating-the-thrust-map says how to take the sweep and what each check
//! is for).
//!
//! The method, in order:
//! 1. Readings at command 0 (motor stopped) are the load cell's zero: their mean, the tare, is
//!    taken off every reading. Without any, the readings are taken as tared already.
//! 2. Checks that the sweep determines the map: a reading in each fifth of the command range,
//!    (0, 0.2] to (0.8, 1], and a largest command of at least [`MIN_TOP_COMMAND`]; thrust must
//!    rise with the command, judged on the mean of each command's readings, a fall of up to
//!    [`NOISE_FALL`] of the largest mean being bench noise.
//! 3. Least squares over every reading (several at one command count several times) of the
//!    piecewise-linear map with knots at commands 0, 0.2, .., 1: the thrusts `T1` .. `T5` (N)
//!    at the knots, `T0 = 0` fixed. Full thrust is `T5`, extrapolated along the last interval
//!    when the sweep stops short of command 1.
//! 4. The parameters are `Tk / T5`, rounded to [`DECIMALS`] places; they must make a valid
//!    `ThrustMap` (rising, inside (0, 1)) and lie in the parameters' ranges.
//!
//! Everything reported after that (fitted thrusts, the error) is of the rounded map, the one
//! the vehicle will run.

use std::fmt;

use drivers::thrust_map::{ThrustMap, ThrustMapError};
use nalgebra::{DMatrix, DVector};

/// Commands of the map's knots, fractions of full command.
pub const KNOTS: [f64; 6] = [0.0, 0.2, 0.4, 0.6, 0.8, 1.0];
/// The parameters, thrust fractions at the interior knots.
pub const PARAMS: [&str; 4] = ["THR_MAP_20", "THR_MAP_40", "THR_MAP_60", "THR_MAP_80"];
/// The smallest top command of a sweep: full thrust is extrapolated over at most half of the
/// last interval.
pub const MIN_TOP_COMMAND: f64 = 0.9;
/// The largest fall of a command's mean thrust below a lower command's, as a fraction of the
/// largest mean, taken as bench noise rather than thrust falling (a load cell's noise, the
/// readings of a dead band at low command).
pub const NOISE_FALL: f64 = 0.01;
/// Decimal places of the parameters (a ten-thousandth of full thrust).
pub const DECIMALS: i32 = 4;

/// One bench reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reading {
    /// The file's line it came from (for messages).
    pub line: usize,
    /// ESC command, fraction of full command (0 to 1).
    pub command: f64,
    /// The load cell's thrust, N, as read (before the tare).
    pub thrust_n: f64,
}

/// One command of the sweep, its readings against the calibrated map.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// ESC command, fraction of full command.
    pub command: f64,
    /// Lines of its readings, in file order.
    pub lines: Vec<usize>,
    /// Mean of its readings less the tare, N.
    pub measured_n: f64,
    /// The calibrated map's thrust there, N.
    pub fitted_n: f64,
}

/// A calibrated thrust map.
#[derive(Clone, Debug, PartialEq)]
pub struct ThrustCalibration {
    /// Readings used (all of them).
    pub readings: usize,
    /// Mean reading at command 0, taken off every reading, N (0 without such readings).
    pub tare_n: f64,
    /// Thrust at command 1, N: the map's unit, `T5`.
    pub full_thrust_n: f64,
    /// The largest command of the sweep (below 1: full thrust is extrapolated).
    pub top_command: f64,
    /// Values of [`PARAMS`], rounded to [`DECIMALS`] places.
    pub params: [f64; 4],
    /// The firmware's map made of them.
    pub map: ThrustMap,
    /// Each command of the sweep, rising.
    pub points: Vec<Point>,
    /// Largest `|fitted_n - measured_n|` over the points (each command's mean), divided by
    /// `full_thrust_n`.
    pub max_error_fraction: f64,
    /// The command where it is largest.
    pub max_error_command: f64,
}

/// Why a sweep gives no map. Lines are the file's, as in [`Reading::line`].
#[derive(Clone, Debug, PartialEq)]
pub enum CalibrationError {
    /// No readings at all.
    NoReadings,
    /// A command outside 0..1 or not a number.
    CommandOutOfRange {
        /// Its line.
        line: usize,
        /// The command.
        command: f64,
    },
    /// A thrust that is not a finite number.
    ThrustNotFinite {
        /// Its line.
        line: usize,
    },
    /// No reading with a command in `(low, high]`.
    MissingInterval {
        /// The interval's open end.
        low: f64,
        /// The interval's closed end.
        high: f64,
    },
    /// The largest command is below [`MIN_TOP_COMMAND`].
    ShortSweep {
        /// The largest command.
        top: f64,
        /// Its readings' lines.
        lines: Vec<usize>,
    },
    /// At the largest command the thrust is not above the tare.
    NoRise {
        /// The largest command.
        top: f64,
        /// Its readings' lines.
        lines: Vec<usize>,
        /// Their mean less the tare, N.
        mean_n: f64,
    },
    /// A command's mean thrust is below a lower command's by more than bench noise.
    Falls {
        /// The command where it falls.
        command: f64,
        /// Its readings' lines.
        lines: Vec<usize>,
        /// Their mean, N (tared).
        mean_n: f64,
        /// The lower command with the higher mean.
        above_command: f64,
        /// Its readings' lines.
        above_lines: Vec<usize>,
        /// Its mean, N (tared).
        above_mean_n: f64,
        /// The fall taken as noise, N.
        tolerance_n: f64,
    },
    /// The readings do not determine the knots (they crowd the knots' left ends).
    Undetermined,
    /// The fitted map is not one the firmware takes.
    BadMap(String),
}

impl std::error::Error for CalibrationError {}

impl fmt::Display for CalibrationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NoReadings => write!(f, "no readings below the header"),
            Self::CommandOutOfRange { line, command } => write!(
                f,
                "line {line}: command {command} is outside 0..1 (commands are fractions of full \
                 command, not percent)"
            ),
            Self::ThrustNotFinite { line } => {
                write!(f, "line {line}: thrust_n is not a finite number")
            }
            Self::MissingInterval { low, high } => write!(
                f,
                "no reading with a command in ({low}, {high}]: the fit needs one in each fifth of \
                 the range, (0, 0.2] to (0.8, 1], to set the map at {} % command",
                (high * 100.0).round()
            ),
            Self::ShortSweep { top, lines } => write!(
                f,
                "{}: the sweep stops at command {top}, below {MIN_TOP_COMMAND}: full thrust (at \
                 command 1) would be extrapolated too far; sweep up to command 1",
                lines_of(lines)
            ),
            Self::NoRise { top, lines, mean_n } => write!(
                f,
                "{}: at the top command {top} the thrust averages {mean_n:.3} N above the tare, \
                 not more: thrust must rise with the command (a load cell mounted the other way \
                 reads negative: flip the sign)",
                lines_of(lines)
            ),
            Self::Falls {
                command,
                lines,
                mean_n,
                above_command,
                above_lines,
                above_mean_n,
                tolerance_n,
            } => write!(
                f,
                "{}: thrust falls as the command rises: at command {command} the readings average \
                 {mean_n:.3} N, {:.3} N below the {above_mean_n:.3} N at command {above_command} \
                 ({}); bench noise may lower it by {tolerance_n:.3} N at most ({} % of the \
                 largest mean)",
                lines_of(lines),
                above_mean_n - mean_n,
                lines_of(above_lines),
                NOISE_FALL * 100.0
            ),
            Self::Undetermined => write!(
                f,
                "the readings do not determine the map: they crowd the left ends of the \
                 intervals (0, 0.2] to (0.8, 1]; take readings across each"
            ),
            Self::BadMap(why) => write!(f, "{why}"),
        }
    }
}

/// `line 7`, `lines 7 and 9`, `lines 7, 9 and 12`, `lines 7, 9, 12 and 5 more`.
fn lines_of(lines: &[usize]) -> String {
    let shown: Vec<String> = lines.iter().take(3).map(usize::to_string).collect();
    match (lines.len(), &shown[..]) {
        (0, _) => "no line".to_string(),
        (1, [one]) => format!("line {one}"),
        (2 | 3, [head @ .., last]) => format!("lines {} and {last}", head.join(", ")),
        (n, _) => format!("lines {} and {} more", shown.join(", "), n - 3),
    }
}

/// One command's readings.
struct Group {
    command: f64,
    lines: Vec<usize>,
    mean_n: f64,
}

/// Calibrates the thrust map from `readings` (any order), or says why it cannot.
pub fn calibrate(readings: &[Reading]) -> Result<ThrustCalibration, CalibrationError> {
    if readings.is_empty() {
        return Err(CalibrationError::NoReadings);
    }
    for r in readings {
        if !(0.0..=1.0).contains(&r.command) {
            return Err(CalibrationError::CommandOutOfRange {
                line: r.line,
                command: r.command,
            });
        }
        if !r.thrust_n.is_finite() {
            return Err(CalibrationError::ThrustNotFinite { line: r.line });
        }
    }
    let groups = groups(readings);
    let tare_n = groups
        .first()
        .filter(|g| g.command == 0.0)
        .map_or(0.0, |g| g.mean_n);
    covered(&groups)?;
    let Some(top) = groups.last() else {
        return Err(CalibrationError::NoReadings);
    };
    if top.command < MIN_TOP_COMMAND {
        return Err(CalibrationError::ShortSweep {
            top: top.command,
            lines: top.lines.clone(),
        });
    }
    if top.mean_n - tare_n <= 0.0 {
        return Err(CalibrationError::NoRise {
            top: top.command,
            lines: top.lines.clone(),
            mean_n: top.mean_n - tare_n,
        });
    }
    rising(&groups, tare_n)?;
    let knots_n = fit(readings, tare_n)?;
    let full_thrust_n = knots_n[5];
    if !(full_thrust_n.is_finite() && full_thrust_n > 0.0) {
        return Err(CalibrationError::BadMap(format!(
            "the fitted full thrust is {full_thrust_n:.3} N, not above zero"
        )));
    }
    let scale = 10f64.powi(DECIMALS);
    let params = [1, 2, 3, 4].map(|k| (knots_n[k] / full_thrust_n * scale).round() / scale);
    let map = firmware_map(params)?;
    let calibrated =
        [0.0, params[0], params[1], params[2], params[3], 1.0].map(|p| p * full_thrust_n);
    let points: Vec<Point> = groups
        .into_iter()
        .map(|g| Point {
            command: g.command,
            measured_n: g.mean_n - tare_n,
            fitted_n: piecewise(&calibrated, g.command),
            lines: g.lines,
        })
        .collect();
    let (max_error_fraction, max_error_command) = points
        .iter()
        .map(|p| ((p.fitted_n - p.measured_n).abs() / full_thrust_n, p.command))
        .fold((0.0, 0.0), |worst, e| if e.0 > worst.0 { e } else { worst });
    Ok(ThrustCalibration {
        readings: readings.len(),
        tare_n,
        full_thrust_n,
        top_command: points.last().map_or(0.0, |p| p.command),
        params,
        map,
        points,
        max_error_fraction,
        max_error_command,
    })
}

/// The readings grouped by command, rising; each group's lines in file order.
fn groups(readings: &[Reading]) -> Vec<Group> {
    let mut sorted = readings.to_vec();
    sorted.sort_by(|a, b| a.command.total_cmp(&b.command).then(a.line.cmp(&b.line)));
    let mut out: Vec<Group> = Vec::new();
    let mut sum = 0.0;
    for r in &sorted {
        match out.last_mut() {
            Some(g) if g.command == r.command => {
                g.lines.push(r.line);
                sum += r.thrust_n;
                g.mean_n = sum / g.lines.len() as f64;
            }
            _ => {
                sum = r.thrust_n;
                out.push(Group {
                    command: r.command,
                    lines: vec![r.line],
                    mean_n: r.thrust_n,
                });
            }
        }
    }
    out
}

/// Checks that each interval `(KNOTS[k-1], KNOTS[k]]` holds a command.
fn covered(groups: &[Group]) -> Result<(), CalibrationError> {
    for pair in KNOTS.windows(2) {
        let (low, high) = (pair[0], pair[1]);
        if !groups.iter().any(|g| g.command > low && g.command <= high) {
            return Err(CalibrationError::MissingInterval { low, high });
        }
    }
    Ok(())
}

/// Checks that no command's mean falls below a lower command's by more than bench noise.
fn rising(groups: &[Group], tare_n: f64) -> Result<(), CalibrationError> {
    let largest = groups.iter().map(|g| g.mean_n - tare_n).fold(0.0, f64::max);
    let tolerance_n = NOISE_FALL * largest;
    let mut highest: Option<&Group> = None;
    for g in groups {
        match highest {
            Some(h) if g.mean_n < h.mean_n - tolerance_n => {
                return Err(CalibrationError::Falls {
                    command: g.command,
                    lines: g.lines.clone(),
                    mean_n: g.mean_n - tare_n,
                    above_command: h.command,
                    above_lines: h.lines.clone(),
                    above_mean_n: h.mean_n - tare_n,
                    tolerance_n,
                });
            }
            Some(h) if g.mean_n <= h.mean_n => {}
            _ => highest = Some(g),
        }
    }
    Ok(())
}

/// The interval of command `command` (above 0, at most 1) and how far along it lies: `(j, t)`
/// with `KNOTS[j] < command <= KNOTS[j + 1]`, `t` in (0, 1].
fn locate(command: f64) -> (usize, f64) {
    let j = (0..5).find(|&j| command <= KNOTS[j + 1]).unwrap_or(4);
    (j, (command - KNOTS[j]) / (KNOTS[j + 1] - KNOTS[j]))
}

/// The piecewise-linear map with thrusts `knots` at [`KNOTS`], at `command` (0 to 1).
pub fn piecewise(knots: &[f64; 6], command: f64) -> f64 {
    if command <= 0.0 {
        return knots[0];
    }
    let (j, t) = locate(command.min(1.0));
    knots[j] + t * (knots[j + 1] - knots[j])
}

/// Least squares of the knots' thrusts over the readings, `T0 = 0`: `[T0, .., T5]`, N.
fn fit(readings: &[Reading], tare_n: f64) -> Result<[f64; 6], CalibrationError> {
    // Readings at command 0 depend on no unknown (T0 is fixed): they only set the tare.
    let used: Vec<&Reading> = readings.iter().filter(|r| r.command > 0.0).collect();
    let mut a = DMatrix::<f64>::zeros(used.len(), 5);
    let mut b = DVector::<f64>::zeros(used.len());
    for (row, r) in used.iter().enumerate() {
        // Unknown `Tk` is column k - 1.
        let (j, t) = locate(r.command);
        if j > 0 {
            a[(row, j - 1)] = 1.0 - t;
        }
        a[(row, j)] = t;
        b[row] = r.thrust_n - tare_n;
    }
    let svd = a.svd(true, true);
    let sv = &svd.singular_values;
    // False for a NaN too.
    let determined = sv.len() == 5 && sv.min() > 1e-9 * sv.max();
    if !determined {
        return Err(CalibrationError::Undetermined);
    }
    let x = svd
        .solve(&b, 0.0)
        .map_err(|_| CalibrationError::Undetermined)?;
    Ok([0.0, x[0], x[1], x[2], x[3], x[4]])
}

/// The firmware's map of `params`, each also inside its parameter's range.
fn firmware_map(params: [f64; 4]) -> Result<ThrustMap, CalibrationError> {
    use shared::mission::params::{TABLE, check, find};
    for (k, (name, &value)) in PARAMS.iter().zip(&params).enumerate() {
        let Some(index) = find(name.as_bytes()) else {
            return Err(CalibrationError::BadMap(format!(
                "the firmware has no parameter {name}"
            )));
        };
        if let Err(why) = check(index, value as f32) {
            let spec = &TABLE[index];
            return Err(CalibrationError::BadMap(format!(
                "{name} would be {value}, {why}: the rotor gives {:.2} % of full thrust at {} % \
                 command{}",
                value * 100.0,
                (KNOTS[k + 1] * 100.0).round(),
                if f64::from(spec.min) > value {
                    " (a dead band of the ESC reaching that far?); the map cannot hold it"
                } else {
                    "; the map cannot hold it"
                }
            )));
        }
    }
    ThrustMap::new(params.map(|p| p as f32)).map_err(|e| {
        CalibrationError::BadMap(match e {
            ThrustMapError::NotIncreasing { index } if index > 0 => format!(
                "{} would be {}, not above {} ({}): the fitted map does not rise",
                PARAMS[index],
                params[index],
                PARAMS[index - 1],
                params[index - 1]
            ),
            other => other.to_string(),
        })
    })
}

#[cfg(test)]
mod tests;
