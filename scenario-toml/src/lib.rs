//! Reading scenario files (docs/formats.md#scenario-files).
//!
//! The TOML is parsed here, on the host; every rule a value must follow is checked by
//! `shared::scenario`, so the simulator and the firmware accept the same scenarios. Any
//! problem comes back as an error naming the file and the key.

mod plant;

pub use plant::PlantDepartures;

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use serde::Deserialize;
use shared::geometry::Vec2;
use shared::scenario::{
    EstimationSetup, FlightSetup, FormationSetup, Problem, RobotsInput, Scenario, ScenarioError,
    ScenarioInput, Truth,
};

/// A scenario file, read and checked.
#[derive(Clone, Debug)]
pub struct LoadedScenario {
    /// `name` from the file.
    pub name: String,
    /// Where it was read from.
    pub path: PathBuf,
    /// The checked values.
    pub scenario: Scenario,
    /// How the simulated plant departs from the model (`[plant]`; the model without it).
    pub plant: PlantDepartures,
}

/// Largest scenario file read, bytes. The paper's files are under 1 KiB; the cap keeps a
/// wrong path (`/dev/zero`, a log file) from filling memory.
pub const MAX_FILE_BYTES: u64 = 1 << 20;
/// Longest scenario `name`, characters (it names output files).
pub const MAX_NAME_CHARS: usize = 64;

// Points and fixed-length lists are read as lists of any length and checked here, so that a
// point with three numbers is an error naming its key rather than a silently dropped number.
#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a scenario: name and the [payload], [robots], [estimation], [formation] tables"
)]
struct FileToml {
    name: String,
    payload: PayloadToml,
    robots: RobotsToml,
    estimation: EstimationToml,
    formation: FormationToml,
    truth: Option<TruthToml>,
    flight: Option<FlightToml>,
    plant: Option<plant::PlantToml>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a [payload] table")]
struct PayloadToml {
    footprint: Vec<Vec<f64>>,
    rail: Vec<Vec<f64>>,
    candidates: Vec<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a [robots] table")]
struct RobotsToml {
    count: usize,
    mass: f64,
    max_thrust: f64,
    torque_per_thrust: f64,
    spin: Vec<i64>,
    min_spacing: f64,
    pair_size: usize,
    initial: Option<Vec<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "an [estimation] table")]
struct EstimationToml {
    grid_min: Vec<f64>,
    grid_max: Vec<f64>,
    resolution: Vec<f64>,
    threshold: f64,
    noise_sigma: f64,
    max_measurements: u32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a [formation] table")]
struct FormationToml {
    balance_eps: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a [truth] table")]
struct TruthToml {
    com: Vec<f64>,
    mass: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a [flight] table")]
struct FlightToml {
    target: Vec<f64>,
    disturbance_torque: f64,
}

/// `v` as `f32`; a finite value beyond `f32`'s range becomes `f32::MAX` with its sign (which
/// `shared`'s range checks then report as "over 3.40282e38"), never infinity.
pub fn to_f32(v: f64) -> f32 {
    if v.is_finite() {
        v.clamp(-f64::from(f32::MAX), f64::from(f32::MAX)) as f32
    } else {
        v as f32
    }
}

fn points(key: &'static str, raw: &[Vec<f64>]) -> Result<Vec<Vec2>, ScenarioError> {
    raw.iter()
        .enumerate()
        .map(|(index, p)| match p.as_slice() {
            &[x, y] => Ok(Vec2::new(to_f32(x), to_f32(y))),
            _ => Err(ScenarioError {
                key,
                problem: Problem::Coordinates {
                    index,
                    found: p.len(),
                },
            }),
        })
        .collect()
}

fn f32s(raw: &[f64]) -> Vec<f32> {
    raw.iter().map(|&v| to_f32(v)).collect()
}

fn fixed<const N: usize>(key: &'static str, raw: &[f64]) -> Result<[f32; N], ScenarioError> {
    if raw.len() != N {
        return Err(ScenarioError {
            key,
            problem: Problem::Length {
                expected: N,
                found: raw.len(),
            },
        });
    }
    Ok(std::array::from_fn(|i| to_f32(raw[i])))
}

/// The scenario key (`section.key`) that the byte `offset` of `text` falls in, found from the
/// nearest `[section]` header and `key =` line above it; `None` when there is none.
fn key_at(text: &str, offset: usize) -> Option<String> {
    let before = &text[..offset.min(text.len())];
    // The whole line holding the offset: a key may follow the offset on its own line.
    let line_end = text[before.len()..]
        .find('\n')
        .map_or(text.len(), |i| before.len() + i);
    let upto = &text[..line_end];
    let mut key = None;
    for line in upto.lines().rev() {
        let line = line.trim();
        if let Some(header) = line.strip_prefix('[') {
            let section = header.split(']').next().unwrap_or("").trim();
            return Some(match key {
                Some(k) => format!("{section}.{k}"),
                None => section.to_string(),
            });
        }
        if key.is_some() || line.starts_with('#') {
            continue;
        }
        if let Some((k, _)) = line.split_once('=') {
            let k = k.trim();
            if !k.is_empty() && !k.contains(['"', '[', ' ', '#']) {
                key = Some(k.to_string());
            }
        }
    }
    key
}

/// Edits (insertions, deletions, substitutions) between `a` and `b`.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let above = row[j + 1];
            row[j + 1] = (above + 1)
                .min(row[j] + 1)
                .min(diagonal + usize::from(ca != *cb));
            diagonal = above;
        }
    }
    row[b.len()]
}

/// For an unknown key (serde's "unknown field `x`, expected ..."), the known name nearest it
/// when one is close (a slip of a letter or two): "; did you mean `y`?".
fn nearest_known(message: &str) -> String {
    let Some(rest) = message.strip_prefix("unknown field `") else {
        return String::new();
    };
    let Some((unknown, expected)) = rest.split_once('`') else {
        return String::new();
    };
    let known = expected.split('`').skip(1).step_by(2);
    let best = known
        .map(|k| (edit_distance(unknown, k), k))
        .min_by_key(|(d, _)| *d);
    match best {
        Some((d, k)) if d > 0 && d <= 2.max(unknown.chars().count() / 3) => {
            format!("; did you mean `{k}`?")
        }
        _ => String::new(),
    }
}

fn toml_error(e: &toml::de::Error, text: &str, origin: &Path) -> anyhow::Error {
    let message = e.message().trim().replace('\n', " ");
    // An unknown key is refused, not ignored: a misspelt one would otherwise fly the default.
    let message =
        format!("{message}{}", nearest_known(&message)).replacen("unknown field", "unknown key", 1);
    let Some(span) = e.span() else {
        return anyhow!("{}: {message}", origin.display());
    };
    let start = span.start.min(text.len());
    let line = text[..start].matches('\n').count() + 1;
    let column = start - text[..start].rfind('\n').map_or(0, |i| i + 1) + 1;
    let source: String = text
        .lines()
        .nth(line - 1)
        .unwrap_or("")
        .trim()
        .chars()
        .take(80)
        .collect();
    let key = key_at(text, start).map_or(String::new(), |k| format!("{k}: "));
    anyhow!(
        "{}: {key}line {line}, column {column} (`{source}`): {message}",
        origin.display()
    )
}

fn check_name(name: &str) -> Result<(), String> {
    let chars = name.chars().count();
    if chars == 0 || chars > MAX_NAME_CHARS {
        return Err(format!(
            "must be 1 to {MAX_NAME_CHARS} characters (got {chars})"
        ));
    }
    if name.chars().any(char::is_control) {
        return Err("must not contain control characters".to_string());
    }
    Ok(())
}

/// Parses and checks scenario TOML. `origin` names the source in error messages.
pub fn parse(text: &str, origin: &Path) -> Result<LoadedScenario> {
    let file: FileToml = toml::from_str(text).map_err(|e| toml_error(&e, text, origin))?;
    check_name(&file.name).map_err(|why| anyhow!("{}: name: {why}", origin.display()))?;
    let input = |file: &FileToml| -> Result<Scenario, ScenarioError> {
        let footprint = points("payload.footprint", &file.payload.footprint)?;
        let rail = points("payload.rail", &file.payload.rail)?;
        let candidates = f32s(&file.payload.candidates);
        let initial = file.robots.initial.as_deref().map(f32s);
        let e = &file.estimation;
        let truth = match &file.truth {
            Some(t) => {
                let [x, y] = fixed::<2>("truth.com", &t.com)?;
                Some(Truth {
                    com: Vec2::new(x, y),
                    mass: to_f32(t.mass),
                })
            }
            None => None,
        };
        let flight = match &file.flight {
            Some(f) => Some(FlightSetup {
                target: fixed::<3>("flight.target", &f.target)?,
                disturbance_torque: to_f32(f.disturbance_torque),
            }),
            None => None,
        };
        Scenario::from_input(&ScenarioInput {
            footprint: &footprint,
            rail: &rail,
            candidates: &candidates,
            robots: RobotsInput {
                count: file.robots.count,
                mass: to_f32(file.robots.mass),
                max_thrust: to_f32(file.robots.max_thrust),
                torque_per_thrust: to_f32(file.robots.torque_per_thrust),
                spin: &file.robots.spin,
                min_spacing: to_f32(file.robots.min_spacing),
                pair_size: file.robots.pair_size,
                initial: initial.as_deref(),
            },
            estimation: EstimationSetup {
                grid_min: fixed::<3>("estimation.grid_min", &e.grid_min)?,
                grid_max: fixed::<3>("estimation.grid_max", &e.grid_max)?,
                resolution: fixed::<3>("estimation.resolution", &e.resolution)?,
                threshold: to_f32(e.threshold),
                noise_sigma: to_f32(e.noise_sigma),
                max_measurements: e.max_measurements,
            },
            formation: FormationSetup {
                balance_eps: to_f32(file.formation.balance_eps),
            },
            truth,
            flight,
        })
    };
    let scenario = input(&file).map_err(|err| anyhow!("{}: {err}", origin.display()))?;
    let plant = match &file.plant {
        Some(p) => p
            .departures()
            .map_err(|why| anyhow!("{}: {why}", origin.display()))?,
        None => PlantDepartures::MODEL,
    };
    Ok(LoadedScenario {
        name: file.name,
        path: origin.to_path_buf(),
        scenario,
        plant,
    })
}

/// Reads, parses and checks the scenario file at `path`. Reads at most [`MAX_FILE_BYTES`].
pub fn load(path: &Path) -> Result<LoadedScenario> {
    let cannot = || format!("cannot read scenario file {}", path.display());
    let file = File::open(path).with_context(cannot)?;
    let mut bytes = Vec::new();
    file.take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .with_context(cannot)?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        bail!(
            "scenario file {} is larger than {} KiB; a scenario is a short TOML file",
            path.display(),
            MAX_FILE_BYTES / 1024
        );
    }
    let text = String::from_utf8(bytes)
        .map_err(|e| anyhow!("scenario file {} is not UTF-8 text ({e})", path.display()))?;
    parse(&text, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    const PAPER: &str = include_str!("../../tests/scenarios/rect-sim1.toml");

    fn error_of(text: &str) -> String {
        format!("{:#}", parse(text, Path::new("s.toml")).unwrap_err())
    }

    #[test]
    fn a_toml_error_names_its_section_and_key() {
        let text =
            "name = \"x\"\n[payload]\nfootprint = [[0, 0]]\n\n[robots]\n# a comment\ncount = = 8\n";
        let offset = text.find("= = 8").unwrap() + 2;
        assert_eq!(key_at(text, offset).as_deref(), Some("robots.count"));
        let offset = text.find("[0, 0]").unwrap();
        assert_eq!(key_at(text, offset).as_deref(), Some("payload.footprint"));
        assert_eq!(key_at(text, 0).as_deref(), Some("name"));
        let err = error_of(&PAPER.replace("count = 8", "count = \"eight\""));
        assert!(err.starts_with("s.toml: robots.count: line"), "{err}");
    }

    #[test]
    fn points_and_fixed_lists_with_a_wrong_count_name_key_and_index() {
        let err = error_of(&PAPER.replace("[0.88, -0.1],", "[0.88, -0.1, 0.5],"));
        assert!(
            err.contains("payload.footprint: point 1 has 3 numbers"),
            "{err}"
        );
        let err = error_of(&PAPER.replace("com = [0.33, 0.01]", "com = [0.33, 0.01, 1]"));
        assert!(err.contains("truth.com: needs 2 entries (got 3)"), "{err}");
    }

    #[test]
    fn numbers_beyond_f32_are_reported_not_made_infinite() {
        assert_eq!(to_f32(1e40), f32::MAX);
        assert_eq!(to_f32(-1e40), -f32::MAX);
        assert!(to_f32(f64::NAN).is_nan());
        let err = error_of(&PAPER.replace("torque_per_thrust = 0.016", "torque_per_thrust = 1e40"));
        assert!(err.contains("robots.torque_per_thrust"), "{err}");
        assert!(err.contains("over 3.40282e38"), "{err}");
    }

    #[test]
    fn a_name_with_control_characters_is_refused() {
        let err = error_of(&PAPER.replace("name = \"rect-sim1\"", "name = \"a\\u001bb\""));
        assert!(
            err.contains("name: must not contain control characters"),
            "{err}"
        );
    }

    #[test]
    fn edits_count_insertions_deletions_and_substitutions() {
        assert_eq!(edit_distance("plant", "plantt"), 1);
        assert_eq!(edit_distance("torqe", "torque"), 1);
        assert_eq!(edit_distance("abc", "xbz"), 2);
        assert_eq!(edit_distance("", "wind"), 4);
    }

    #[test]
    fn an_unknown_key_is_refused_with_its_line_and_the_key_it_is_near() {
        let text = "name = \"x\"\n[flight]\ntarget = [0.0, 0.0, 1.0]\ndisturbance_torqe = 0.3\n";
        let said = format!(
            "{:#}",
            parse(text, Path::new("t.toml")).expect_err("refused")
        );
        assert!(said.contains("flight.disturbance_torqe: line 4"), "{said}");
        assert!(said.contains("unknown key"), "{said}");
        assert!(
            said.contains("did you mean `disturbance_torque`?"),
            "{said}"
        );
        // Nothing near: no guess.
        let far = "name = \"x\"\nwind_speed = 5\n";
        let said = format!(
            "{:#}",
            parse(far, Path::new("t.toml")).expect_err("refused")
        );
        assert!(
            said.contains("wind_speed") && !said.contains("did you mean"),
            "{said}"
        );
    }
}
