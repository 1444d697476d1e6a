//! Runs `shared`'s mission against the physics plant (SPEC.md section 5, `mission`): the
//! estimation lifts are real lift-offs of the simulated payload read from the simulated IMU,
//! the robots move along the rail as the mission commands, and the flight is the plant's.

use anyhow::{Result, anyhow};
use shared::control::vector::Vec3;
use shared::estimation::Measurement;
use shared::geometry::Vec2;
use shared::mission::{
    AbortReason, Mission, MissionConfig, MissionPlanner, OperatorCommand, Phase, Reason, TickInput,
    Transition,
};
use shared::scenario::Scenario;

use crate::harness::{CONTROL_HZ, DROP_TILT_DEG};
use crate::plant::sensors::Sensors;
use crate::plant::{PHYSICS_DT, Plant, PlantConfig};

/// Longest mission simulated, s.
pub const MISSION_TIME_LIMIT: f32 = 900.0;

/// One mission run's set-up.
#[derive(Clone, Debug)]
pub struct MissionSetup {
    /// Seed of sensor noise and disturbance.
    pub seed: u64,
    /// The rotors' command-to-thrust over-read factor.
    pub map_error: f32,
    /// The mission's configuration.
    pub config: MissionConfig,
    /// Failure injection: motion capture stops this long after take-off began, s.
    pub mocap_lost_after_takeoff: Option<f32>,
    /// Operator commands after the start: (seconds after take-off began, command).
    pub commands: Vec<(f32, OperatorCommand)>,
}

impl Default for MissionSetup {
    /// Seed 1, an exact command-to-thrust map, the default mission, no failure, no command
    /// but the start.
    fn default() -> Self {
        Self {
            seed: 1,
            map_error: 1.0,
            config: MissionConfig::default(),
            mocap_lost_after_takeoff: None,
            commands: Vec::new(),
        }
    }
}

/// What the mission did.
#[derive(Clone, Debug)]
pub struct MissionOutcome {
    /// The converged estimate [COM x, COM y, mass], if estimation converged.
    pub estimate: Option<[f32; 3]>,
    /// Lifts taken.
    pub measurements: u32,
    /// The flight formation, if one was chosen.
    pub positions: Option<Vec<f32>>,
    /// Landed at the target and disarmed.
    pub delivered: bool,
    /// Roll or pitch exceeded 45 degrees.
    pub dropped: bool,
    /// Distance from the landing point at the end, m.
    pub final_position_error_m: f32,
    /// Each phase entered and how long it lasted, s.
    pub phases: Vec<(String, f32)>,
    /// Each lift: group, reading (N, or `None` when it could not lift), model lift-off thrust
    /// for the truth (N).
    pub lifts: Vec<(usize, Option<f32>, f32)>,
    /// Why it stopped early (or landed in place), if it did.
    pub aborted: Option<AbortReason>,
    /// Whether the rotors were ever armed.
    pub armed: bool,
    /// Whether the payload left the ground.
    pub flew: bool,
    /// Thrust of every rotor at the end, N.
    pub final_thrusts: Vec<f32>,
    /// Simulated time, s.
    pub simulated_s: f32,
}

/// Runs the mission; `on_transition` sees each transition with its time as it happens.
pub fn run(
    scenario: &Scenario,
    setup: &MissionSetup,
    on_transition: &mut dyn FnMut(f32, &Transition),
) -> Result<MissionOutcome> {
    let truth = scenario
        .truth
        .ok_or_else(|| anyhow!("[truth]: the mission needs the scenario's truth to simulate"))?;
    let flight = scenario
        .flight
        .ok_or_else(|| anyhow!("[flight]: the mission needs the scenario's flight target"))?;
    let rail = &scenario.payload.rail;
    let robots = &scenario.robots;
    let rotor_points =
        |positions: &[f32]| -> Vec<Vec2> { positions.iter().map(|&s| rail.point_at(s)).collect() };
    let mut plant = Plant::new(PlantConfig {
        footprint: scenario.payload.footprint.to_vec(),
        com: truth.com,
        mass: truth.mass,
        robot_mass: robots.mass,
        rotor_points: rotor_points(&robots.initial),
        spin: robots.spin.to_vec(),
        torque_per_thrust: robots.torque_per_thrust,
        max_thrust: robots.max_thrust,
        map_error: setup.map_error,
        // The paper's disturbance acts on the flight; it is switched on at take-off.
        disturbance_peak: 0.0,
        disturbance_phase: [0.4 + setup.seed as f32 % 3.0, 1.9],
    });
    let mut sensors = Sensors::new(setup.seed);
    let mut planner = MissionPlanner::new(scenario, setup.config)
        .map_err(|e| anyhow!("the mission cannot start: {e}"))?;
    let mut mission = Mission::new(scenario, setup.config);
    let dt = 1.0 / CONTROL_HZ as f32;
    let physics_per_tick = (dt / PHYSICS_DT).round() as usize;
    let n = robots.count();
    let mut phases: Vec<(String, f32)> = Vec::new();
    let mut entered = 0.0f32;
    let mut record = |t: f32, tr: &Transition, phases: &mut Vec<(String, f32)>| {
        if let Some(last) = phases.last_mut() {
            last.1 = t - entered;
        }
        phases.push((tr.to.name().to_string(), 0.0));
        entered = t;
    };
    let mut current = robots.initial.to_vec();
    let mut mocap_lost_at = f32::INFINITY;
    let mut takeoff_at = f32::INFINITY;
    let mut next_command = 0usize;
    let mut command = Some(OperatorCommand::Start);
    let mut lifts = Vec::new();
    let mut group = 0usize;
    let (mut dropped, mut armed, mut flew) = (false, false, false);
    let mut thrusts = vec![0.0f32; n];
    loop {
        let t = plant.time();
        if t > MISSION_TIME_LIMIT {
            break;
        }
        let truth_now = plant.state();
        let imu = sensors.imu(&truth_now, dt);
        let mocap = sensors
            .mocap(&truth_now, plant.time_us())
            .filter(|_| t < mocap_lost_at);
        if command.is_none() {
            if let Some(&(after, c)) = setup.commands.get(next_command) {
                if t >= takeoff_at + after {
                    command = Some(c);
                    next_command += 1;
                }
            }
        }
        let out = mission.step(&TickInput {
            time_us: plant.time_us(),
            imu,
            mocap,
            command: command.take(),
        });
        if let Some(job) = &out.job {
            // The firmware runs this off the tick; its result is taken at its deadline tick
            // either way.
            mission.deliver(planner.run(job));
        }
        armed |= out.armed;
        flew |= mission.flight().is_some_and(|f| f.airborne());
        if let Some(tr) = out.transition {
            if matches!(tr.to, Phase::Flying(_)) && matches!(tr.reason, Reason::Armed) {
                plant.set_disturbance_peak(flight.disturbance_torque);
                takeoff_at = t;
                if let Some(after) = setup.mocap_lost_after_takeoff {
                    mocap_lost_at = t + after;
                }
            }
            on_transition(t, &tr);
            record(t, &tr, &mut phases);
            match tr.reason {
                Reason::PairChosen { group: g, .. } => group = g,
                Reason::LiftRead(m) => {
                    let model = shared::estimation::groups::lift_group(scenario, group)
                        .and_then(|g| {
                            shared::statics::lift_off_thrust(
                                &scenario.payload.hull,
                                truth.com,
                                truth.mass,
                                &g.rotor_points,
                                robots.mass,
                            )
                        })
                        .unwrap_or(f32::NAN);
                    let reading = match m {
                        Measurement::Lifted { thrust } => Some(thrust),
                        Measurement::CouldNotLift => None,
                    };
                    lifts.push((group, reading, model));
                }
                _ => {}
            }
        }
        if out.robots.as_slice() != current.as_slice() {
            current = out.robots.to_vec();
            plant.set_rotor_points(&rotor_points(&current));
        }
        thrusts.copy_from_slice(&out.thrusts[..n]);
        let euler = truth_now.attitude.to_euler();
        if euler.x.abs().to_degrees() > DROP_TILT_DEG || euler.y.abs().to_degrees() > DROP_TILT_DEG
        {
            dropped = true;
            break;
        }
        if matches!(out.phase, Phase::Disarmed | Phase::Aborted) {
            break;
        }
        for _ in 0..physics_per_tick {
            plant.step(&thrusts);
        }
    }
    let end = plant.time();
    if let Some(last) = phases.last_mut() {
        last.1 = end - entered;
    }
    let landing = Vec3::new(flight.target[0], flight.target[1], 0.0);
    let final_error = (plant.state().position - landing).norm();
    let delivered = mission.phase() == Phase::Disarmed
        && mission.abort_reason().is_none()
        && !dropped
        && final_error < 0.25;
    Ok(MissionOutcome {
        estimate: mission.estimate().map(|e| e.theta),
        measurements: mission.measurements(),
        positions: mission.formation().map(|p| p.to_vec()),
        delivered,
        dropped,
        final_position_error_m: final_error,
        phases,
        lifts,
        aborted: mission.abort_reason(),
        armed,
        flew,
        final_thrusts: thrusts,
        simulated_s: end,
    })
}
