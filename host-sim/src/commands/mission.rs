//! `host-sim mission`: the autonomous pipeline in the physics plant (docs/formats.md#mission):
//! estimation by real lift-off detection, formation decision, rearrangement, flight. Without
//! `--scenario` it runs the paper's experiment case rect-ex1 (built into the binary), printing
//! each phase as it happens. This is the project's main job.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::Args;
use serde_json::json;
use shared::control::imu_monitor::ImuFailure;
use shared::estimation::{EstimatorOptions, ThrustScaleAxis};
use shared::flight::AdaptConfig;
use shared::mission::MissionConfig;

use crate::cli::{Outcome, check_map_error, check_range};
use crate::commands::fly::MixerArg;
use crate::inject::{self, Injection};
use crate::mission_figures;
use crate::mission_run::{self, EscLink, MISSION_TIME_LIMIT, MissionOutcome, MissionSetup};
use crate::pilot_script::PilotScript;
use crate::report::print_json;
use crate::say;
use crate::scenario_file;

/// The paper's experiment case, built in.
const RECT_EX1: &str = include_str!("../../../tests/scenarios/rect-ex1.toml");

/// Arguments of `mission`.
#[derive(Debug, Args)]
pub struct MissionArgs {
    /// Scenario file (default: the paper's experiment case rect-ex1, built in).
    #[arg(long, value_name = "FILE")]
    scenario: Option<PathBuf>,
    /// Print one JSON object on stdout and nothing else.
    #[arg(long)]
    json: bool,
    /// Seed of sensor noise and disturbance.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The rotors' command-to-thrust map over-reads by this factor (0.5 to 2).
    #[arg(long, value_name = "S", default_value_t = 1.0)]
    map_error: f64,
    /// Estimate the thrust-scale factor alongside theta (axis 0.9..1.2 step 0.05).
    #[arg(long)]
    bias_term: bool,
    /// Standard deviation of the lift detector's readings, N: the estimator's noise model for
    /// the lifts (default 0.5, the detector's characterised bound; above 0, at most the
    /// rotors' maximum thrust).
    #[arg(
        long,
        value_name = "N",
        conflicts_with = "scenario_sigma",
        allow_negative_numbers = true
    )]
    lift_sigma: Option<f64>,
    /// Use the scenario's noise_sigma (the paper's simulated noise) as the lifts' noise model.
    #[arg(long)]
    scenario_sigma: bool,
    /// Failure injection: motion capture stops this many seconds after take-off (0 to 900).
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    mocap_lost_after: Option<f64>,
    /// Mixer for the flight.
    #[arg(long, value_enum, default_value = "equal-split")]
    mixer: MixerArg,
    /// Failure injection, seconds after take-off began: `load-shift:DX,DY@T` moves the
    /// payload's COM by (DX, DY) m over half a second; `rotor-out:J@T` stops the rotor of
    /// robot J (from 1); `mocap-loss@T` stops motion capture; `stepper-stall:J` (no time) stalls robot
    /// J's stepper halfway through the rearrangement; `imu-stuck@T` freezes the IMU,
    /// `imu-noise:X@T` adds X times its noise (0 < X <= 1000); `gcs-loss@T` stops the simulated
    /// ground station's heartbeat; `battery:V@T` drops the pack to V volts. The IMU, ground
    /// station and battery faults also take `@start+T`, T s after the mission's start (and
    /// `gcs-loss` or `battery:V` without a time: from the start). Repeatable: every rotor-out
    /// counts, the last one of another kind.
    #[arg(long, value_name = "KIND@SECONDS", value_parser = Injection::parse)]
    inject: Vec<Injection>,
    /// The ESCs report each rotor's RPM (bidirectional DShot): the rotor monitor reads it as
    /// well as the vehicle's response (docs/failures.md#rotors-that-stop-in-flight).
    #[arg(long)]
    esc_telemetry: bool,
    /// How the flight controller drives the ESCs: `dshot` on its outputs, or `dronecan` on its
    /// CAN bus, each ESC's RPM coming in its Status at 50 Hz (docs/hardware.md#can-escs).
    #[arg(long, value_enum, default_value_t = EscLink::Dshot)]
    esc: EscLink,
    /// Switch off the formation's in-flight adaptation to a load that shifts.
    #[arg(long)]
    no_adapt: bool,
    /// Write the flight's time series (CSV), a figure of the flight (rail positions, rotor
    /// thrusts, roll and pitch, with the shift marked) and a one-page summary of the mission
    /// (phases, lifts against the model, height, attitude, thrusts) into this folder.
    #[arg(long, value_name = "DIR")]
    output: Option<PathBuf>,
    /// Write the mission's flight log to this file (ULog, PX4's format: PlotJuggler, Flight
    /// Review and pyulog open it; docs/formats.md#flight-logs).
    #[arg(long, value_name = "FILE.ulg")]
    log: Option<PathBuf>,
    /// A person at the sticks: play this stick script (timed stick and switch positions, as
    /// an RC receiver's channels or a joystick's MANUAL_CONTROL; docs/manual-control.md).
    #[arg(long, value_name = "FILE")]
    rc: Option<PathBuf>,
}

/// How a mission came out, for the exit code: dropped, aborted (or its start refused),
/// delivered or not.
pub fn outcome_of(mission: &MissionOutcome) -> Outcome {
    Outcome::of_run(
        mission.dropped,
        mission.aborted.is_some() || mission.start_refused.is_some(),
        mission.delivered,
    )
}

/// Runs the command.
pub fn run(args: &MissionArgs) -> Result<Outcome> {
    // Every flag is checked before the mission is built.
    let map_error = check_map_error(args.map_error)?;
    let mocap_lost_after = args
        .mocap_lost_after
        .map(|s| {
            check_range(
                "--mocap-lost-after",
                s,
                (0.0, false),
                f64::from(MISSION_TIME_LIMIT),
                "s",
            )
        })
        .transpose()?;
    let pilot = args.rc.as_deref().map(PilotScript::load).transpose()?;
    let loaded = match &args.scenario {
        Some(path) => scenario_file::load(path)?,
        None => scenario_file::parse(RECT_EX1, std::path::Path::new("rect-ex1 (built in)"))?,
    };
    inject::check_robots(&args.inject, &loaded)?;
    // A reading's noise beyond the rotors' whole range would carry no information.
    let max_thrust = f64::from(loaded.scenario.robots.max_thrust);
    let lift_sigma = args
        .lift_sigma
        .map(|s| check_range("--lift-sigma", s, (0.0, true), max_thrust, "N"))
        .transpose()?;
    let config = MissionConfig {
        estimator: EstimatorOptions {
            thrust_scale: args.bias_term.then_some(ThrustScaleAxis::DEFAULT),
        },
        mixer: args.mixer.kind(),
        lift_noise_sigma: if args.scenario_sigma {
            None
        } else {
            Some(lift_sigma.unwrap_or(shared::mission::DETECTOR_SIGMA))
        },
        adapt: AdaptConfig {
            enabled: !args.no_adapt,
            ..AdaptConfig::DEFAULT
        },
        ..MissionConfig::default()
    };
    let setup = inject::apply(
        &args.inject,
        MissionSetup {
            seed: args.seed,
            map_error,
            config,
            mocap_lost_after_takeoff: mocap_lost_after,
            log: args.log.clone(),
            esc_telemetry: args.esc_telemetry,
            esc: args.esc,
            pilot,
            plant: loaded.plant,
            ..MissionSetup::default()
        },
    );
    let json = args.json;
    if !json {
        say!("mission on {}", loaded.name)?;
    }
    let started = Instant::now();
    // The progress lines are written as the mission runs; a failure to write stops them and
    // is reported after the run (a reader that went away ends the process in `say`).
    let mut progress: Result<()> = Ok(());
    let (outcome, _) = mission_run::run(&loaded.scenario, &setup, &mut |t, name, reason| {
        if !json && progress.is_ok() {
            progress = say!("  {t:7.2} s  {name:<17} {reason}");
        }
    })?;
    progress?;
    let wall_s = started.elapsed().as_secs_f64();
    let mut written = match &args.output {
        Some(dir) => mission_figures::write(
            dir,
            &loaded.name,
            &outcome,
            loaded.scenario.robots.max_thrust,
        )?,
        None => Vec::new(),
    };
    written.extend(args.log.iter().cloned());
    if json {
        print_json(json!({
            "scenario": loaded.name,
            "estimate": outcome.estimate,
            "measurements": outcome.measurements,
            "positions": outcome.positions,
            "delivered": outcome.delivered,
            "dropped": outcome.dropped,
            "final_position_error_m": outcome.final_position_error_m,
            "phases": outcome.phases.iter().map(|(name, d)| json!({"name": name, "duration_s": d})).collect::<Vec<_>>(),
            "lifts": outcome.lifts.iter().map(|(g, r, m)| json!({"pair": g, "reading": r, "model": m})).collect::<Vec<_>>(),
            "aborted": outcome.aborted.map(|r| r.to_string()),
            "simulated_s": outcome.simulated_s,
            "wall_s": wall_s,
            "max_tilt_deg": outcome.max_tilt_deg,
            "can_bus": outcome.can_bus_load.map(|(frames, share)| json!({
                "frames_per_second": frames,
                "share": share,
            })),
            "max_thrust_fraction": outcome.max_thrust_fraction,
            "rotors_out": rotors_out_json(&outcome),
            "rotor_landing_offset_m": outcome.rotor_landing_offset_m,
            "adaptations": outcome.adaptations.iter().map(|a| json!({
                "time_s": a.t,
                "com": a.com,
                "mass": a.mass,
                "positions": a.positions,
                "rebalanced_s": a.rebalanced_at,
            })).collect::<Vec<_>>(),
            "imu_fault": outcome.imu_fault_at.map(|at| json!({
                "injected_s": at,
                "detected": outcome.imu_detected.map(|(f, _)| match f {
                    ImuFailure::Stuck => "stuck",
                    ImuFailure::Noisy => "noisy",
                }),
                "detected_s": outcome.imu_detected.map(|(_, d)| d),
            })),
            "files": written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "notices": outcome.notices.iter().map(|(t, text)| json!({"time_s": t, "text": text})).collect::<Vec<_>>(),
            "start_refused": outcome.start_refused.map(|r| r.to_string()),
            "gcs_lost_at_s": outcome.gcs_lost_at,
            "battery_dropped_at_s": outcome.battery_dropped_at,
            "min_battery_volts": outcome.min_battery_volts.is_finite().then_some(outcome.min_battery_volts),
        }))?;
    } else {
        for (g, r, m) in &outcome.lifts {
            match r {
                Some(r) => say!("lift with pair {g}: read {r:.3} N, the model says {m:.3} N")?,
                None => say!("lift with pair {g}: could not lift, the model says {m:.3} N")?,
            }
        }
        match outcome.estimate {
            Some(e) => say!(
                "estimate: COM ({:.3}, {:.3}) m, mass {:.2} kg after {} lifts",
                e[0],
                e[1],
                e[2],
                outcome.measurements
            )?,
            None => say!("no estimate ({} lifts)", outcome.measurements)?,
        }
        say!(
            "{}: final position error {:.3} m; {:.1} s simulated in {:.1} s",
            match outcome_of(&outcome) {
                Outcome::Done => "delivered",
                Outcome::Dropped => "DROPPED",
                Outcome::Aborted => "ABORTED",
                Outcome::NotDelivered => "NOT delivered",
            },
            outcome.final_position_error_m,
            outcome.simulated_s,
            wall_s
        )?;
        if let Some(why) = &outcome.aborted {
            say!("aborted: {why}")?;
        }
        if let Some(at) = outcome.imu_fault_at {
            match outcome.imu_detected {
                Some((failure, d)) => say!(
                    "IMU fault injected at {at:.4} s; the monitor found it {:.1} ms later: {failure}",
                    1000.0 * (d - at)
                )?,
                None => say!("IMU fault injected at {at:.4} s; the monitor did not flag it")?,
            }
        }
        if let Some(why) = &outcome.start_refused {
            say!("start refused: {why}")?;
        }
        say!(
            "in flight: largest tilt {:.1} deg, largest rotor command {:.0} % of its maximum",
            outcome.max_tilt_deg,
            100.0 * outcome.max_thrust_fraction
        )?;
        if let Some((frames, share)) = outcome.can_bus_load {
            say!(
                "CAN bus (DroneCAN ESCs): {frames:.0} frames a second, {:.1} % of 1 Mbit/s",
                100.0 * share
            )?;
        }
        for a in &outcome.adaptations {
            let rebalanced = a
                .rebalanced_at
                .map_or("the robots did not get there".to_string(), |r| {
                    format!("rebalanced at {r:.2} s")
                });
            say!(
                "  {:7.2} s  the load shifted: COM ({:.3}, {:.3}) m, mass {:.2} kg; {rebalanced}",
                a.t,
                a.com[0],
                a.com[1],
                a.mass
            )?;
        }
        for (robot, at) in &outcome.rotors_stopped {
            let found = outcome
                .rotors_found
                .iter()
                .find(|(r, _)| r == robot)
                .map_or("not found".to_string(), |(_, f)| {
                    format!("found at {f:.3} s, {:.0} ms later", 1000.0 * (f - at))
                });
            say!("  {at:7.2} s  rotor {} stopped: {found}", robot + 1)?;
        }
        if let Some(offset) = outcome.rotor_landing_offset_m {
            say!("  came down {offset:.3} m from where the first rotor stopped")?;
        }
        for (robot, f) in &outcome.rotors_found {
            if !outcome.rotors_stopped.iter().any(|(r, _)| r == robot) {
                say!(
                    "  {f:7.2} s  rotor {} found stopped, but it was not",
                    robot + 1
                )?;
            }
        }
        for path in &written {
            say!("wrote {}", path.display())?;
        }
    }
    Ok(outcome_of(&outcome))
}

/// The report's `rotors_out`: each rotor stopped in the plant or found stopped by the
/// mission (robots from 1), with `stopped_s` (injected) and `detected_s` (found), simulated
/// seconds, `null` when it did not happen.
fn rotors_out_json(outcome: &mission_run::MissionOutcome) -> Vec<serde_json::Value> {
    let mut robots: Vec<usize> = Vec::new();
    for (r, _) in outcome.rotors_stopped.iter().chain(&outcome.rotors_found) {
        if !robots.contains(r) {
            robots.push(*r);
        }
    }
    robots
        .into_iter()
        .map(|r| {
            let at = |list: &[(usize, f32)]| list.iter().find(|(x, _)| *x == r).map(|(_, t)| *t);
            json!({
                "robot": r + 1,
                "stopped_s": at(&outcome.rotors_stopped),
                "detected_s": at(&outcome.rotors_found),
            })
        })
        .collect()
}
