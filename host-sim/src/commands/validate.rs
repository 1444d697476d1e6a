//! `host-sim validate`: reads and checks a scenario file, prints its derived geometry.

use anyhow::Result;
use serde_json::json;

use crate::cli::{Common, Outcome};
use crate::report::print_json;
use crate::say;
use crate::scenario_file::{self, LoadedScenario};

/// Runs the command.
pub fn run(common: &Common) -> Result<Outcome> {
    let loaded = scenario_file::load(&common.scenario)?;
    if common.json {
        print_json(report(&loaded))?;
        return Ok(Outcome::Done);
    }
    let s = &loaded.scenario;
    say!(
        "scenario {} ({}): valid",
        loaded.name,
        loaded.path.display()
    )?;
    say!(
        "  footprint {} vertices, hull {} vertices; rail {:.3} m; {} candidates",
        s.payload.footprint.len(),
        s.payload.hull.vertices().len(),
        s.payload.rail.perimeter(),
        s.payload.candidates.len()
    )?;
    say!(
        "  {} robots, lifting {} at a time; grid {} x {} x {} = {} points",
        s.robots.count(),
        s.robots.pair_size,
        s.estimation.axis_len(0),
        s.estimation.axis_len(1),
        s.estimation.axis_len(2),
        s.estimation.grid_points()
    )?;
    Ok(Outcome::Done)
}

fn report(loaded: &LoadedScenario) -> serde_json::Value {
    let s = &loaded.scenario;
    let xy = |p: shared::geometry::Vec2| [p.x, p.y];
    let grid_shape = [0, 1, 2].map(|a| s.estimation.axis_len(a));
    json!({
        "name": loaded.name,
        "valid": true,
        "hull": s.payload.hull.vertices().iter().map(|&p| xy(p)).collect::<Vec<_>>(),
        "rail_length": s.payload.rail.perimeter(),
        "candidates": s.payload.candidates.iter()
            .map(|&c| json!({"arc_length": c, "point": xy(s.payload.rail.point_at(c))}))
            .collect::<Vec<_>>(),
        "robots": s.robots.count(),
        "pair_size": s.robots.pair_size,
        "grid_shape": grid_shape,
        "grid_points": s.estimation.grid_points(),
    })
}
