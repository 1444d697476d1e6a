//! `shared`'s mission flown in this process ([`InProcess`], the `mission` command): each tick
//! as the firmware's control step takes it, and [`run`], the plant loop around it summed up
//! as a [`MissionOutcome`].

use anyhow::{Result, anyhow};
use shared::control::imu_monitor::ImuFailure;
use shared::estimation::Measurement;
use shared::mission::{
    AbortReason, CommandRefusal, JobRequest, Mission, MissionConfig, MissionPlanner,
    OperatorCommand, Phase, Reason, Supervision, TickInput,
};
use shared::scenario::Scenario;

use super::{Adaptation, Autopilot, Commanded, Event, FlightSample, MissionSetup, Sensed, fly};
use crate::flight_log::LogFile;
use crate::hil::run::BATTERY_EVERY;
use crate::hil::session::carried_volts;

/// `shared`'s mission in this process: the tick side and the planner, each job run in line
/// and taken at its deadline tick, as the firmware takes it.
pub struct InProcess {
    mission: Mission,
    planner: MissionPlanner,
    max_thrust: f32,
    /// Every transition's reason, in order.
    pub reasons: Vec<Reason>,
    /// Every job asked for, in order.
    pub jobs: Vec<JobRequest>,
    /// Every refused start, in order.
    pub refusals: Vec<CommandRefusal>,
    /// Every operator command's reply, in order.
    pub replies: Vec<(OperatorCommand, Result<(), CommandRefusal>)>,
    /// The flight log being written, if one is.
    log: Option<LogFile>,
    /// The mission's configuration (its RC channel map reads a scripted receiver's frames).
    config: MissionConfig,
    /// The sticks steered the payload at the last tick.
    steered: bool,
    /// Steps taken, and the pack's voltage as the firmware holds it between two of the HIL
    /// plant's `BATTERY_STATUS` (sent every [`BATTERY_EVERY`] steps from the first).
    steps: u64,
    battery_volts: Option<f32>,
}

impl InProcess {
    /// The mission of `scenario` with `config`, idle.
    pub fn new(scenario: &Scenario, config: MissionConfig) -> Result<Self> {
        Ok(Self {
            mission: Mission::new(scenario, config),
            planner: MissionPlanner::new(scenario, config)
                .map_err(|e| anyhow!("the mission cannot start: {e}"))?,
            max_thrust: scenario.robots.max_thrust,
            reasons: Vec::new(),
            jobs: Vec::new(),
            refusals: Vec::new(),
            replies: Vec::new(),
            log: None,
            config,
            steered: false,
            steps: 0,
            battery_volts: None,
        })
    }

    /// The mission's tick side.
    pub fn mission(&self) -> &Mission {
        &self.mission
    }
}

impl Autopilot for InProcess {
    fn step(&mut self, sensed: &Sensed) -> Result<Commanded> {
        if self.steps.is_multiple_of(BATTERY_EVERY) {
            self.battery_volts = Some(carried_volts(sensed.battery_volts));
        }
        self.steps += 1;
        let input = TickInput {
            time_us: sensed.time_us,
            imu: sensed.imu,
            mocap: sensed.mocap,
            command: sensed.command,
            faults: sensed.faults,
            esc_rpm: sensed.esc_rpm,
            supervision: Supervision {
                gcs_heartbeat: sensed.gcs_heartbeat,
                battery_volts: self.battery_volts,
            },
            manual: crate::pilot_script::samples(sensed.pilot.as_ref(), &self.config),
        };
        let out = self.mission.step(&input);
        // Recorded as the firmware's control step records it: before a job's result is taken.
        if let Some(log) = &mut self.log {
            log.step(&input, &out, &self.mission);
        }
        if let Some(job) = &out.job {
            // The firmware runs it off the tick; its result is taken at its deadline tick
            // either way.
            self.mission.deliver(self.planner.run(job));
            self.jobs.push(job.clone());
        }
        let mut events = Vec::new();
        if let Some(tr) = out.transition {
            self.reasons.push(tr.reason);
            if tr.to == Phase::Rearranging
                && let Some(positions) = self.mission.formation()
            {
                events.push(Event::FormationChosen(positions.to_vec()));
            }
            events.push(Event::Phase {
                name: tr.to.name().to_string(),
                reason: tr.reason.to_string(),
            });
            match tr.reason {
                Reason::PairChosen { group, .. } => events.push(Event::PairChosen(group)),
                Reason::LiftRead(Measurement::Lifted { thrust }) => {
                    events.push(Event::LiftRead(Some(thrust)));
                }
                Reason::LiftRead(Measurement::CouldNotLift) => events.push(Event::LiftRead(None)),
                _ => {}
            }
        }
        if let Some(a) = out.adaptation {
            events.push(Event::Adapted(a));
        }
        if let Some(n) = out.notice {
            events.push(Event::Notice(n.to_string()));
        }
        let steered = self.mission.flight().is_some_and(|f| f.steered());
        if steered != self.steered {
            self.steered = steered;
            events.push(Event::Steered(steered));
        }
        if let Some(reply) = out.reply {
            self.replies.push((reply.command, reply.outcome));
        }
        if let Some(reply) = out.reply
            && reply.command == OperatorCommand::Start
            && let Err(why) = reply.outcome
        {
            self.refusals.push(why);
            events.push(Event::StartRefused(why.to_string()));
        }
        let n = out.robots.len();
        Ok(Commanded {
            // As the firmware sends them: fractions of the rotors' maximum.
            thrust: out.thrusts[..n]
                .iter()
                .map(|t| (t / self.max_thrust).clamp(0.0, 1.0))
                .collect(),
            rail: out.robots.to_vec(),
            armed: out.armed,
            events,
            over: matches!(out.phase, Phase::Disarmed | Phase::Aborted),
        })
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
    /// Landed at the target and disarmed, with no abort on the way.
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
    /// Where each robot is on the rail at the end, arc length, m.
    pub final_rail: Vec<f32>,
    /// Simulated time, s.
    pub simulated_s: f32,
    /// Control ticks.
    pub ticks: u64,
    /// Largest roll or pitch in flight, degrees.
    pub max_tilt_deg: f32,
    /// Largest rotor command in flight, fraction of the maximum.
    pub max_thrust_fraction: f32,
    /// When the injected load shift began, s.
    pub shift_at: Option<f32>,
    /// When the injected IMU fault began, s.
    pub imu_fault_at: Option<f32>,
    /// Horizontal distance from where the payload was when the IMU fault began to where it
    /// ended (landing in place: the landing error), m.
    pub moved_after_imu_fault_m: Option<f32>,
    /// What the mission's IMU monitor found after the start, and when, s.
    pub imu_detected: Option<(ImuFailure, f32)>,
    /// Each rotor stopped by injection (or whose fade began): robot (from 0), simulated
    /// time, s.
    pub rotors_stopped: Vec<(usize, f32)>,
    /// From the first rotor stop or fade on, each tick's time (s) and tilt (degrees).
    pub tilts_after_stop: Vec<(f32, f32)>,
    /// Horizontal distance from where the first injected rotor stopped to where the payload
    /// ended, m.
    pub rotor_landing_offset_m: Option<f32>,
    /// Each rotor the mission found stopped (by the monitor or its ESC): robot (from 0),
    /// simulated time, s.
    pub rotors_found: Vec<(usize, f32)>,
    /// Each in-flight re-formation.
    pub adaptations: Vec<Adaptation>,
    /// The flight sampled at 100 Hz.
    pub series: Vec<FlightSample>,
    /// What the supervision said (ground link, battery), with when, s.
    pub notices: Vec<(f32, String)>,
    /// Why the start was refused, if it was (the mission then never began).
    pub start_refused: Option<CommandRefusal>,
    /// When the simulated ground station stopped, s.
    pub gcs_lost_at: Option<f32>,
    /// When the pack's voltage dropped, s.
    pub battery_dropped_at: Option<f32>,
    /// Lowest pack voltage at the terminals, V.
    pub min_battery_volts: f32,
    /// Each time the sticks took over the payload (`true`) or let it go, s.
    pub steered: Vec<(f32, bool)>,
    /// When a stick script first sent the kill switch on, s.
    pub kill_sent_at: Option<f32>,
    /// The first tick from the kill switch's frame on whose every rotor command was zero, s.
    pub rotors_zero_at: Option<f32>,
    /// When take-off began, s, if it did.
    pub takeoff_at: Option<f32>,
    /// The DroneCAN bus's traffic (`--esc dronecan`): frames a second, share of 1 Mbit/s.
    pub can_bus_load: Option<(f32, f32)>,
}

/// A flight counts as delivered within this distance of the target, m.
pub const DELIVERY_RADIUS: f32 = 0.25;

/// Runs `shared`'s mission in this process; `on_phase` sees each phase (time, name, reason)
/// as it happens.
pub fn run(
    scenario: &Scenario,
    setup: &MissionSetup,
    on_phase: &mut dyn FnMut(f32, &str, &str),
) -> Result<(MissionOutcome, InProcess)> {
    // A stick script's switches mapped as `hil` sets them on the vehicle.
    let mut config = setup.config;
    if setup.pilot.is_some() {
        crate::pilot_script::PilotScript::configure(&mut config);
    }
    // DroneCAN ESCs are the vehicle's `ESC_PROTOCOL` 3, as `hil` would set it.
    if setup.esc == super::EscLink::Dronecan {
        config.hardware.esc_protocol = shared::mission::drives::ESC_PROTOCOL_DRONECAN;
    }
    let mut autopilot = InProcess::new(scenario, config)?;
    if let Some(route) = &setup.route {
        autopilot
            .mission
            .set_route(route)
            .map_err(|e| anyhow!("the route was refused: {e}"))?;
    }
    if let Some(path) = &setup.log {
        autopilot.log = Some(LogFile::create(
            path,
            &setup.config,
            scenario.robots.max_thrust,
        )?);
    }
    let record = fly(scenario, setup, &mut autopilot, on_phase)?;
    if let Some(log) = autopilot.log.take() {
        log.finish()?;
    }
    let mission = autopilot.mission();
    let delivered = mission.phase() == Phase::Disarmed
        && mission.abort_reason().is_none()
        && !record.dropped
        && record.final_position_error_m < DELIVERY_RADIUS;
    let outcome = MissionOutcome {
        estimate: mission.estimate().map(|e| e.theta),
        measurements: mission.measurements(),
        positions: mission.formation().map(|p| p.to_vec()),
        delivered,
        dropped: record.dropped,
        final_position_error_m: record.final_position_error_m,
        phases: record.phases,
        lifts: record.lifts,
        aborted: mission.abort_reason(),
        armed: record.armed,
        flew: record.flew,
        final_thrusts: record.final_thrusts,
        final_rail: record.final_rail,
        simulated_s: record.simulated_s,
        ticks: record.ticks,
        max_tilt_deg: record.max_tilt_deg,
        max_thrust_fraction: record.max_thrust_fraction,
        shift_at: record.shift_at,
        imu_fault_at: record.imu_fault_at,
        moved_after_imu_fault_m: record.moved_after_imu_fault_m,
        imu_detected: mission
            .imu_detection()
            .map(|d| (d.failure, d.time_us as f32 * 1e-6)),
        rotors_stopped: record.rotors_stopped,
        rotor_landing_offset_m: record.rotor_landing_offset_m,
        tilts_after_stop: record.tilts_after_stop,
        rotors_found: match (mission.flight(), record.takeoff_at) {
            (Some(flight), Some(takeoff)) => flight
                .rotors_lost()
                .iter()
                .map(|r| (usize::from(r.robot), takeoff + r.at))
                .collect(),
            _ => Vec::new(),
        },
        adaptations: record.adaptations,
        series: record.series,
        notices: record.notices,
        start_refused: autopilot.refusals.first().copied(),
        gcs_lost_at: record.gcs_lost_at,
        battery_dropped_at: record.battery_dropped_at,
        min_battery_volts: record.min_battery_volts,
        steered: record.steered,
        kill_sent_at: record.kill_sent_at,
        rotors_zero_at: record.rotors_zero_at,
        takeoff_at: record.takeoff_at,
        can_bus_load: record.can_bus_load,
    };
    Ok((outcome, autopilot))
}

impl MissionOutcome {
    /// When the mission named robot `robot`'s rotor (from 0) stopped, simulated time, s.
    pub fn named_at(&self, robot: usize) -> Option<f32> {
        self.rotors_found
            .iter()
            .find(|(r, _)| *r == robot)
            .map(|&(_, t)| t)
    }

    /// The largest tilt (degrees) from the first rotor stop or fade up to simulated time `t`.
    pub fn tilt_until(&self, t: f32) -> f32 {
        self.tilts_after_stop
            .iter()
            .take_while(|(at, _)| *at <= t)
            .fold(0.0f32, |m, (_, tilt)| m.max(*tilt))
    }
}
