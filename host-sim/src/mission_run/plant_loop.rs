//! The plant loop ([`fly`]): the physics plant stepped at its rate, the sensors sampled and
//! the injected failures applied each control tick, the autopilot's commands taken back, and
//! what the plant saw recorded ([`PlantRecord`]); docs/system.md#pipeline.

use crate::plant::departures::ApplyDepartures;
use anyhow::{Result, anyhow};
use shared::control::navigator::ImuSample;
use shared::control::vector::Vec3;
use shared::flight::AdaptEvent;
use shared::geometry::{Rail, Vec2};
use shared::mission::{HardwareFaults, OperatorCommand};
use shared::scenario::{MAX_ROBOTS, Scenario};

use super::{
    Autopilot, EscLink, Event, ImuFaultKind, LOAD_SHIFT_TIME, MISSION_TIME_LIMIT, MissionSetup,
    PACK_SAG_VOLTS, PACK_VOLTS, Sensed,
};
use crate::harness::{CONTROL_HZ, DROP_TILT_DEG};
use crate::plant::dronecan_escs::DroneCanEscs;
use crate::plant::sensors::{ImuNoise, Sensors};
use crate::plant::{PHYSICS_DT, Plant, PlantConfig};

/// Height the payload frame must rise above its start to count as having flown, m.
const FLEW_HEIGHT: f32 = 0.1;

/// One sample of the flight for reports and figures, every [`SERIES_EVERY`] ticks.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FlightSample {
    /// Simulated time, s.
    pub t: f32,
    /// Each robot's rail position, m.
    pub rail: Vec<f32>,
    /// Each rotor's thrust, N.
    pub thrust: Vec<f32>,
    /// Roll and pitch, degrees.
    pub roll_pitch_deg: [f32; 2],
    /// Height above the start, m.
    pub height: f32,
    /// Horizontal position from the start (world x, y), m.
    pub xy: [f32; 2],
}

/// Ticks between two [`FlightSample`]s (100 Hz).
pub const SERIES_EVERY: u64 = 4;

/// An in-flight re-formation, as the plant saw it.
#[derive(Clone, Debug, PartialEq)]
pub struct Adaptation {
    /// When the shift was measured, s.
    pub t: f32,
    /// The COM measured, m.
    pub com: [f32; 2],
    /// The mass measured, kg.
    pub mass: f32,
    /// Where the robots went (empty if no formation could be had).
    pub positions: Vec<f32>,
    /// When they arrived, s (`None`: gave up or still moving).
    pub rebalanced_at: Option<f32>,
}

/// What the plant saw.
#[derive(Clone, Debug, Default)]
pub struct PlantRecord {
    /// Each phase entered and how long it lasted, s.
    pub phases: Vec<(String, f32)>,
    /// Each lift: group, reading (N, or `None` when it could not lift), model lift-off thrust
    /// for the truth (N).
    pub lifts: Vec<(usize, Option<f32>, f32)>,
    /// Roll or pitch exceeded 45 degrees.
    pub dropped: bool,
    /// Distance from the landing point at the end, m.
    pub final_position_error_m: f32,
    /// Whether the rotors were ever armed.
    pub armed: bool,
    /// Whether the payload rose [`FLEW_HEIGHT`] above its start.
    pub flew: bool,
    /// Thrust of every rotor at the end, N.
    pub final_thrusts: Vec<f32>,
    /// The robots' rail positions at the end, m.
    pub final_rail: Vec<f32>,
    /// The autopilot said the mission is over.
    pub over: bool,
    /// Control ticks.
    pub ticks: u64,
    /// Simulated time, s.
    pub simulated_s: f32,
    /// Largest roll or pitch while airborne (from take-off to the mission's end), degrees.
    pub max_tilt_deg: f32,
    /// Largest rotor command as a fraction of its maximum, from take-off to the end.
    pub max_thrust_fraction: f32,
    /// When the load shift began, s, if one was injected and happened.
    pub shift_at: Option<f32>,
    /// When the injected IMU fault began (its first faulty sample), s, if it happened.
    pub imu_fault_at: Option<f32>,
    /// Horizontal distance from where the payload was when the injected IMU fault began to
    /// where it ended, m.
    pub moved_after_imu_fault_m: Option<f32>,
    /// Each injected rotor stop that happened (or fade that began): robot (from 0),
    /// simulated time, s.
    pub rotors_stopped: Vec<(usize, f32)>,
    /// From the first rotor stop or fade on, each tick's time (s) and tilt (largest of roll
    /// and pitch, degrees).
    pub tilts_after_stop: Vec<(f32, f32)>,
    /// Horizontal distance from where the first injected rotor stopped to where the payload
    /// ended, m (the landing "where it is" measured).
    pub rotor_landing_offset_m: Option<f32>,
    /// When take-off began, s (simulated time), if it did.
    pub takeoff_at: Option<f32>,
    /// The DroneCAN bus's traffic (`--esc dronecan`): frames a second, share of 1 Mbit/s.
    pub can_bus_load: Option<(f32, f32)>,
    /// Each in-flight re-formation.
    pub adaptations: Vec<Adaptation>,
    /// The flight, sampled at 100 Hz from take-off.
    pub series: Vec<FlightSample>,
    /// What the supervision said, with when, s.
    pub notices: Vec<(f32, String)>,
    /// Why the start was refused, if it was.
    pub start_refused: Option<String>,
    /// When the simulated ground station stopped, s.
    pub gcs_lost_at: Option<f32>,
    /// When the pack's voltage dropped, s.
    pub battery_dropped_at: Option<f32>,
    /// Lowest pack voltage at the terminals, V.
    pub min_battery_volts: f32,
    /// Each time the sticks took over the payload (`true`) or let it go, s.
    pub steered: Vec<(f32, bool)>,
    /// When the stick script first sent the kill switch on, s.
    pub kill_sent_at: Option<f32>,
    /// The first tick from the kill switch's frame on whose every rotor command was zero, s.
    pub rotors_zero_at: Option<f32>,
}

/// Flies `autopilot` in the plant of `scenario`'s truth until its mission is over, the
/// payload drops or the time limit; `on_phase` sees each phase (time, name, reason), and
/// each notice of the supervision and a refused start (time, `notice` or `refused`, text).
pub fn fly(
    scenario: &Scenario,
    setup: &MissionSetup,
    autopilot: &mut dyn Autopilot,
    on_phase: &mut dyn FnMut(f32, &str, &str),
) -> Result<PlantRecord> {
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
        ..PlantConfig::MODEL
    });
    // The plant's departures from the model (`[plant]`, docs/formats.md#the-plant-section).
    setup.plant.apply(plant.config_mut(), setup.seed);
    plant.refresh();
    let mut sensors = Sensors::departed(setup.seed, &setup.plant, &plant);
    if let Some(bias) = setup.gyro_bias {
        sensors = sensors.with_gyro_bias(bias);
    }
    let dt = 1.0 / CONTROL_HZ as f32;
    let physics_per_tick = (dt / PHYSICS_DT).round() as usize;
    let n = robots.count();
    let start = plant.state().position;
    let limit = setup.time_limit.min(MISSION_TIME_LIMIT);
    let mut record = PlantRecord {
        final_thrusts: vec![0.0; n],
        final_rail: robots.initial.to_vec(),
        min_battery_volts: f32::INFINITY,
        ..PlantRecord::default()
    };
    let mut entered = 0.0f32;
    let mut mocap_lost_at = f32::INFINITY;
    let mut takeoff_at = f32::INFINITY;
    let mut next_command = 0usize;
    // The set-up's commands, one a tick: the rails confirmed (when asked for), the start.
    let mut setup_commands: Vec<OperatorCommand> = if setup.confirm_rails {
        vec![OperatorCommand::Start, OperatorCommand::ConfirmRails]
    } else {
        vec![OperatorCommand::Start]
    };
    let mut command = setup_commands.pop();
    let mut group = 0usize;
    let mut shift_from = truth.com;
    let mut stall = setup.stepper_stall.map(StepperStall::new);
    let mut faults = HardwareFaults::NONE;
    let mut last_imu: Option<ImuSample> = None;
    let mut imu_fault_position: Option<Vec3> = None;
    let mut frozen: Option<ImuSample> = None;
    let mut imu_noise = match setup.imu_fault.map(|f| f.kind) {
        Some(ImuFaultKind::Noise(x)) => Some(ImuNoise::new(setup.seed, x)),
        _ => None,
    };
    let mut dead = vec![false; n];
    let mut can_escs = (setup.esc == EscLink::Dronecan).then(|| DroneCanEscs::new(n));
    let mut stopped_over: Option<Vec3> = None;
    loop {
        let t = plant.time();
        if t >= limit {
            break;
        }
        if let Some(shift) = &setup.load_shift {
            let begin = takeoff_at + shift.after;
            if t >= begin && record.shift_at.is_none() {
                record.shift_at = Some(t);
                shift_from = plant.com();
            }
            let progress = ((t - begin) / LOAD_SHIFT_TIME).clamp(0.0, 1.0);
            if t >= begin && t <= begin + LOAD_SHIFT_TIME + dt {
                plant.set_com(shift_from + shift.offset * progress);
            }
        }
        for stop in &setup.rotors_out {
            let begin = takeoff_at + stop.after;
            if t < begin || dead.get(stop.robot).is_none_or(|&d| d) {
                continue;
            }
            if stop.fade > 0.0 {
                if !record.rotors_stopped.iter().any(|(r, _)| *r == stop.robot) {
                    record.rotors_stopped.push((stop.robot, t));
                    stopped_over.get_or_insert(plant.state().position);
                }
                plant.set_rotor_health(stop.robot, 1.0 - (t - begin) / stop.fade);
                continue;
            }
            dead[stop.robot] = true;
            plant.stop_rotor(stop.robot);
            record.rotors_stopped.push((stop.robot, t));
            stopped_over.get_or_insert(plant.state().position);
        }
        let truth_now = plant.state();
        sensors.hear_rotors(&plant);
        let mut imu = sensors.imu(&truth_now, dt);
        // The board's front end finds a saturated or stalled IMU (on the raw path).
        faults.imu = sensors.imu_fault().is_some();
        // A DroneCAN ESC gone silent, or saying it failed, is its rotor's failure.
        if let Some(escs) = &can_escs {
            faults.rotors_out = escs.failed();
        }
        if let Some(fault) = &setup.imu_fault {
            let begin = if fault.from_start {
                fault.after
            } else {
                takeoff_at + fault.after
            };
            if t >= begin {
                if record.imu_fault_at.is_none() {
                    record.imu_fault_at = Some(t);
                    imu_fault_position = Some(truth_now.position);
                }
                imu = match fault.kind {
                    ImuFaultKind::Stuck => *frozen.get_or_insert(last_imu.unwrap_or(imu)),
                    ImuFaultKind::Noise(_) => imu_noise.as_mut().map_or(imu, |n| n.add(imu)),
                };
            }
        }
        last_imu = Some(imu);
        let mocap = sensors
            .mocap(&truth_now, plant.time_us())
            .filter(|_| t < mocap_lost_at);
        if command.is_none() {
            command = setup_commands.pop();
        }
        // The stick script's frame, at its rate (times after take-off began; its first step
        // before it).
        let pilot = setup.pilot.as_ref().and_then(|script| {
            let every = (CONTROL_HZ as f32 / script.rate_hz).round().max(1.0) as u64;
            if !record.ticks.is_multiple_of(every) {
                return None;
            }
            let frame = script.frame_at(t - takeoff_at)?;
            if script.step_at(t - takeoff_at).kill && record.kill_sent_at.is_none() {
                record.kill_sent_at = Some(t);
            }
            Some(frame)
        });
        if command.is_none()
            && let Some(&(after, c)) = setup.commands.get(next_command)
            && t >= takeoff_at + after
        {
            command = Some(c);
            next_command += 1;
        }
        // The ground station: a heartbeat once a second from the first tick, until it is lost.
        let gcs_lost = setup
            .gcs_loss
            .is_some_and(|onset| onset.begun(t, takeoff_at));
        if gcs_lost && record.gcs_lost_at.is_none() {
            record.gcs_lost_at = Some(t);
        }
        let gcs_heartbeat = !gcs_lost && record.ticks.is_multiple_of(u64::from(CONTROL_HZ));
        // The pack: its open-circuit voltage, less the model pack's sag in proportion to the
        // thrust and the plant's sag beyond it (`[plant]` battery_sag).
        let open_circuit = match setup.battery_drop {
            Some(drop) if drop.onset.begun(t, takeoff_at) => {
                if record.battery_dropped_at.is_none() {
                    record.battery_dropped_at = Some(t);
                }
                drop.volts
            }
            _ => PACK_VOLTS,
        };
        let full = robots.max_thrust * n as f32;
        let load = record.final_thrusts.iter().sum::<f32>() / full.max(f32::MIN_POSITIVE);
        let battery_volts =
            (open_circuit - PACK_SAG_VOLTS * load.clamp(0.0, 1.0) - plant.battery_sag_volts())
                .max(0.0);
        record.min_battery_volts = record.min_battery_volts.min(battery_volts);
        let out = autopilot.step(&Sensed {
            time_us: plant.time_us(),
            imu,
            mocap,
            command: command.take(),
            faults,
            esc_rpm: if let Some(escs) = can_escs.as_mut() {
                let max = robots.max_thrust.max(f32::MIN_POSITIVE);
                let commands: Vec<f32> = record.final_thrusts.iter().map(|t| t / max).collect();
                let rpm: Vec<f32> = plant.rotor_rpm().collect();
                Some(escs.step(plant.time_us(), &commands, &rpm))
            } else {
                setup.esc_telemetry.then(|| {
                    let mut rpm = [f32::NAN; MAX_ROBOTS];
                    for (r, v) in rpm.iter_mut().zip(plant.rotor_rpm()) {
                        *r = v;
                    }
                    rpm
                })
            },
            gcs_heartbeat,
            gcs_lost,
            battery_volts,
            pilot,
        })?;
        record.ticks += 1;
        record.armed |= out.armed;
        record.flew |= start.z - truth_now.position.z > FLEW_HEIGHT;
        for event in &out.events {
            match event {
                Event::Phase { name, reason } => {
                    if name == "takeoff" && takeoff_at.is_infinite() {
                        plant.set_disturbance_peak(flight.disturbance_torque);
                        takeoff_at = t;
                        record.takeoff_at = Some(t);
                        if let Some(after) = setup.mocap_lost_after_takeoff {
                            mocap_lost_at = t + after;
                        }
                    }
                    on_phase(t, name, reason);
                    if let Some(last) = record.phases.last_mut() {
                        last.1 = t - entered;
                    }
                    record.phases.push((name.clone(), 0.0));
                    entered = t;
                }
                Event::PairChosen(g) => group = *g,
                Event::LiftRead(reading) => {
                    let model = model_lift(scenario, group).unwrap_or(f32::NAN);
                    record.lifts.push((group, *reading, model));
                }
                Event::Adapted(AdaptEvent::Shifted { com, mass }) => {
                    record.adaptations.push(Adaptation {
                        t,
                        com: [com.x, com.y],
                        mass: *mass,
                        positions: Vec::new(),
                        rebalanced_at: None,
                    });
                }
                Event::Adapted(AdaptEvent::Rebalanced) => {
                    if let Some(a) = record.adaptations.last_mut() {
                        a.positions = out.rail.iter().take(n).map(|&p| rail.wrap(p)).collect();
                        a.rebalanced_at = Some(t);
                    }
                }
                Event::Adapted(_) => {}
                Event::FormationChosen(target) => {
                    if let Some(stall) = &mut stall {
                        stall.formation_chosen(rail, &record.final_rail, target);
                    }
                }
                Event::Notice(text) => {
                    on_phase(t, "notice", text);
                    record.notices.push((t, text.clone()));
                }
                Event::Steered(on) => {
                    let what = if *on {
                        "Position: the sticks steer"
                    } else {
                        "the sticks no longer steer"
                    };
                    on_phase(t, "mode", what);
                    record.steered.push((t, *on));
                }
                Event::StartRefused(why) => {
                    on_phase(t, "refused", why);
                    record.start_refused = Some(why.clone());
                }
            }
        }
        if record.start_refused.is_some() {
            break;
        }
        let mut wanted: Vec<f32> = out.rail.iter().take(n).map(|&p| rail.wrap(p)).collect();
        if let Some(stall) = &mut stall
            && stall.hold(rail, &record.final_rail, &mut wanted)
        {
            faults.stalled_robots |= 1 << stall.robot;
        }
        if wanted.len() == n && wanted != record.final_rail {
            record.final_rail = wanted;
            plant.set_rotor_points(&rotor_points(&record.final_rail));
        }
        for (j, c) in record.final_thrusts.iter_mut().enumerate() {
            let fraction = if out.armed && !dead[j] {
                out.thrust.get(j).copied().unwrap_or(0.0)
            } else {
                0.0
            };
            *c = fraction.clamp(0.0, 1.0) * robots.max_thrust;
        }
        if record.kill_sent_at.is_some()
            && record.rotors_zero_at.is_none()
            && out.thrust.iter().all(|&f| f == 0.0)
        {
            record.rotors_zero_at = Some(t);
        }
        let euler = truth_now.attitude.to_euler();
        if t >= takeoff_at {
            let tilt = euler.x.abs().max(euler.y.abs()).to_degrees();
            record.max_tilt_deg = record.max_tilt_deg.max(tilt);
            if !record.rotors_stopped.is_empty() {
                record.tilts_after_stop.push((t, tilt));
            }
            let top = record.final_thrusts.iter().fold(0.0f32, |m, &c| m.max(c));
            record.max_thrust_fraction = record
                .max_thrust_fraction
                .max(top / robots.max_thrust.max(f32::MIN_POSITIVE));
            if record.ticks.is_multiple_of(SERIES_EVERY) {
                record.series.push(FlightSample {
                    t,
                    rail: record.final_rail.clone(),
                    thrust: record.final_thrusts.clone(),
                    roll_pitch_deg: [euler.x.to_degrees(), euler.y.to_degrees()],
                    height: start.z - truth_now.position.z,
                    xy: [
                        truth_now.position.x - start.x,
                        truth_now.position.y - start.y,
                    ],
                });
            }
        }
        if euler.x.abs().to_degrees() > DROP_TILT_DEG || euler.y.abs().to_degrees() > DROP_TILT_DEG
        {
            record.dropped = true;
            break;
        }
        if out.over {
            record.over = true;
            break;
        }
        for _ in 0..physics_per_tick {
            plant.step(&record.final_thrusts);
        }
    }
    let end = plant.time();
    if let Some(last) = record.phases.last_mut() {
        last.1 = end - entered;
    }
    let (x, y) = match &setup.route {
        Some(route) if !route.is_empty() => route.landing_point().unwrap_or((start.x, start.y)),
        _ => (flight.target[0], flight.target[1]),
    };
    let landing = Vec3::new(x, y, start.z);
    let end_position = plant.state().position;
    record.final_position_error_m = (end_position - landing).norm();
    record.moved_after_imu_fault_m = imu_fault_position.map(|p| {
        let d = end_position - p;
        d.x.hypot(d.y)
    });
    record.rotor_landing_offset_m = stopped_over.map(|p| {
        let d = end_position - p;
        d.x.hypot(d.y)
    });
    record.simulated_s = end;
    record.can_bus_load = can_escs.as_ref().map(DroneCanEscs::load);
    Ok(record)
}

/// The model's lift-off thrust per robot of lift group `group` for `scenario`'s truth, N
/// (`None` without a truth, or for a group the scenario does not have).
pub fn model_lift(scenario: &Scenario, group: usize) -> Option<f32> {
    let truth = scenario.truth?;
    let g = shared::estimation::groups::lift_group(scenario, group)?;
    shared::liftoff_thrust::lift_off_thrust(
        &scenario.payload.hull,
        truth.com,
        truth.mass,
        &g.rotor_points,
        scenario.robots.mass,
    )
}

/// An injected stepper stall: the robot stops once it has covered half of its move to the
/// formation (its move is one trapezoid in one direction, so half the travel is half the way).
#[derive(Clone, Copy, Debug)]
struct StepperStall {
    robot: usize,
    /// Its move's length along the rail going forward and going backward, m; set when the
    /// formation is chosen.
    gaps: Option<(f32, f32)>,
    /// Travel so far since the formation was chosen, signed, m.
    travelled: f32,
    /// Where it stopped.
    stopped_at: Option<f32>,
}

impl StepperStall {
    fn new(robot: usize) -> Self {
        Self {
            robot,
            gaps: None,
            travelled: 0.0,
            stopped_at: None,
        }
    }

    fn formation_chosen(&mut self, rail: &Rail, now: &[f32], target: &[f32]) {
        if let (Some(&from), Some(&to)) = (now.get(self.robot), target.get(self.robot)) {
            self.gaps = Some((rail.forward_gap(from, to), rail.forward_gap(to, from)));
        }
    }

    /// Holds the robot where it stalled (changing `wanted`); true once it has.
    fn hold(&mut self, rail: &Rail, now: &[f32], wanted: &mut [f32]) -> bool {
        let (Some((forward, backward)), Some(&from), Some(next)) =
            (self.gaps, now.get(self.robot), wanted.get_mut(self.robot))
        else {
            return false;
        };
        if self.stopped_at.is_none() {
            // One tick's move is short: the shorter way round is the way it went.
            let step = rail.forward_gap(from, *next);
            let step = if step > rail.perimeter() / 2.0 {
                step - rail.perimeter()
            } else {
                step
            };
            self.travelled += step;
            let gap = if self.travelled >= 0.0 {
                forward
            } else {
                backward
            };
            if gap > 0.0 && self.travelled.abs() >= gap / 2.0 {
                self.stopped_at = Some(from);
            }
        }
        match self.stopped_at {
            Some(at) => {
                *next = at;
                true
            }
            None => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square rail of perimeter 4 m.
    fn rail() -> Rail {
        Rail::new(&[
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ])
        .expect("a square")
    }

    /// Moves robot 1 of two from `from` by `step` per tick for `ticks` ticks with a stall
    /// injected; where it ends up.
    fn stall_run(from: f32, to: f32, step: f32, ticks: usize) -> (f32, bool) {
        let rail = rail();
        let mut stall = StepperStall::new(1);
        let mut now = vec![3.0, from];
        stall.formation_chosen(&rail, &now, &[3.0, to]);
        let mut stalled = false;
        for k in 1..=ticks {
            let mut wanted = vec![3.0, rail.wrap(from + step * k as f32)];
            stalled |= stall.hold(&rail, &now, &mut wanted);
            now = wanted;
        }
        (now[1], stalled)
    }

    #[test]
    fn a_stalled_stepper_stops_halfway() {
        // Forward 0.2 -> 0.6 in 1 cm steps: stops at 0.4.
        let (at, stalled) = stall_run(0.2, 0.6, 0.01, 40);
        assert!(stalled);
        assert!((at - 0.4).abs() < 0.011, "stopped at {at}");
        // Backward across the rail's start, 0.1 -> 3.7 (0.4 m back): stops at 3.9.
        let (at, stalled) = stall_run(0.1, 3.7, -0.01, 40);
        assert!(stalled);
        assert!((at - 3.9).abs() < 0.011, "stopped at {at}");
        // Short of halfway it keeps going.
        let (at, stalled) = stall_run(0.2, 0.6, 0.01, 15);
        assert!(!stalled);
        assert!((at - 0.35).abs() < 1e-4, "at {at}");
    }
}
