//! `host-sim validate`: reads and checks a scenario file, prints its derived geometry; with
//! `--board`, also whether that flight controller drives all its robots, as the vehicle checks
//! a payload description before it takes it (docs/hardware.md#robots-a-board-drives).

use anyhow::{Result, bail};
use clap::Args;
use serde_json::json;
use shared::mission::HardwareConfig;
use shared::mission::drives::{self, BoardDrives};
use shared::mission::esc_protocol::{Choices, EscProtocol};

use crate::cli::{Common, Outcome};
use crate::report::print_json;
use crate::say;
use crate::scenario_file::{self, LoadedScenario};

/// Arguments of `validate`.
#[derive(Debug, Args)]
pub struct ValidateArgs {
    /// The scenario file and `--json`.
    #[command(flatten)]
    pub common: Common,
    /// The flight controller that is to fly it: `pixhawk6c` (8 rotors on its outputs, 16 on
    /// DroneCAN; 16 steppers) or `qemu` (16). Without it, the limit of 16 robots every board's
    /// software takes.
    #[arg(long, value_name = "BOARD", value_parser = parse_board)]
    pub board: Option<(String, BoardDrives)>,
    /// The board's `ESC_PROTOCOL` for `--board`: 0 DShot600 (the default), 1 PWM,
    /// 2 OneShot125, 3 DroneCAN.
    #[arg(long, value_name = "N", requires = "board", value_parser = parse_esc_protocol)]
    pub esc_protocol: Option<u8>,
}

/// An `ESC_PROTOCOL` value by number.
fn parse_esc_protocol(text: &str) -> Result<u8, String> {
    text.parse::<i32>()
        .ok()
        .and_then(|n| EscProtocol::from_value(n).ok())
        .map(EscProtocol::value)
        .ok_or_else(|| format!("`{text}` is no ESC_PROTOCOL: {Choices}"))
}

/// A board by name ([`drives::BOARDS`]).
fn parse_board(name: &str) -> Result<(String, BoardDrives), String> {
    drives::board(name)
        .map(|d| (name.to_string(), d))
        .ok_or_else(|| {
            let known: Vec<&str> = drives::BOARDS.iter().map(|(n, _)| *n).collect();
            format!("no board `{name}`; the boards are {}", known.join(", "))
        })
}

/// Runs the command.
pub fn run(args: &ValidateArgs) -> Result<Outcome> {
    let common = &args.common;
    let loaded = scenario_file::load(&common.scenario)?;
    let protocol = args
        .esc_protocol
        .unwrap_or(HardwareConfig::DEFAULT.esc_protocol);
    if let Some((name, board)) = &args.board
        && let Err(e) = board.check(loaded.scenario.robots.count(), protocol)
    {
        bail!(
            "{}: {name} refuses this payload description: {e}",
            loaded.path.display()
        );
    }
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
    if let Some((name, board)) = &args.board {
        say!(
            "  {name} drives them: {} rotors (ESC_PROTOCOL {}), {} steppers",
            board.rotors(protocol),
            drives::esc_protocol_name(protocol),
            board.steppers
        )?;
    }
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
