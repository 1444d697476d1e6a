//! The mission's tunables as named 32-bit float parameters: every
//! field of [`MissionConfig`] an operator may change, with its unit, its range and what it
//! does, in one table. The ground link (`link::param`) serves this table over MAVLink's
//! parameter protocol and stores its values; the mission reads them back through
//! [`ParamValues::config`].
//!
//! A value is accepted only when it is finite, inside `[min, max]` and, for a parameter marked
//! integer, a whole number ([`check`]). The ranges bound what the mission has been shown to
//! tolerate or what is physically sensible; they are not tuning advice. The drivers' settings
//! ([`super::hardware`]: ESC protocol, thrust map, steppers) are parameters too, and so is the
//! ground link's map origin (`ORIG_*`, [`ORIGIN`]; no field of the configuration,
//! docs/ground-link.md#the-map-origin). Not here: the estimator's thrust-scale axis (a grid,
//! not a number).

use crate::control::allocation::MixerKind;
use crate::mission::config::MissionConfig;
use crate::mission::supervision::GcsLossAction;
use crate::numbers::Num;

/// Longest parameter name, bytes (MAVLink's `param_id`).
pub const NAME_LEN: usize = 16;

/// One parameter: where it lives in the [`MissionConfig`] and what values it may take.
#[derive(Clone, Copy)]
pub struct ParamSpec {
    /// Name, at most [`NAME_LEN`] bytes, upper case (`GROUP_WHAT`).
    pub name: &'static str,
    /// Unit, as people write it (`-` for none).
    pub unit: &'static str,
    /// Smallest value accepted.
    pub min: f32,
    /// Largest value accepted.
    pub max: f32,
    /// Only whole numbers are accepted (counts, choices).
    pub integer: bool,
    /// The only values accepted, when not every whole number in range is one (a choice among
    /// PX4's numbers); empty: every value in range.
    pub allowed: &'static [f32],
    /// What it does, one line (with the `docs` feature: the host's tables and README; the
    /// firmware does without the text).
    #[cfg(feature = "docs")]
    pub doc: &'static str,
    /// Reads it from a configuration.
    pub get: fn(&MissionConfig) -> f32,
    /// Writes it into a configuration (the value already checked).
    pub set: fn(&mut MissionConfig, f32),
}

impl ParamSpec {
    /// A value it accepts, a fraction `t` (0 to 1) of the way through its range or its
    /// choices (for tests and fuzzing that want valid values).
    pub fn valid_value(&self, t: f32) -> f32 {
        let t = crate::math::clamp(t, 0.0, 1.0);
        if !self.allowed.is_empty() {
            let last = self.allowed.len() - 1;
            return self.allowed[((t * last as f32) as usize).min(last)];
        }
        let v = self.min + t * (self.max - self.min);
        if self.integer {
            crate::math::clamp(crate::math::round(v), self.min, self.max)
        } else {
            v
        }
    }

    /// Its value in [`MissionConfig::DEFAULT`].
    pub fn default_value(&self) -> f32 {
        (self.get)(&MissionConfig::DEFAULT)
    }
}

impl core::fmt::Debug for ParamSpec {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("ParamSpec")
            .field("name", &self.name)
            .finish()
    }
}

macro_rules! param {
    ($name:literal, $unit:literal, $min:expr, $max:expr, $doc:literal, |$c:ident| $field:expr) => {
        param!(@ $name, $unit, $min, $max, false, $doc, |$c| $field)
    };
    // A whole-number field (a count or a choice, of any integer type).
    (whole $name:literal, $unit:literal, $min:expr, $max:expr, $doc:literal, |$c:ident| $field:expr) => {
        ParamSpec {
            name: $name,
            unit: $unit,
            min: $min,
            max: $max,
            integer: true,
            allowed: &[],
            #[cfg(feature = "docs")]
            doc: $doc,
            get: |$c: &MissionConfig| $field as f32,
            set: |$c: &mut MissionConfig, v: f32| $field = v as _,
        }
    };
    // A switch: 1 on, 0 off (a `bool` field; any value above one half is on).
    (flag $name:literal, $doc:literal, |$c:ident| $field:expr) => {
        ParamSpec {
            name: $name,
            unit: "-",
            min: 0.0,
            max: 1.0,
            integer: true,
            allowed: &[],
            #[cfg(feature = "docs")]
            doc: $doc,
            get: |$c: &MissionConfig| if $field { 1.0 } else { 0.0 },
            set: |$c: &mut MissionConfig, v: f32| $field = v > 0.5,
        }
    };
    // A whole-number parameter of the ground link (the map origin): no field of the
    // configuration; read with `ParamValues::get`.
    (link $name:literal, $unit:literal, $min:expr, $max:expr, $default:expr, $doc:literal) => {
        ParamSpec {
            name: $name,
            unit: $unit,
            min: $min,
            max: $max,
            integer: true,
            allowed: &[],
            #[cfg(feature = "docs")]
            doc: $doc,
            get: |_: &MissionConfig| $default,
            set: |_: &mut MissionConfig, _: f32| {},
        }
    };
    (@ $name:literal, $unit:literal, $min:expr, $max:expr, $int:expr, $doc:literal, |$c:ident| $field:expr) => {
        ParamSpec {
            name: $name,
            unit: $unit,
            min: $min,
            max: $max,
            integer: $int,
            allowed: &[],
            #[cfg(feature = "docs")]
            doc: $doc,
            get: |$c: &MissionConfig| $field,
            set: |$c: &mut MissionConfig, v: f32| $field = v,
        }
    };
}

/// Number of parameters.
pub const COUNT: usize = 134;

/// Index of the first of the map origin's five parameters, in this order: `ORIG_LAT_DEG`,
/// `ORIG_LAT_E7`, `ORIG_LON_DEG`, `ORIG_LON_E7`, `ORIG_ALT` (docs/ground-link.md#the-map-origin).
/// They are the ground link's, not the mission's: no field of [`MissionConfig`].
pub const ORIGIN: usize = 96;
/// How many parameters the map origin has.
pub const ORIGIN_LEN: usize = 5;
/// `ORIG_ALT`'s default, m: PX4's simulation home (47.397742 N, 8.545594 E, 488 m), a
/// clearly borrowed place a ground station can show until the origin is set.
pub const ORIGIN_DEFAULT_ALT: f32 = 488.0;

/// Whether parameter `index` is the map origin's (the ground link's, no field of
/// [`MissionConfig`]).
pub const fn is_origin(index: usize) -> bool {
    index >= ORIGIN && index < ORIGIN + ORIGIN_LEN
}

pub mod metadata;
mod table;
#[cfg(test)]
mod tests;

pub use table::TABLE;

/// Why a value was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamError {
    /// No parameter has this name or index.
    Unknown,
    /// Not a finite number.
    NotFinite,
    /// Outside the parameter's range.
    OutOfRange {
        /// Smallest accepted.
        min: f32,
        /// Largest accepted.
        max: f32,
    },
    /// A fraction given to a parameter that takes whole numbers.
    NotWhole,
    /// A number in range that is none of the parameter's choices.
    NotAChoice,
}

impl core::fmt::Display for ParamError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Unknown => write!(f, "no such parameter"),
            Self::NotFinite => write!(f, "not a finite number"),
            Self::OutOfRange { min, max } => write!(f, "outside {}..{}", Num(min), Num(max)),
            Self::NotWhole => write!(f, "not a whole number"),
            Self::NotAChoice => write!(f, "not one of its choices"),
        }
    }
}

/// Whether `value` is acceptable for parameter `index`.
pub fn check(index: usize, value: f32) -> Result<(), ParamError> {
    let spec = TABLE.get(index).ok_or(ParamError::Unknown)?;
    if !value.is_finite() {
        return Err(ParamError::NotFinite);
    }
    if value < spec.min || value > spec.max {
        return Err(ParamError::OutOfRange {
            min: spec.min,
            max: spec.max,
        });
    }
    if spec.integer && crate::math::floor(value) != value {
        return Err(ParamError::NotWhole);
    }
    if !spec.allowed.is_empty() && !spec.allowed.contains(&value) {
        return Err(ParamError::NotAChoice);
    }
    Ok(())
}

/// The index of the parameter called `name` (MAVLink `param_id`: up to 16 bytes, NUL-padded).
pub fn find(name: &[u8]) -> Option<usize> {
    let end = name.iter().position(|&b| b == 0).unwrap_or(name.len());
    let name = &name[..end];
    TABLE.iter().position(|p| p.name.as_bytes() == name)
}

/// The current value of every parameter, in table order; always valid (every value passed
/// [`check`]).
#[derive(Clone, Debug)]
pub struct ParamValues {
    values: [f32; COUNT],
}

/// Equal when every parameter has the same value in force, bit for bit (one never set equals
/// one set to its default). Not derived: NaN marks "never set", and NaN equals nothing.
impl PartialEq for ParamValues {
    fn eq(&self, other: &Self) -> bool {
        (0..COUNT).all(|i| self.get(i).map(f32::to_bits) == other.get(i).map(f32::to_bits))
    }
}

impl Default for ParamValues {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl ParamValues {
    /// Every parameter at its default ([`MissionConfig::DEFAULT`]).
    pub const DEFAULT: Self = Self {
        values: [f32::NAN; COUNT],
    };

    /// Value of parameter `index` (`None` past the table).
    pub fn get(&self, index: usize) -> Option<f32> {
        let v = *self.values.get(index)?;
        // NaN marks "never set": the default, read from the table.
        Some(if v.is_nan() {
            TABLE[index].default_value()
        } else {
            v
        })
    }

    /// Sets parameter `index` to `value` if [`check`] accepts it; otherwise keeps the old value.
    pub fn set(&mut self, index: usize, value: f32) -> Result<(), ParamError> {
        check(index, value)?;
        self.values[index] = value;
        Ok(())
    }

    /// The mission configuration these values make (the defaults for what no parameter
    /// covers).
    pub fn config(&self) -> MissionConfig {
        let mut config = MissionConfig::DEFAULT;
        for (index, spec) in TABLE.iter().enumerate() {
            if let Some(v) = self.get(index) {
                (spec.set)(&mut config, v);
            }
        }
        config
    }
}

/// The parameter table in Markdown (name, unit, range, default, what it does), as
/// docs/ground-link.md lists it.
#[cfg(feature = "docs")]
pub fn markdown_table(out: &mut impl core::fmt::Write) -> core::fmt::Result {
    writeln!(out, "| index | name | unit | min | max | default | what |")?;
    writeln!(out, "|---|---|---|---|---|---|---|")?;
    for (i, p) in TABLE.iter().enumerate() {
        let kind = if p.integer { " (whole)" } else { "" };
        writeln!(
            out,
            "| {i} | `{}` | {} | {} | {} | {} | {}{kind} |",
            p.name,
            p.unit,
            p.min,
            p.max,
            p.default_value(),
            p.doc
        )?;
    }
    Ok(())
}
