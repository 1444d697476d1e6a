//! Runs `shared`'s flight software against the physics plant at the firmware's rates
//! (docs/system.md#flight; docs/formats.md#fly): IMU and control at 400 Hz, physics at 2 kHz,
//! motion capture at 100 Hz with latency.
//!
//! The vehicle takes off from the ground, follows the reference trajectory to the target,
//! hovers, lands and disarms. The controller believes the COM and mass it is given; the plant
//! always has the truth. Nothing here decides anything: the navigator and the flight stack
//! (cascade, mixer, plan, take-off check, land detector, failsafes) are `shared`'s, the same
//! the mission flies.

use crate::plant::departures::ApplyDepartures;
use anyhow::{Result, anyhow, bail};
use shared::control::allocation::MixerKind;
use shared::control::navigator::Navigator;
use shared::control::trajectory::FlightPhase;
use shared::control::vector::Vec3;
use shared::flight::{FlightConfig, FlightModel, FlightStack, FlightStop};
use shared::formation::{FormationProblem, solve};
use shared::geometry::Vec2;
use shared::scenario::{GRAVITY, Scenario};

use crate::plant::sensors::Sensors;
use crate::plant::{PHYSICS_DT, Plant, PlantConfig};

/// Control rate, Hz (the firmware's).
pub const CONTROL_HZ: u32 = shared::timing::CONTROL_RATE_HZ;
/// Time on the ground, rotors off, before the plan starts (the estimators settle), s.
pub const ARM_DELAY: f32 = 1.0;
/// Roll or pitch beyond this counts as dropped (the paper), degrees.
pub const DROP_TILT_DEG: f32 = 45.0;
/// Time allowed beyond the plan's nominal duration (waiting at segment ends, landing), s.
const FLIGHT_GRACE: f32 = 30.0;

/// Which formation the robots fly in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FormationChoice {
    /// Robot `j` at `j * perimeter / count` (or the scenario's `initial`).
    Even,
    /// `shared::formation`'s optimum for the believed COM.
    Optimized,
}

impl FormationChoice {
    /// The name on the command line (`even`, `optimized`), also used in file names.
    pub fn name(self) -> &'static str {
        match self {
            Self::Even => "even",
            Self::Optimized => "optimized",
        }
    }

    /// The name for people: `even formation`, `optimised formation`.
    pub fn label(self) -> &'static str {
        match self {
            Self::Even => "even formation",
            Self::Optimized => "optimised formation",
        }
    }

    /// The other one.
    pub fn other(self) -> Self {
        match self {
            Self::Even => Self::Optimized,
            Self::Optimized => Self::Even,
        }
    }
}

/// The mixer's name as on the command line: `equal-split`, `allocation`.
pub fn mixer_name(mixer: MixerKind) -> &'static str {
    match mixer {
        MixerKind::EqualSplit => "equal-split",
        MixerKind::Allocation => "allocation",
    }
}

/// One flight to simulate.
#[derive(Clone, Copy, Debug)]
pub struct FlightSetup {
    /// Formation.
    pub formation: FormationChoice,
    /// Mixer.
    pub mixer: MixerKind,
    /// COM the controller believes, m.
    pub believed_com: Vec2,
    /// Payload mass the controller believes, kg.
    pub believed_mass: f32,
    /// Seed of sensor noise and disturbance phase.
    pub seed: u64,
    /// Command-to-thrust over-read factor of the plant's rotors.
    pub map_error: f32,
    /// How the plant departs from the model (the scenario's `[plant]`).
    pub plant: scenario_toml::PlantDepartures,
}

/// One row of the time series (100 Hz).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Time since the start, s.
    pub t: f32,
    /// True position, NED, m.
    pub position: Vec3,
    /// Reference position, NED, m.
    pub reference: Vec3,
    /// True roll, pitch, yaw, degrees.
    pub attitude_deg: Vec3,
    /// Largest rotor command as a fraction of the maximum.
    pub max_thrust_fraction: f32,
    /// Collective commanded, N.
    pub collective: f32,
    /// Whether the allocation cut anything.
    pub saturated: bool,
}

/// What a flight produced.
#[derive(Clone, Debug)]
pub struct FlightOutcome {
    /// Roll or pitch exceeded 45 degrees.
    pub dropped: bool,
    /// Largest tilt of the body from level, degrees.
    pub max_tilt_deg: f32,
    /// RMS of the distance between truth and reference over the plan, m.
    pub rms_tracking_error_m: f32,
    /// Distance of the payload from its landing point at the end, m.
    pub final_position_error_m: f32,
    /// Largest rotor command over the flight as a fraction of the maximum.
    pub max_thrust_fraction: f32,
    /// Greatest height of the payload frame above the ground, m (near 0: never took off).
    pub max_height_m: f32,
    /// The formation flown (arc lengths).
    pub positions: Vec<f32>,
    /// Whether the landing was detected and the rotors stopped.
    pub landed: bool,
    /// Why the rotors stopped, if they did (the flight stack's reason).
    pub stop: Option<FlightStop>,
    /// Simulated time, s.
    pub simulated_s: f32,
    /// The time series.
    pub samples: Vec<Sample>,
}

/// The formation's arc lengths for `choice`.
pub fn formation_positions(
    scenario: &Scenario,
    choice: FormationChoice,
    com: Vec2,
) -> Result<Vec<f32>> {
    match choice {
        FormationChoice::Even => Ok(scenario.robots.initial.to_vec()),
        FormationChoice::Optimized => {
            let problem =
                FormationProblem::for_scenario(scenario, com, Some(&scenario.robots.initial));
            let f = solve(&problem).map_err(|e| anyhow!("formation: {e}"))?;
            Ok(f.positions.to_vec())
        }
    }
}

/// Flies one fixed formation (`setup`, no estimation before it) on `scenario`'s truth and
/// flight set-up: take-off, the plan to the target, hover and landing.
pub fn fly_formation(scenario: &Scenario, setup: &FlightSetup) -> Result<FlightOutcome> {
    let Some(truth) = scenario.truth else {
        bail!("[truth]: the scenario has no truth to simulate");
    };
    let Some(flight) = scenario.flight else {
        bail!("[flight]: the scenario has no flight target");
    };
    let positions = formation_positions(scenario, setup.formation, setup.believed_com)?;
    let rail = &scenario.payload.rail;
    let points: Vec<Vec2> = positions.iter().map(|&s| rail.point_at(s)).collect();
    let robots = &scenario.robots;
    let mut seed_rng = setup.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let mut phase = || {
        seed_rng ^= seed_rng << 13;
        seed_rng ^= seed_rng >> 7;
        seed_rng ^= seed_rng << 17;
        (seed_rng % 6283) as f32 * 1e-3
    };
    let mut plant = Plant::new(PlantConfig {
        footprint: scenario.payload.footprint.to_vec(),
        com: truth.com,
        mass: truth.mass,
        robot_mass: robots.mass,
        rotor_points: points.clone(),
        spin: robots.spin.to_vec(),
        torque_per_thrust: robots.torque_per_thrust,
        max_thrust: robots.max_thrust,
        map_error: setup.map_error,
        disturbance_peak: flight.disturbance_torque,
        disturbance_phase: [phase(), phase()],
        ..PlantConfig::MODEL
    });
    setup.plant.apply(plant.config_mut(), setup.seed);
    plant.refresh();
    let mut sensors = Sensors::departed(setup.seed, &setup.plant, &plant);

    // The flight software, as the mission builds it after the formation decision.
    let model = FlightModel::build(
        scenario,
        &positions,
        setup.believed_com,
        setup.believed_mass,
        setup.mixer,
    )
    .map_err(|e| anyhow!("mixer: {e}"))?;
    let mut navigator = Navigator::new();
    let mut flight_stack: Option<FlightStack> = None;
    let start = plant.state().position;
    let landing_point = Vec3::new(flight.target[0], flight.target[1], start.z);

    let dt = 1.0 / CONTROL_HZ as f32;
    let physics_per_tick = (dt / PHYSICS_DT).round() as usize;
    let nominal =
        shared::control::trajectory::FlightPlan::new(start, flight.target, 0.0, Default::default());
    let end = ARM_DELAY + nominal.duration() + FLIGHT_GRACE;
    let n = positions.len();
    let mut commands = vec![0.0f32; n];
    let (mut dropped, mut max_tilt, mut max_fraction) = (false, 0.0f32, 0.0f32);
    let mut max_height = 0.0f32;
    let (mut squared_error, mut error_samples) = (0.0f64, 0u64);
    let mut samples = Vec::new();
    let mut stop = None;
    let mut tick: u64 = 0;
    loop {
        let t = plant.time();
        if t >= end {
            break;
        }
        let now_us = plant.time_us();
        let truth_now = plant.state();
        sensors.hear_rotors(&plant);
        let imu = sensors.imu(&truth_now, dt);
        if let Some(fix) = sensors.mocap(&truth_now, now_us) {
            navigator.motion_capture(&fix);
        }
        let nav = navigator.update(&imu, dt, now_us);
        if t >= ARM_DELAY && flight_stack.is_none() {
            flight_stack = Some(FlightStack::new(
                FlightConfig::default(),
                model.clone(),
                nav.position.position,
                flight.target,
            ));
        }
        let out = flight_stack.as_mut().map(|f| f.step(&nav, None, dt));
        let (setpoint, phase, collective, saturated) = match &out {
            Some(o) => {
                commands.copy_from_slice(&o.thrusts[..n]);
                if let Some(shared::flight::FlightEvent::Stopped(why)) = o.event {
                    stop = Some(why);
                }
                (
                    o.setpoint.position,
                    o.phase,
                    o.collective,
                    o.saturation.any(),
                )
            }
            None => (start, FlightPhase::Takeoff, 0.0, false),
        };

        let tilt = truth_now
            .attitude
            .rotate(Vec3::DOWN)
            .z
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees();
        max_tilt = max_tilt.max(tilt);
        max_height = max_height.max(start.z - truth_now.position.z);
        let fraction = commands.iter().fold(0.0f32, |m, &c| m.max(c)) / robots.max_thrust;
        max_fraction = max_fraction.max(fraction);
        if out.is_some() && phase != FlightPhase::Done && stop.is_none() {
            let e = (truth_now.position - setpoint).norm();
            squared_error += f64::from(e * e);
            error_samples += 1;
        }
        if tick % 4 == 0 {
            let e = truth_now.attitude.to_euler();
            samples.push(Sample {
                t,
                position: truth_now.position,
                reference: setpoint,
                attitude_deg: Vec3::new(e.x.to_degrees(), e.y.to_degrees(), e.z.to_degrees()),
                max_thrust_fraction: fraction,
                collective,
                saturated,
            });
        }
        let euler = truth_now.attitude.to_euler();
        if euler.x.abs().to_degrees() > DROP_TILT_DEG || euler.y.abs().to_degrees() > DROP_TILT_DEG
        {
            dropped = true;
            break;
        }
        if stop.is_some() {
            break;
        }
        for _ in 0..physics_per_tick {
            plant.step(&commands);
        }
        tick += 1;
    }
    let final_state = plant.state();
    Ok(FlightOutcome {
        dropped,
        max_tilt_deg: max_tilt,
        rms_tracking_error_m: if error_samples > 0 {
            (squared_error / error_samples as f64).sqrt() as f32
        } else {
            0.0
        },
        final_position_error_m: (final_state.position - landing_point).norm(),
        max_thrust_fraction: max_fraction,
        max_height_m: max_height,
        positions,
        landed: stop == Some(FlightStop::Landed),
        stop,
        simulated_s: plant.time(),
        samples,
    })
}

/// One estimation lift in the plant: what the detector read and what the model predicts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiftOutcome {
    /// The detector's reading (in commanded units).
    pub measured: shared::estimation::Measurement,
    /// The model's lift-off thrust for the truth (actual thrust), N.
    pub model: f32,
    /// Simulated time of the lift, s.
    pub duration_s: f32,
}

/// Runs one estimation lift of group `group` (robots placed by `shared::rail::moves::lift_targets` from the
/// scenario's initial formation) on the plant, reading lift-off with `shared`'s detector.
pub fn run_lift(
    scenario: &Scenario,
    group: usize,
    seed: u64,
    map_error: f32,
) -> Result<LiftOutcome> {
    run_lift_from(scenario, group, &scenario.robots.initial, seed, map_error)
}

/// [`run_lift`] with the robots starting from `from` instead of the initial formation.
pub fn run_lift_from(
    scenario: &Scenario,
    group: usize,
    from: &[f32],
    seed: u64,
    map_error: f32,
) -> Result<LiftOutcome> {
    use shared::estimation::groups::lift_group;
    use shared::liftoff_detector::{LiftState, LiftoffConfig, LiftoffDetector};
    use shared::liftoff_thrust::lift_off_thrust;

    let Some(truth) = scenario.truth else {
        bail!("[truth]: the scenario has no truth to simulate");
    };
    let g = lift_group(scenario, group)
        .ok_or_else(|| anyhow!("lifting group {group} does not exist"))?;
    let rail = &scenario.payload.rail;
    let candidates: Vec<f32> = g
        .candidates
        .iter()
        .map(|&c| scenario.payload.candidates[c])
        .collect();
    let robots = &scenario.robots;
    let targets = shared::rail::moves::lift_targets(rail, from, &candidates, robots.min_spacing)
        .ok_or_else(|| anyhow!("lifting group {group} cannot be reached by the robots"))?;
    let points: Vec<Vec2> = targets.iter().map(|&s| rail.point_at(s)).collect();
    let pair: Vec<usize> = candidates
        .iter()
        .filter_map(|c| targets.iter().position(|t| (t - c).abs() < 1e-5))
        .collect();
    let model = lift_off_thrust(
        &scenario.payload.hull,
        truth.com,
        truth.mass,
        &g.rotor_points,
        robots.mass,
    )
    .ok_or_else(|| anyhow!("the truth's COM lies outside the hull"))?;
    let mut plant = Plant::new(PlantConfig {
        footprint: scenario.payload.footprint.to_vec(),
        com: truth.com,
        mass: truth.mass,
        robot_mass: robots.mass,
        rotor_points: points,
        spin: robots.spin.to_vec(),
        torque_per_thrust: robots.torque_per_thrust,
        max_thrust: robots.max_thrust,
        map_error,
        disturbance_peak: 0.0,
        disturbance_phase: [0.0, 0.0],
        ..PlantConfig::MODEL
    });
    let mut sensors = Sensors::new(seed);
    let mut navigator = Navigator::new();
    let own_weight = robots.mass * GRAVITY;
    let mut detector =
        LiftoffDetector::new(LiftoffConfig::default(), own_weight, robots.max_thrust);
    let dt = 1.0 / CONTROL_HZ as f32;
    let physics_per_tick = (dt / PHYSICS_DT).round() as usize;
    let n = targets.len();
    let mut commands = vec![own_weight; n];
    // The attitude estimator settles (gyro bias) before the lift, as in the mission's checks.
    let started = 5.0;
    loop {
        let t = plant.time();
        if t > 120.0 {
            bail!("lift with group {group} did not end");
        }
        let truth_now = plant.state();
        let imu = sensors.imu(&truth_now, dt);
        if let Some(fix) = sensors.mocap(&truth_now, plant.time_us()) {
            navigator.motion_capture(&fix);
        }
        let nav = navigator.update(&imu, dt, plant.time_us());
        if t >= started {
            match detector.step(nav.attitude.attitude, dt) {
                LiftState::Measured(m) => {
                    return Ok(LiftOutcome {
                        measured: m,
                        model,
                        duration_s: t - started,
                    });
                }
                LiftState::Restless => bail!(
                    "lift with group {group}: the payload did not come to rest ({:.2} deg within a settle window)",
                    detector.window_moved().to_degrees()
                ),
                _ => {}
            }
            for &i in &pair {
                commands[i] = detector.pair_thrust();
            }
        }
        for _ in 0..physics_per_tick {
            plant.step(&commands);
        }
    }
}
