//! The autonomous mission as the flight controller runs it at 400 Hz (docs/system.md#mission-phases):
//! pre-flight checks, the estimation loop (choose a pair, move the robots, ramp and read the
//! lift-off, update, check convergence), the formation decision with a thrust-margin check,
//! the rearrangement, arming and the flight, with the operator's commands at any time.
//!
//! This is the tick side: each [`Mission::step`] takes the IMU sample, a motion-capture fix
//! and an operator command if they came, and the time, and returns every rotor's thrust and
//! every robot's rail setpoint (the stepper drivers follow them with
//! [`crate::rail::stepper`] profiles). Nothing slow runs here: pair selection, the Bayes
//! update, the formation decision and the mixer are [`JobRequest`]s that the caller runs on
//! a [`crate::mission::MissionPlanner`] and hands back with [`Mission::deliver`]; the mission
//! takes each result exactly [`JobRequest::deadline_ticks`] after asking, while the rotors
//! hold what the phase needs (off on the ground).
//!
//! Every tick's IMU sample also goes through an [`ImuMonitor`]: a frozen or wildly noisy IMU,
//! like a fault the board's drivers report, stops the mission on the ground; in flight the
//! vehicle lands where it is, and with an IMU fault it navigates on motion capture alone
//! ([`Navigator::drop_imu`]).
//!
//! This file holds the mission's state: its construction, what it tells the caller, the jobs'
//! bookkeeping and the phase's entry. The tick's work is split by concern:
//!
//! - `tick`: the tick itself ([`Mission::step`]) and its dispatch to the phase's step.
//! - `commands`: the operator's commands and the route to fly.
//! - `estimation`: the estimation loop's phases, from the pre-flight checks to convergence.
//! - `flight`: the formation decision, the rearrangement, the flight and its adaptation.
//! - `supervision`: the ground link's and the battery's failsafes, and the rotors watched
//!   in flight.
//! - `manual`: the kill switch, the mode switch, Position mode's steering and manual control
//!   lost.
//! - `bench`: the bring-up commands on the ground.

use crate::control::imu_monitor::ImuMonitor;
use crate::control::navigator::Navigator;
use crate::control::trajectory::FlightPhase;
use crate::control::vector::Vec3;
use crate::estimation::Estimate;
use crate::flight::{AdaptEvent, Adapter, FlightStack, Route};
use crate::liftoff_detector::LiftoffDetector;
use crate::manual::Pilot;
use crate::mission::config::MissionConfig;
use crate::mission::jobs::{JobRequest, JobResult, LiftPlan, NO_SCENARIO};
use crate::mission::phases::{AbortReason, Phase, Reason, Transition};
use crate::mission::supervision::{BatteryLevel, BatteryMonitor, LinkMonitor, Notice};
use crate::rail::moves::{Positions, RailMove};
use crate::scenario::Scenario;
use crate::timing::{CONTROL_RATE_HZ, LoopMonitor, LoopStats};

mod bench;
mod commands;
mod estimation;
mod flight;
mod manual;
mod supervision;
mod tick;

pub use crate::mission::interface::{
    CommandRefusal, CommandReply, EscRpm, HardwareFaults, ImuDetection, OperatorCommand, TickInput,
    TickOutput,
};
use bench::Bench;
pub use bench::MARK_TOLERANCE;
pub use estimation::{SET_DOWN_CUT_TILT, SET_DOWN_TIME};

/// A job asked for and not yet taken.
#[derive(Clone, Debug)]
struct PendingJob {
    due: u64,
    result: Option<JobResult>,
    /// A mixer without rotors found stopped ([`JobRequest::MixerWithout`]): the flight takes
    /// it, not the estimation or the adaptation.
    mixer: bool,
}

/// The tick side of the mission.
#[derive(Clone, Debug)]
pub struct Mission {
    scenario: Scenario,
    config: MissionConfig,
    navigator: Navigator,
    clock: LoopMonitor,
    tick: u64,
    phase: Phase,
    phase_time: f32,
    robots: Positions,
    rail_move: Option<(RailMove, Positions)>,
    lift_plan: Option<LiftPlan>,
    lift: Option<LiftoffDetector>,
    /// The lifting pair's thrust when its lift was read, N: the set-down ramps down from it.
    set_down_from: f32,
    /// The body's down axis at rest before the lift, for the set-down's tilt; the set-down
    /// cut (`None`) once the payload tipped past [`estimation::SET_DOWN_CUT_TILT`].
    set_down_axis: Option<crate::control::vector::Vec3>,
    pending: Option<PendingJob>,
    outgoing: Option<JobRequest>,
    latest: Option<Estimate>,
    converged_in_a_row: u32,
    estimate: Option<Estimate>,
    formation: Option<Positions>,
    flight: Option<FlightStack>,
    adapter: Option<Adapter>,
    adaptation: Option<AdaptEvent>,
    /// Rotors found stopped, said once the full mixer without them flies (whether the rotors
    /// left hold the hover is that mixer's to tell).
    rotors_notice: Option<Notice>,
    abort: Option<AbortReason>,
    imu_monitor: ImuMonitor,
    imu_detection: Option<ImuDetection>,
    link: LinkMonitor,
    battery: BatteryMonitor,
    /// The rotors' commands raised for a pack that sags.
    compensation: crate::control::voltage_compensation::VoltageCompensation,
    /// Time left of the hold after the ground link was lost in flight, s.
    gcs_hold: Option<f32>,
    /// Notices that could not go out in their own tick (one goes out per tick; a tick makes
    /// at most three: the link's, the battery's, the rotors').
    notices: heapless::Deque<Notice, 4>,
    /// A ground station's route (docs/ground-link.md#missions); empty: the payload
    /// description's target is flown.
    route: Route,
    /// The route item the flight begins with (a set-current before the start).
    route_first: u8,
    /// A jump along the route asked for in flight, for the next tick.
    jump: Option<u8>,
    /// The operator holds the vehicle where it is in flight.
    held: bool,
    /// Where the flight took off (the geofence's centre), once built.
    home: Option<Vec3>,
    /// The geofence was breached in this flight (its action is taken once).
    fence_breached: bool,
    /// The flight was built in the last tick: arming begins in this one (the build and the
    /// phase's change, its report and log record, in one tick exceed the control step's
    /// budget).
    flight_built: bool,
    /// The bring-up side: the rails confirmed, a jog, a calibration, a motor test.
    bench: Bench,
    /// The person at the sticks: the source in force, the kill switch, the mode switch.
    pilot: Pilot,
    /// Position mode is asked for: the sticks steer in the air (after the take-off).
    position: bool,
    /// Time left of the hold after manual control was lost in Position mode, s.
    manual_hold: Option<f32>,
}

impl Mission {
    /// A mission for `scenario` with the robots at their initial positions, idle, the rail
    /// positions confirmed: the simulator places the robots there. (The flight controller
    /// starts [`Self::unloaded`]: its rails are confirmed by the operator.)
    pub fn new(scenario: &Scenario, config: MissionConfig) -> Self {
        let mut mission = Self::UNLOADED;
        mission.load(scenario, config);
        mission.bench.rails_confirmed = true;
        mission
    }

    /// A mission with no payload description, idle: a constant, so the flight controller can
    /// place it in a static; [`Self::load`] gives it its payload.
    pub const UNLOADED: Self = Self::unloaded();

    /// [`Self::UNLOADED`]; called at run time it builds the value field by field. A static
    /// initialised from the constant keeps the whole 18 KB value in the flight controller's
    /// flash (its few non-zero bytes put it in `.data`); built at start into a zeroed static
    /// it costs a few stores.
    #[inline(never)]
    pub const fn unloaded() -> Self {
        Self {
            scenario: NO_SCENARIO,
            config: MissionConfig::DEFAULT,
            navigator: Navigator::new(),
            clock: LoopMonitor::at_rate(CONTROL_RATE_HZ),
            tick: 0,
            phase: Phase::Idle,
            phase_time: 0.0,
            robots: Positions::new(),
            rail_move: None,
            lift_plan: None,
            lift: None,
            set_down_from: 0.0,
            set_down_axis: None,
            pending: None,
            outgoing: None,
            latest: None,
            converged_in_a_row: 0,
            estimate: None,
            formation: None,
            flight: None,
            adapter: None,
            adaptation: None,
            rotors_notice: None,
            abort: None,
            imu_monitor: ImuMonitor::new(),
            imu_detection: None,
            link: LinkMonitor::new(),
            battery: BatteryMonitor::new(),
            compensation: crate::control::voltage_compensation::VoltageCompensation::new(),
            gcs_hold: None,
            notices: heapless::Deque::new(),
            route: Route::EMPTY,
            route_first: 0,
            jump: None,
            held: false,
            home: None,
            fence_breached: false,
            flight_built: false,
            bench: Bench::IDLE,
            pilot: Pilot::new(&MissionConfig::DEFAULT.manual),
            position: false,
            manual_hold: None,
        }
    }

    /// In place: a fresh, idle mission for `scenario`, as [`Self::new`] builds it (the state
    /// estimate and the loop clock carry on). The robots are commanded to the description's
    /// start positions; whether their positions are known (confirmed) carries on too, since
    /// the steppers keep count of every move.
    pub fn load(&mut self, scenario: &Scenario, config: MissionConfig) {
        self.scenario.clone_from(scenario);
        self.reset(config);
    }

    /// [`Self::load`] with the description handed over, not copied (a copy of its
    /// fixed-capacity lists costs the flight controller's step some 2,000 instructions).
    pub fn load_owned(&mut self, scenario: Scenario, config: MissionConfig) {
        self.scenario = scenario;
        self.reset(config);
    }

    /// The rest of [`Self::load`], the description in place.
    fn reset(&mut self, config: MissionConfig) {
        self.bench.jog = None;
        self.bench.motor_test = None;
        self.config = config;
        self.phase = Phase::Idle;
        self.phase_time = 0.0;
        self.robots.clone_from(&self.scenario.robots.initial);
        self.rail_move = None;
        self.lift_plan = None;
        self.lift = None;
        self.pending = None;
        self.outgoing = None;
        self.latest = None;
        self.converged_in_a_row = 0;
        self.estimate = None;
        self.formation = None;
        self.flight = None;
        self.adapter = None;
        self.adaptation = None;
        self.rotors_notice = None;
        self.abort = None;
        self.imu_detection = None;
        self.navigator.restore_imu();
        self.gcs_hold = None;
        self.jump = None;
        self.held = false;
        self.home = None;
        self.fence_breached = false;
        self.flight_built = false;
        self.pilot.configure(&self.config.manual);
        self.position = false;
        self.manual_hold = None;
    }

    /// Whether the flight flies its plan: taking off, moving or hovering, not landing,
    /// nothing stopped.
    fn cruising(&self) -> bool {
        matches!(
            self.phase,
            Phase::Flying(FlightPhase::Takeoff | FlightPhase::Transit | FlightPhase::Hover)
        ) && self.abort.is_none()
            && self
                .flight
                .as_ref()
                .is_some_and(|f| f.landing_cause().is_none() && f.stopped().is_none())
    }

    /// Whether the mission is not running: idle, or ended (landed or stopped).
    fn not_running(&self) -> bool {
        matches!(self.phase, Phase::Idle | Phase::Disarmed | Phase::Aborted)
    }

    /// Holds the flight where it is while the operator or a lost ground link asks for it.
    fn apply_hold(&mut self) {
        let hold = self.held || self.gcs_hold.is_some() || self.manual_hold.is_some();
        if let Some(f) = self.flight.as_mut() {
            f.hold_position(hold);
        }
    }

    /// The phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The estimate once estimation has converged.
    pub fn estimate(&self) -> Option<Estimate> {
        self.estimate
    }

    /// The estimate after the latest lift's update (before and after convergence), once a
    /// lift's result has come back.
    pub fn latest_estimate(&self) -> Option<Estimate> {
        self.latest
    }

    /// Lifts taken so far (as far as the results have come back).
    pub fn measurements(&self) -> u32 {
        self.latest.map_or(0, |e| e.measurements)
    }

    /// The flight formation once chosen.
    pub fn formation(&self) -> Option<&Positions> {
        self.formation.as_ref()
    }

    /// The flight, once built.
    pub fn flight(&self) -> Option<&FlightStack> {
        self.flight.as_ref()
    }

    /// Why the mission aborted (or lands in place), if it did.
    pub fn abort_reason(&self) -> Option<AbortReason> {
        self.abort
    }

    /// The first IMU failure the monitor found after the start, and when (the mission stopped
    /// or landed for it unless it had already stopped or was landing for another reason).
    pub fn imu_detection(&self) -> Option<ImuDetection> {
        self.imu_detection
    }

    /// Whether the navigation has dropped the IMU (it failed in flight).
    pub fn imu_dropped(&self) -> bool {
        self.navigator.imu_dropped()
    }

    /// Whether the ground link is up (a ground station's heartbeat within `FS_GCS_LOSS_T`).
    pub fn link_up(&self) -> bool {
        self.link.up()
    }

    /// The filtered battery voltage, V, once one was read.
    pub fn battery_volts(&self) -> Option<f32> {
        self.battery.volts()
    }

    /// How the battery stands.
    pub fn battery_level(&self) -> BatteryLevel {
        self.battery.level()
    }

    /// Largest thrust of one robot's rotor, N (0 when unloaded).
    pub fn robot_max_thrust(&self) -> f32 {
        self.scenario.robots.max_thrust
    }

    /// Ticks stepped so far.
    pub fn ticks(&self) -> u64 {
        self.tick
    }

    /// Whether the next [`Self::step`] needs the pending job's result: the caller must
    /// [`Self::deliver`] it first (in lockstep it waits for it; in real time a missing result
    /// aborts the mission as [`AbortReason::JobOverrun`]).
    pub fn needs_result(&self) -> bool {
        self.pending
            .as_ref()
            .is_some_and(|p| p.result.is_none() && self.tick + 1 >= p.due)
    }

    /// Hands back the result of the pending job; `false` (and dropped) when no job is pending
    /// (for example after an abort).
    pub fn deliver(&mut self, result: JobResult) -> bool {
        match &mut self.pending {
            Some(p) if p.result.is_none() => {
                p.result = Some(result);
                true
            }
            _ => false,
        }
    }

    /// The loop's timing since the last call (periods, overruns).
    pub fn take_loop_stats(&mut self) -> LoopStats {
        self.clock.take_stats()
    }

    fn enter(&mut self, to: Phase, reason: Reason) -> Transition {
        // A flight built but not yet armed is armed only from the rearrangement.
        self.flight_built = false;
        let t = Transition {
            from: self.phase,
            to,
            reason,
        };
        // The first reason stands: a rotor found stopped in a landing for the pack says so
        // (its own transition and notice), and the mission still ended for the pack.
        if let Reason::Abort(why) = reason
            && self.abort.is_none()
        {
            self.abort = Some(why);
        }
        self.phase = to;
        self.phase_time = 0.0;
        t
    }

    fn abort(&mut self, why: AbortReason) -> Transition {
        self.pending = None;
        self.outgoing = None;
        self.lift = None;
        self.rail_move = None;
        self.enter(Phase::Aborted, Reason::Abort(why))
    }

    fn request(&mut self, job: JobRequest) {
        self.pending = Some(PendingJob {
            due: self.tick + u64::from(job.deadline_ticks()),
            result: None,
            mixer: matches!(job, JobRequest::MixerWithout { .. }),
        });
        self.outgoing = Some(job);
    }

    /// The pending job's result once its tick has come: `Ok(None)` before, `Err` when it is
    /// due and missing.
    fn take_result(&mut self) -> Result<Option<JobResult>, AbortReason> {
        let Some(p) = &mut self.pending else {
            return Ok(None);
        };
        if self.tick < p.due {
            return Ok(None);
        }
        let result = p.result.take().ok_or(AbortReason::JobOverrun)?;
        self.pending = None;
        Ok(Some(result))
    }

    /// Moves the robots along the planned move; true once they are there.
    fn follow_rail_move(&mut self) -> bool {
        let Some((mv, targets)) = self.rail_move.as_ref() else {
            return true;
        };
        if self.phase_time < mv.duration() {
            self.robots = mv.positions_at(&self.scenario.payload.rail, self.phase_time);
            return false;
        }
        self.robots = targets.clone();
        self.rail_move = None;
        true
    }
}
