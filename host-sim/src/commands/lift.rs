//! `host-sim lift --pair I --com X,Y --mass M`: the lift-off thrust model of `shared::liftoff_thrust`
//! for adjacent candidate pair `I` (candidates `I` and `I+1`, wrapping).

use anyhow::{Result, bail};
use clap::Args;
use serde_json::json;
use shared::estimation::groups::{group_count, lift_group};
use shared::geometry::Vec2;
use shared::liftoff_thrust::lift_off_thrust;

use crate::cli::{Common, Outcome, check_mass, pair};
use crate::report::print_json;
use crate::say;
use crate::scenario_file;

/// Arguments of `lift`.
#[derive(Debug, Args)]
pub struct LiftArgs {
    #[command(flatten)]
    common: Common,
    /// Index of the pair: candidates I and I+1 (wrapping).
    #[arg(long = "pair", value_name = "I")]
    pair_index: usize,
    /// Centre of mass X,Y in the body frame, m (negative: --com -0.2,0.1).
    #[arg(long, value_name = "X,Y", value_parser = pair, allow_hyphen_values = true)]
    com: [f64; 2],
    /// Payload mass, kg (above 0, at most 1000).
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    mass: f64,
}

/// Runs the command.
pub fn run(args: &LiftArgs) -> Result<Outcome> {
    let mass = check_mass("--mass", args.mass)?;
    let loaded = scenario_file::load(&args.common.scenario)?;
    let s = &loaded.scenario;
    let count = group_count(s);
    let Some(group) = lift_group(s, args.pair_index) else {
        bail!(
            "--pair {}: the scenario has {count} pairs (0 to {})",
            args.pair_index,
            count.saturating_sub(1)
        );
    };
    let com = Vec2::new(args.com[0] as f32, args.com[1] as f32);
    let Some(thrust) = lift_off_thrust(
        &s.payload.hull,
        com,
        mass,
        &group.rotor_points,
        s.robots.mass,
    ) else {
        bail!(
            "--com {},{}: lies outside the footprint's convex hull",
            args.com[0],
            args.com[1]
        );
    };
    if !thrust.is_finite() {
        bail!(
            "--com {},{} --mass {}: the model's lift-off thrust is not a finite number",
            args.com[0],
            args.com[1],
            args.mass
        );
    }
    let feasible = thrust <= s.robots.max_thrust;
    if args.common.json {
        print_json(json!({
            "pair": args.pair_index,
            "candidates": group.candidates.iter().map(|&c| s.payload.candidates[c]).collect::<Vec<_>>(),
            "rotor_points": group.rotor_points.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>(),
            "thrust": thrust,
            "feasible": feasible,
            "max_thrust": s.robots.max_thrust,
            "reachable": group.reachable,
        }))?;
    } else {
        say!(
            "pair {} (candidates at {} m along the rail): lift-off at {thrust:.3} N per robot ({} at max {} N){}",
            args.pair_index,
            group
                .candidates
                .iter()
                .map(|&c| format!("{:.3}", s.payload.candidates[c]))
                .collect::<Vec<_>>()
                .join(" and "),
            if feasible { "feasible" } else { "NOT feasible" },
            s.robots.max_thrust,
            if group.reachable {
                ""
            } else {
                "; robots cannot stand there (min_spacing)"
            }
        )?;
    }
    Ok(Outcome::Done)
}
