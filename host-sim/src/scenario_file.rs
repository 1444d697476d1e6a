//! Reading scenario files (SPEC.md section 5, "Scenario files").
//!
//! The TOML is parsed here, on the host; every rule a value must follow is checked by
//! `shared::scenario`, so the simulator and the firmware accept the same scenarios. Any
//! problem comes back as an error naming the file and the key.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow};
use serde::Deserialize;
use shared::geometry::Vec2;
use shared::scenario::{
    EstimationSetup, FlightSetup, FormationSetup, RobotsInput, Scenario, ScenarioInput, Truth,
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
}

#[derive(Deserialize)]
struct FileToml {
    name: String,
    payload: PayloadToml,
    robots: RobotsToml,
    estimation: EstimationToml,
    formation: FormationToml,
    truth: Option<TruthToml>,
    flight: Option<FlightToml>,
}

#[derive(Deserialize)]
struct PayloadToml {
    footprint: Vec<[f64; 2]>,
    rail: Vec<[f64; 2]>,
    candidates: Vec<f64>,
}

#[derive(Deserialize)]
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
struct EstimationToml {
    grid_min: [f64; 3],
    grid_max: [f64; 3],
    resolution: [f64; 3],
    threshold: f64,
    noise_sigma: f64,
    max_measurements: u32,
}

#[derive(Deserialize)]
struct FormationToml {
    balance_eps: f64,
}

#[derive(Deserialize)]
struct TruthToml {
    com: [f64; 2],
    mass: f64,
}

#[derive(Deserialize)]
struct FlightToml {
    target: [f64; 3],
    disturbance_torque: f64,
}

fn points(raw: &[[f64; 2]]) -> Vec<Vec2> {
    raw.iter()
        .map(|p| Vec2::new(p[0] as f32, p[1] as f32))
        .collect()
}

fn f32s(raw: &[f64]) -> Vec<f32> {
    raw.iter().map(|&v| v as f32).collect()
}

fn f32x3(raw: [f64; 3]) -> [f32; 3] {
    raw.map(|v| v as f32)
}

/// Parses and checks scenario TOML. `origin` names the source in error messages.
pub fn parse(text: &str, origin: &Path) -> Result<LoadedScenario> {
    let file: FileToml = toml::from_str(text).map_err(|e| {
        let message = e.message().trim().replace('\n', " ");
        match e.span() {
            Some(span) => {
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
                anyhow!(
                    "{}: line {line}, column {column} (`{source}`): {message}",
                    origin.display()
                )
            }
            None => anyhow!("{}: {message}", origin.display()),
        }
    })?;
    let footprint = points(&file.payload.footprint);
    let rail = points(&file.payload.rail);
    let candidates = f32s(&file.payload.candidates);
    let initial = file.robots.initial.as_deref().map(f32s);
    let e = &file.estimation;
    let input = ScenarioInput {
        footprint: &footprint,
        rail: &rail,
        candidates: &candidates,
        robots: RobotsInput {
            count: file.robots.count,
            mass: file.robots.mass as f32,
            max_thrust: file.robots.max_thrust as f32,
            torque_per_thrust: file.robots.torque_per_thrust as f32,
            spin: &file.robots.spin,
            min_spacing: file.robots.min_spacing as f32,
            pair_size: file.robots.pair_size,
            initial: initial.as_deref(),
        },
        estimation: EstimationSetup {
            grid_min: f32x3(e.grid_min),
            grid_max: f32x3(e.grid_max),
            resolution: f32x3(e.resolution),
            threshold: e.threshold as f32,
            noise_sigma: e.noise_sigma as f32,
            max_measurements: e.max_measurements,
        },
        formation: FormationSetup {
            balance_eps: file.formation.balance_eps as f32,
        },
        truth: file.truth.map(|t| Truth {
            com: Vec2::new(t.com[0] as f32, t.com[1] as f32),
            mass: t.mass as f32,
        }),
        flight: file.flight.map(|f| FlightSetup {
            target: f32x3(f.target),
            disturbance_torque: f.disturbance_torque as f32,
        }),
    };
    let scenario =
        Scenario::from_input(&input).map_err(|err| anyhow!("{}: {err}", origin.display()))?;
    Ok(LoadedScenario {
        name: file.name,
        path: origin.to_path_buf(),
        scenario,
    })
}

/// Reads, parses and checks the scenario file at `path`.
pub fn load(path: &Path) -> Result<LoadedScenario> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read scenario file {}", path.display()))?;
    parse(&text, path)
}
