//! `host-sim formation [--com X,Y] [--mass M] [--output DIR]`: the formation decision of
//! `shared::formation` for a COM and mass (default: the scenario's truth), beside the even
//! formation it replaces; with `--output`, both as CSV and a figure
//! ([`crate::formation_report`]).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Result, anyhow, bail};
use clap::Args;
use serde_json::json;
use shared::formation::{Formation, FormationFigures, FormationProblem, figures, solve};
use shared::geometry::{Rail, Vec2};
use shared::scenario::GRAVITY;

use crate::cli::{Common, Outcome, check_mass, pair, show};
use crate::figures::formation::FormationFigure;
use crate::formation_report;
use crate::report::print_json;
use crate::say;
use crate::scenario_file;

/// Arguments of `formation`.
#[derive(Debug, Args)]
pub struct FormationArgs {
    #[command(flatten)]
    common: Common,
    /// Estimated centre of mass X,Y, m (default: the scenario's truth).
    #[arg(long, value_name = "X,Y", value_parser = pair, allow_hyphen_values = true)]
    com: Option<[f64; 2]>,
    /// Estimated payload mass, kg (default: the scenario's truth; above 0, at most 1000).
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    mass: Option<f64>,
    /// Write both formations (CSV) and a figure of them on the payload (footprint, rail,
    /// candidates, spins, the COM and the truth) into this folder.
    #[arg(long, value_name = "DIR")]
    output: Option<PathBuf>,
}

/// Runs the command.
pub fn run(args: &FormationArgs) -> Result<Outcome> {
    let given_mass = args.mass.map(|m| check_mass("--mass", m)).transpose()?;
    let loaded = scenario_file::load(&args.common.scenario)?;
    let s = &loaded.scenario;
    // The scenario's truth passed its checks when the file was read; only a given --com can
    // lie outside the hull here.
    let com = match (args.com, s.truth) {
        (Some([x, y]), _) => {
            let com = Vec2::new(x as f32, y as f32);
            if !s.payload.hull.contains(com, 0.0) {
                bail!(
                    "--com {},{}: lies outside the footprint's convex hull",
                    show(x),
                    show(y)
                );
            }
            com
        }
        (None, Some(t)) => t.com,
        (None, None) => bail!(
            "{}: the scenario has no [truth]; give the COM with --com",
            loaded.path.display()
        ),
    };
    let mass = match (given_mass, s.truth) {
        (Some(m), _) => m,
        (None, Some(t)) => t.mass,
        (None, None) => bail!(
            "{}: the scenario has no [truth]; give the mass with --mass",
            loaded.path.display()
        ),
    };
    let problem = FormationProblem::for_scenario(s, com, Some(&s.robots.initial));
    let started = Instant::now();
    let source = if args.com.is_some() {
        format!("--com {},{}", com.x, com.y)
    } else {
        format!("{}: truth.com", loaded.path.display())
    };
    let formation = solve(&problem).map_err(|e| anyhow!("{source}: no formation: {e}"))?;
    let solve_ms = started.elapsed().as_secs_f64() * 1e3;
    let even = figures(
        &s.payload.rail,
        &s.robots.initial,
        &s.robots.spin,
        com,
        s.robots.torque_per_thrust,
    );
    let count = s.robots.count() as f32;
    let hover_fraction = (mass + count * s.robots.mass) * GRAVITY / (count * s.robots.max_thrust);
    let written = match &args.output {
        Some(dir) => formation_report::write(
            dir,
            &loaded.name,
            &FormationFigure {
                title: format!(
                    "{}: formation for COM ({:.3}, {:.3}) m, mass {:.2} kg",
                    loaded.name, com.x, com.y, mass
                ),
                scenario: s,
                even: (&s.robots.initial, even),
                optimised: (&formation.positions, formation.figures),
                com: (com, args.com.is_some()),
                truth: s.truth.map(|t| t.com),
            },
        )?,
        None => Vec::new(),
    };
    let files: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    if args.common.json {
        let mut value = json!({
            "positions": formation.positions.as_slice(),
            "points": points(&s.payload.rail, &formation.positions),
            "det": formation.figures.det,
            "balance": formation.figures.balance,
            "min_gap": formation.figures.min_gap,
            "solve_ms": solve_ms,
            "com": [com.x, com.y],
            "mass": mass,
            "hover_thrust_fraction": hover_fraction,
            "seeds_balanced": formation.seeds_balanced,
            "sweeps": formation.sweeps,
            "even": {
                "positions": s.robots.initial.as_slice(),
                "points": points(&s.payload.rail, &s.robots.initial),
                "det": even.det,
                "balance": even.balance,
                "min_gap": even.min_gap,
            },
        });
        if args.output.is_some() {
            value["files"] = json!(files);
        }
        print_json(value)?;
    } else {
        print_human(
            &loaded.name,
            com,
            &formation,
            &even,
            solve_ms,
            hover_fraction,
        )?;
        for f in &files {
            say!("  wrote {f}")?;
        }
    }
    Ok(Outcome::Done)
}

fn points(rail: &Rail, positions: &[f32]) -> Vec<[f32; 2]> {
    positions
        .iter()
        .map(|&p| {
            let q = rail.point_at(p);
            [q.x, q.y]
        })
        .collect()
}

fn print_human(
    name: &str,
    com: Vec2,
    f: &Formation,
    even: &FormationFigures,
    solve_ms: f64,
    hover_fraction: f32,
) -> Result<()> {
    say!(
        "{name}: formation for COM ({:.3}, {:.3}), solved in {solve_ms:.2} ms",
        com.x,
        com.y
    )?;
    let list: Vec<String> = f.positions.iter().map(|p| format!("{p:.3}")).collect();
    say!("  positions (m along the rail): {}", list.join(", "))?;
    say!(
        "  optimised: det(BB^T) {:.4e}, balance [{:.1e}, {:.1e}] m, smallest gap {:.3} m",
        f.figures.det,
        f.figures.balance[0],
        f.figures.balance[1],
        f.figures.min_gap
    )?;
    say!(
        "  even:      det(BB^T) {:.4e}, balance [{:.3}, {:.3}] m, smallest gap {:.3} m",
        even.det,
        even.balance[0],
        even.balance[1],
        even.min_gap
    )?;
    say!(
        "  hover thrust: {:.0} % of the rotors' maximum",
        100.0 * hover_fraction
    )
}
