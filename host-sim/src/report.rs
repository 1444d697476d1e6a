//! What the commands print and write: lines and JSON on stdout, flight reports on disk (the
//! time series as CSV and the figures of [`crate::figures`]).
//!
//! Stdout is written through [`say`] (macro [`say!`](crate::say)), never `println!`, which
//! panics when the reader has gone away (`host-sim mission | head -1`): a closed stdout ends the
//! process quietly with code 0, as a filter does. JSON goes through [`print_json`], which prints
//! the simulator's `f32` values as their shortest decimal (`0.12`, not `0.11999999731779099`).
//! Files on disk are named from the scenario's `name` only after [`file_stem`] has made it a
//! plain file name, so no scenario can write outside the folder given with `--output`.

use std::fmt;
use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde_json::Value;

use crate::harness::{FlightOutcome, FlightSetup};

/// Writes one line to stdout. When the reader has gone away (a broken pipe) the process ends
/// here, quietly, with code 0; any other failure to write is returned.
pub fn say(line: fmt::Arguments<'_>) -> Result<()> {
    let mut out = io::stdout().lock();
    match writeln!(out, "{line}").and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => std::process::exit(0),
        Err(e) => Err(e).context("cannot write to stdout"),
    }
}

/// `println!` for the commands: one line to stdout through [`report::say`](crate::report::say).
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::report::say(format_args!($($arg)*))
    };
}

/// Prints `value` as one line of JSON, with [`shortest_f32_numbers`] applied.
pub fn print_json(mut value: Value) -> Result<()> {
    shortest_f32_numbers(&mut value);
    say(format_args!("{value}"))
}

/// Rewrites every number in `value` that is exactly an `f32` as the `f64` nearest to that
/// `f32`'s shortest decimal form, so that it prints as `0.12` and not as the `f32`'s exact
/// binary value `0.11999999731779099`. Numbers computed in `f64` are (but for round values,
/// which print the same either way) not exactly `f32`s and stay as they are.
pub fn shortest_f32_numbers(value: &mut Value) {
    match value {
        Value::Number(n) if n.is_f64() => {
            let v = n.as_f64().unwrap_or(f64::NAN);
            let single = v as f32;
            if single.is_finite() && f64::from(single) == v {
                let shortest = single.to_string().parse::<f64>().ok();
                if let Some(shortest) = shortest.and_then(serde_json::Number::from_f64) {
                    *n = shortest;
                }
            }
        }
        Value::Array(items) => items.iter_mut().for_each(shortest_f32_numbers),
        Value::Object(map) => map.values_mut().for_each(shortest_f32_numbers),
        _ => {}
    }
}

/// `name` made into a plain file name: letters, digits, `-` and `_` kept, every other run of
/// characters (path separators, dots, spaces) one `_`, none at either end; `scenario` when
/// nothing is left. The result has no separator and is never `.` or `..`.
pub fn file_stem(name: &str) -> String {
    let mut stem = String::new();
    for c in name.chars() {
        if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
            stem.push(c);
        } else if !stem.ends_with('_') {
            stem.push('_');
        }
    }
    let stem = stem.trim_matches('_');
    if stem.is_empty() {
        "scenario".to_string()
    } else {
        stem.to_string()
    }
}

/// Writes `<dir>/<stem>.csv`, `<stem>-height.png` and `<stem>-attitude.png` with
/// `stem = <name>-<formation>-<mixer>` (`name` through [`file_stem`], formation and mixer as
/// on the command line), and returns the files written. Positions in the CSV are world NED
/// from the take-off point: `z_down_m` and `ref_z_down_m` are positive downwards (the height
/// is minus them; once the plan is over the setpoint sits 0.3 m below the ground, which holds
/// the payload down until the rotors stop). A figure that cannot be drawn (no font) is
/// reported on stderr; the CSV always is written.
pub fn write_flight(
    dir: &Path,
    name: &str,
    setup: &FlightSetup,
    outcome: &FlightOutcome,
) -> Result<Vec<PathBuf>> {
    fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let stem = format!(
        "{}-{}-{}",
        file_stem(name),
        setup.formation.name(),
        crate::harness::mixer_name(setup.mixer)
    );
    let csv = dir.join(format!("{stem}.csv"));
    let mut f =
        fs::File::create(&csv).with_context(|| format!("cannot write {}", csv.display()))?;
    writeln!(
        f,
        "t_s,x_m,y_m,z_down_m,ref_x_m,ref_y_m,ref_z_down_m,roll_deg,pitch_deg,yaw_deg,max_thrust_fraction,collective_n,saturated"
    )?;
    for s in &outcome.samples {
        writeln!(
            f,
            "{:.4},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.3},{:.3},{:.3},{:.4},{:.3},{}",
            s.t,
            s.position.x,
            s.position.y,
            s.position.z,
            s.reference.x,
            s.reference.y,
            s.reference.z,
            s.attitude_deg.x,
            s.attitude_deg.y,
            s.attitude_deg.z,
            s.max_thrust_fraction,
            s.collective,
            u8::from(s.saturated)
        )?;
    }
    let mut written = vec![csv];
    let label = format!(
        "{}, {} mixer",
        setup.formation.label(),
        crate::harness::mixer_name(setup.mixer)
    );
    let height = crate::figures::height(
        &dir.join(format!("{stem}-height.png")),
        &format!("{name}: height, {label}"),
        &[(label.as_str(), outcome)],
    );
    let attitude = crate::figures::attitude(
        &dir.join(format!("{stem}-attitude.png")),
        &format!("{name}: roll and pitch, {label}"),
        outcome,
    );
    for figure in [height, attitude] {
        match figure {
            Ok(path) => written.push(path),
            Err(e) => warn(&format!("figure skipped: {e:#}")),
        }
    }
    Ok(written)
}

/// Writes the paper's comparison figure, height over time for several flights, to
/// `<dir>/<name>-height-comparison.png` (`name` through [`file_stem`]).
pub fn write_comparison(
    dir: &Path,
    name: &str,
    flights: &[(&str, &FlightOutcome)],
) -> Result<PathBuf> {
    fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    crate::figures::height(
        &dir.join(format!("{}-height-comparison.png", file_stem(name))),
        &format!("{name}: height, even vs optimised formation"),
        flights,
    )
}

/// Prints a warning line on stderr; a closed stderr is ignored.
pub fn warn(message: &str) {
    let _ = writeln!(io::stderr(), "warning: {message}");
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn file_stems_are_plain_names_inside_the_folder() {
        assert_eq!(file_stem("rect-sim1"), "rect-sim1");
        assert_eq!(file_stem("L_sim 2"), "L_sim_2");
        assert_eq!(file_stem("../../escaped"), "escaped");
        assert_eq!(file_stem("/etc/passwd"), "etc_passwd");
        assert_eq!(file_stem("a\\..\\b"), "a_b");
        assert_eq!(file_stem(".."), "scenario");
        assert_eq!(file_stem(""), "scenario");
        for name in ["../../escaped", "..", "/abs", "a/../../b", "c:\\x"] {
            let path = Path::new("out").join(format!("{}.csv", file_stem(name)));
            assert_eq!(path.parent(), Some(Path::new("out")), "{name}");
        }
    }

    #[test]
    fn f32_values_print_as_their_shortest_decimal() {
        let mut v = json!({
            "a": 0.12f32,
            "b": [0.56f32, 1.0e-7f32, -3.5f32],
            "c": 0.1f64,
            "n": 3,
            "s": "0.11999999731779099",
        });
        assert!(v.to_string().contains("0.11999999731779099,"), "{v}");
        shortest_f32_numbers(&mut v);
        assert_eq!(
            v.to_string(),
            r#"{"a":0.12,"b":[0.56,1e-7,-3.5],"c":0.1,"n":3,"s":"0.11999999731779099"}"#
        );
    }
}
