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

use crate::control::imu_monitor::ImuMonitor;
use crate::control::navigator::{NavState, Navigator};
use crate::control::trajectory::FlightPhase;
use crate::control::vector::Vec3;
use crate::estimation::{Estimate, Status};
use crate::flight::{
    AdaptEvent, Adapter, CascadeSetpoints, EscTelemetry, FlightCommand, FlightEvent, FlightModel,
    FlightStack, FlightStop, LandingCause, Route,
};
use crate::geometry::Vec2;
use crate::liftoff_detector::{LiftState, LiftoffDetector};
use crate::math;
use crate::mission::config::MissionConfig;
use crate::mission::jobs::{JobRequest, JobResult, LiftPlan, NO_SCENARIO};
use crate::mission::phases::{AbortReason, Phase, Reason, Transition};
use crate::mission::supervision::{
    BatteryLevel, BatteryMonitor, GcsLossAction, LinkChange, LinkMonitor, LinkResponse, Notice,
};
use crate::rail::moves::{Positions, RailMove};
use crate::scenario::{GRAVITY, MAX_ROBOTS, Scenario};
use crate::timing::{CONTROL_RATE_HZ, LoopMonitor, LoopStats};

mod bench;

pub use crate::mission::interface::{
    CommandRefusal, CommandReply, EscRpm, HardwareFaults, ImuDetection, OperatorCommand, TickInput,
    TickOutput,
};
use bench::Bench;
pub use bench::MARK_TOLERANCE;

/// A job asked for and not yet taken.
#[derive(Clone, Debug)]
struct PendingJob {
    due: u64,
    result: Option<JobResult>,
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
    pending: Option<PendingJob>,
    outgoing: Option<JobRequest>,
    latest: Option<Estimate>,
    converged_in_a_row: u32,
    estimate: Option<Estimate>,
    formation: Option<Positions>,
    flight: Option<FlightStack>,
    adapter: Option<Adapter>,
    adaptation: Option<AdaptEvent>,
    abort: Option<AbortReason>,
    imu_monitor: ImuMonitor,
    imu_detection: Option<ImuDetection>,
    link: LinkMonitor,
    battery: BatteryMonitor,
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
    /// The flight was built in the last tick: arming begins in this one (the build and the
    /// phase's change, its report and log record, in one tick exceed the control step's
    /// budget).
    flight_built: bool,
    /// The bring-up side: the rails confirmed, a jog, a calibration, a motor test.
    bench: Bench,
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
            pending: None,
            outgoing: None,
            latest: None,
            converged_in_a_row: 0,
            estimate: None,
            formation: None,
            flight: None,
            adapter: None,
            adaptation: None,
            abort: None,
            imu_monitor: ImuMonitor::new(),
            imu_detection: None,
            link: LinkMonitor::new(),
            battery: BatteryMonitor::new(),
            gcs_hold: None,
            notices: heapless::Deque::new(),
            route: Route::EMPTY,
            route_first: 0,
            jump: None,
            held: false,
            flight_built: false,
            bench: Bench::IDLE,
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
        self.abort = None;
        self.imu_detection = None;
        self.navigator.restore_imu();
        self.gcs_hold = None;
        self.jump = None;
        self.held = false;
        self.flight_built = false;
    }

    /// Flies `route` instead of the payload description's target from the next start (an
    /// empty route: the target again). Refused while the mission runs.
    pub fn set_route(&mut self, route: &Route) -> Result<(), CommandRefusal> {
        if !self.not_running() {
            return Err(CommandRefusal::AlreadyStarted);
        }
        self.route.clone_from(route);
        self.route_first = 0;
        Ok(())
    }

    /// The route flown (empty: the payload description's target).
    pub fn route(&self) -> &Route {
        &self.route
    }

    /// Flies the route from item `item` on: before the start, the flight begins there; in
    /// flight, the vehicle goes there now from where it is. Refused without a route, for an
    /// item it does not have, once landing, or (before the start) for an item the vehicle
    /// cannot take off to.
    pub fn set_route_item(&mut self, item: u8) -> Result<(), CommandRefusal> {
        let first = usize::from(item);
        if first >= self.route.len() {
            return Err(CommandRefusal::NoRouteItem);
        }
        match self.phase {
            Phase::Flying(_) => {
                let landing = self
                    .flight
                    .as_ref()
                    .is_none_or(|f| f.landing_cause().is_some() || f.stopped().is_some());
                if landing || self.abort.is_some() {
                    return Err(CommandRefusal::Landing);
                }
                self.jump = Some(item);
            }
            _ if self.not_running() || self.flight.is_none() => {
                Route::new(&self.route.items()[first..])
                    .map_err(|_| CommandRefusal::NoRouteItem)?;
                self.route_first = item;
            }
            _ => return Err(CommandRefusal::AlreadyStarted),
        }
        Ok(())
    }

    /// The route's progress in flight: the item flown (the first one before the flight) and
    /// the last one reached; `None` without a route.
    pub fn route_progress(&self) -> Option<(u8, Option<u8>)> {
        if self.route.is_empty() {
            return None;
        }
        Some(
            self.flight
                .as_ref()
                .map_or((self.route_first, None), |f| f.route_progress()),
        )
    }

    /// Whether the operator holds the vehicle where it is (and it is not landing).
    pub fn held(&self) -> bool {
        self.held && self.flight.as_ref().is_some_and(|f| f.holding())
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

    fn not_running(&self) -> bool {
        matches!(self.phase, Phase::Idle | Phase::Disarmed | Phase::Aborted)
    }

    /// Holds the flight where it is while the operator or a lost ground link asks for it.
    fn apply_hold(&mut self) {
        let hold = self.held || self.gcs_hold.is_some();
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
        if let Reason::Abort(why) = reason {
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

    fn own_weight(&self) -> f32 {
        self.scenario.robots.mass * GRAVITY
    }

    /// One tick.
    pub fn step(&mut self, input: &TickInput) -> TickOutput {
        self.tick += 1;
        let dt = self.clock.step(input.time_us);
        self.phase_time += dt;
        // The calibrated offsets off the sample before anything reads it.
        let imu = self.config.sensors.correct(&input.imu);
        let imu_failure = self.imu_monitor.check(&imu);
        let started = !matches!(self.phase, Phase::Idle | Phase::Disarmed | Phase::Aborted);
        if let Some(failure) = imu_failure
            && started
            && self.imu_detection.is_none()
        {
            self.imu_detection = Some(ImuDetection {
                failure,
                time_us: input.time_us,
            });
        }
        if (imu_failure.is_some() || input.faults.imu) && matches!(self.phase, Phase::Flying(_)) {
            // From this sample on the IMU is not to be trusted: land on motion capture.
            self.navigator.drop_imu();
        }
        self.navigator.update(&imu, dt, input.time_us);
        // The fix after the sample: a fix is never newer than the tick it arrives in.
        if let Some(fix) = &input.mocap {
            self.navigator.motion_capture(fix);
        }
        let nav = self.navigator.state();
        let mut thrusts = [0.0f32; MAX_ROBOTS];
        let mut cascade = None;
        // The supervision first: a heartbeat in the start's own tick counts for it.
        let sup = self.config.supervision;
        let link_change = self.link.update(
            input.time_us,
            input.supervision.gcs_heartbeat,
            sup.gcs_timeout,
        );
        let battery_change = self
            .battery
            .update(input.supervision.battery_volts, dt, &sup);
        let mut notice = self.notices.pop_front();
        let (reply, mut transition) = match input.command {
            Some(c) => self.command(c),
            None => (None, None),
        };
        let mut supervision_landing = false;
        if transition.is_none() {
            let (t, landing, said) = self.supervise(link_change, battery_change, input.time_us, dt);
            transition = t;
            if let Some(why) = landing
                && self.abort.is_none()
            {
                self.abort = Some(why);
                supervision_landing = true;
            }
            for n in said.into_iter().flatten() {
                if notice.is_none() {
                    notice = Some(n);
                } else {
                    // Room for every tick's notices while one goes out per tick: the oldest
                    // is dropped only if ticks of three came faster than one a tick.
                    if self.notices.is_full() {
                        self.notices.pop_front();
                    }
                    let _ = self.notices.push_back(n);
                }
            }
        }
        let mut fault_landing = false;
        let fault = input
            .faults
            .reason(self.scenario.robots.count())
            .or(imu_failure.map(AbortReason::from));
        if transition.is_none()
            && let Some(why) = fault
        {
            match self.phase {
                Phase::Idle | Phase::Disarmed | Phase::Aborted => {}
                // In flight: land where it is, once (the reason is kept for the landing).
                Phase::Flying(_) => {
                    if self.abort.is_none() {
                        self.abort = Some(why);
                        fault_landing = true;
                    }
                }
                _ => transition = Some(self.abort(why)),
            }
        }
        if transition.is_none() {
            let flight_command = match input.command {
                Some(OperatorCommand::Kill) => Some(FlightCommand::Kill),
                Some(OperatorCommand::LandNow | OperatorCommand::Abort) => {
                    Some(FlightCommand::LandNow)
                }
                _ if fault_landing || supervision_landing => Some(FlightCommand::LandNow),
                _ => None,
            };
            transition = self.advance(&nav, dt, flight_command, &mut thrusts, &mut cascade);
        }
        if matches!(self.phase, Phase::Flying(_))
            && let Some(found) = self.watch_rotors(input, &nav, &thrusts, dt)
        {
            // Said this tick; the one it displaces goes out next.
            if let Some(other) = notice.replace(found) {
                if self.notices.is_full() {
                    self.notices.pop_back();
                }
                let _ = self.notices.push_front(other);
            }
        }
        let mut armed = matches!(
            self.phase,
            Phase::Lifting | Phase::Arming | Phase::Flying(_)
        );
        if !matches!(self.phase, Phase::Lifting | Phase::Flying(_)) {
            thrusts = [0.0; MAX_ROBOTS];
        }
        let stalled = input.faults.stalled_robots != 0;
        let mut calibrated = None;
        // Nothing on the bench in flight: one look.
        if stalled || self.bench_busy() {
            let spinning;
            (spinning, calibrated) = self.bench_step(&input.imu, dt, stalled, &mut thrusts);
            armed |= spinning;
        }
        if !matches!(self.phase, Phase::Flying(_)) {
            cascade = None;
        }
        TickOutput {
            thrusts,
            robots: self.robots.clone(),
            armed,
            phase: self.phase,
            transition,
            adaptation: self.adaptation.take(),
            job: self.outgoing.take(),
            reply,
            notice,
            calibrated,
            nav,
            cascade,
        }
    }

    /// What the ground link's and the battery's changes mean in this phase: a transition (on
    /// the ground after the start: stop), the reason of a landing in place to begin (in
    /// flight), and what to tell people.
    fn supervise(
        &mut self,
        link: Option<LinkChange>,
        battery: Option<BatteryLevel>,
        time_us: u64,
        dt: f32,
    ) -> (Option<Transition>, Option<AbortReason>, [Option<Notice>; 2]) {
        let sup = self.config.supervision;
        let on_ground = !matches!(
            self.phase,
            Phase::Idle | Phase::Disarmed | Phase::Aborted | Phase::Flying(_)
        );
        let cruising = self.cruising();
        let watched = sup.gcs_action != GcsLossAction::Off;
        let mut notices = [None, None];
        let mut landing = None;
        match link {
            Some(LinkChange::Lost) if watched => {
                if on_ground {
                    return (Some(self.abort(AbortReason::GcsLost)), None, notices);
                }
                let response = match sup.gcs_action {
                    _ if !cruising => LinkResponse::Nothing,
                    GcsLossAction::HoldThenLand => {
                        self.gcs_hold = Some(sup.gcs_hold_time);
                        self.apply_hold();
                        LinkResponse::Hold(sup.gcs_hold_time)
                    }
                    _ => LinkResponse::Continue,
                };
                notices[0] = Some(Notice::LinkLost {
                    silent: self.link.silence(time_us).unwrap_or(0.0),
                    response,
                });
            }
            Some(LinkChange::Regained) if watched => {
                let resumed = self.gcs_hold.take().is_some();
                self.apply_hold();
                notices[0] = Some(Notice::LinkRegained { resumed });
            }
            _ => {}
        }
        if let Some(left) = self.gcs_hold.as_mut() {
            *left -= dt;
            if *left <= 0.0 || !cruising {
                self.gcs_hold = None;
                self.apply_hold();
                if cruising {
                    landing = Some(AbortReason::GcsLost);
                }
            }
        }
        let volts = self.battery.volts().unwrap_or(0.0);
        match battery {
            Some(BatteryLevel::Low) if on_ground => {
                return (
                    Some(self.abort(AbortReason::BatteryLow { volts })),
                    None,
                    notices,
                );
            }
            Some(BatteryLevel::Critical) if on_ground => {
                return (
                    Some(self.abort(AbortReason::BatteryCritical { volts })),
                    None,
                    notices,
                );
            }
            Some(BatteryLevel::Critical) if cruising => {
                self.gcs_hold = None;
                self.held = false;
                self.apply_hold();
                landing = Some(AbortReason::BatteryCritical { volts });
            }
            Some(BatteryLevel::Critical) => {
                notices[1] = Some(Notice::BatteryCritical {
                    volts,
                    threshold: sup.battery_critical,
                });
            }
            Some(BatteryLevel::Low) => {
                notices[1] = Some(Notice::BatteryLow {
                    volts,
                    threshold: sup.battery_low,
                });
            }
            Some(BatteryLevel::Ok) | None => {}
        }
        (None, landing, notices)
    }

    /// The operator's command; the transition it makes on the ground, if any (in flight the
    /// flight stack carries it out).
    fn command(&mut self, command: OperatorCommand) -> (Option<CommandReply>, Option<Transition>) {
        // Mission mode asked for before the start: the start.
        let command = match command {
            OperatorCommand::Resume if self.phase == Phase::Idle => OperatorCommand::Start,
            other => other,
        };
        self.stop_motor_test_for(command);
        if command.is_bench() {
            let outcome = self.bench_command(command);
            return (Some(CommandReply { command, outcome }), None);
        }
        let finished = matches!(self.phase, Phase::Disarmed | Phase::Aborted);
        let flying = matches!(self.phase, Phase::Flying(_));
        let mut transition = None;
        let outcome = match command {
            OperatorCommand::Kill if finished => Ok(()),
            _ if finished => Err(CommandRefusal::Finished),
            OperatorCommand::Start if self.scenario.robots.count() == 0 => {
                Err(CommandRefusal::NoPayload)
            }
            // The pre-arm checks of the bench: the rails known, each robot on its mark,
            // nothing under way.
            OperatorCommand::Start if self.phase == Phase::Idle && self.rails_ready().is_err() => {
                Err(self
                    .rails_ready()
                    .err()
                    .unwrap_or(CommandRefusal::RailsUnconfirmed))
            }
            OperatorCommand::Start if self.phase == Phase::Idle && self.bench_busy() => {
                Err(CommandRefusal::BenchBusy)
            }
            OperatorCommand::Start
                if self.phase == Phase::Idle
                    && self.config.supervision.gcs_action != GcsLossAction::Off
                    && !self.link.up() =>
            {
                Err(CommandRefusal::NoGroundLink)
            }
            OperatorCommand::Start
                if self.phase == Phase::Idle
                    && self.battery.volts().is_some_and(|v| {
                        let low = self.config.supervision.battery_low;
                        let critical = self.config.supervision.battery_critical;
                        (low > 0.0 && v < low) || (critical > 0.0 && v < critical)
                    }) =>
            {
                let volts = self.battery.volts().unwrap_or(0.0);
                Err(CommandRefusal::BatteryLow {
                    millivolts: (volts * 1000.0) as u32,
                })
            }
            OperatorCommand::Start if self.phase == Phase::Idle => {
                // A pack changed since a low reading is graded afresh.
                self.battery.regrade(&self.config.supervision);
                transition = Some(self.enter(Phase::PreflightChecks, Reason::Started));
                Ok(())
            }
            OperatorCommand::Start | OperatorCommand::Resume if flying && self.held => {
                self.held = false;
                self.apply_hold();
                Ok(())
            }
            OperatorCommand::Start => Err(CommandRefusal::AlreadyStarted),
            // Mission mode asked for while the mission runs: it is in it already.
            OperatorCommand::Resume => Ok(()),
            OperatorCommand::Hold if !flying => Err(CommandRefusal::NotFlying),
            OperatorCommand::Hold => {
                let cruising = self.cruising();
                // A hold before the payload has left the ground would hold it there under
                // take-off thrust.
                let airborne = self.flight.as_ref().is_some_and(|f| f.airborne());
                if !airborne {
                    Err(CommandRefusal::NotFlying)
                } else if cruising {
                    self.held = true;
                    self.apply_hold();
                    Ok(())
                } else {
                    Err(CommandRefusal::Landing)
                }
            }
            OperatorCommand::LandNow if !flying => Err(CommandRefusal::NotFlying),
            OperatorCommand::Abort if flying => {
                self.abort = Some(AbortReason::OperatorAbort);
                Ok(())
            }
            OperatorCommand::Abort => {
                transition = Some(self.abort(AbortReason::OperatorAbort));
                Ok(())
            }
            OperatorCommand::Kill if !flying => {
                transition = Some(self.abort(AbortReason::Killed));
                Ok(())
            }
            OperatorCommand::Kill | OperatorCommand::LandNow => Ok(()),
            // Taken above.
            OperatorCommand::ConfirmRails
            | OperatorCommand::Jog { .. }
            | OperatorCommand::Calibrate(_)
            | OperatorCommand::MotorTest(_) => Ok(()),
        };
        (Some(CommandReply { command, outcome }), transition)
    }

    fn advance(
        &mut self,
        nav: &NavState,
        dt: f32,
        command: Option<FlightCommand>,
        thrusts: &mut [f32; MAX_ROBOTS],
        cascade: &mut Option<CascadeSetpoints>,
    ) -> Option<Transition> {
        let step = match self.phase {
            Phase::Idle | Phase::Disarmed | Phase::Aborted => Ok(None),
            Phase::PreflightChecks => Ok(self.checks(nav)),
            Phase::SelectingPair => self.selecting_pair(),
            Phase::MovingRobots => Ok(self.moving_to_lift()),
            Phase::Lifting => Ok(self.lifting(nav, dt, thrusts)),
            Phase::Relaxing => self.relaxing(),
            Phase::DecidingFormation => self.deciding_formation(),
            Phase::Rearranging => self.rearranging(nav),
            Phase::Arming => Ok((self.phase_time >= self.config.arm_time)
                .then(|| self.enter(Phase::Flying(FlightPhase::Takeoff), Reason::Armed))),
            Phase::Flying(_) => Ok(self.fly(nav, dt, command, thrusts, cascade)),
        };
        step.unwrap_or_else(|why| Some(self.abort(why)))
    }

    fn checks(&mut self, nav: &NavState) -> Option<Transition> {
        if self.phase_time < self.config.checks_time {
            return None;
        }
        let level = nav.level_cosine() > math::cos(0.17);
        if nav.position.valid && level {
            self.request(JobRequest::SelectPair {
                robots: self.robots.clone(),
            });
            Some(self.enter(Phase::SelectingPair, Reason::ChecksPassed))
        } else if self.phase_time > 5.0 * self.config.checks_time {
            Some(self.abort(AbortReason::SensorsNotReady))
        } else {
            None
        }
    }

    fn selecting_pair(&mut self) -> Result<Option<Transition>, AbortReason> {
        let Some(result) = self.take_result()? else {
            return Ok(None);
        };
        let JobResult::Pair(plan) = result else {
            return Err(AbortReason::JobOverrun);
        };
        let plan = plan?;
        let reason = Reason::PairChosen {
            group: plan.group,
            information: plan.information,
        };
        self.rail_move = Some((plan.rail_move.clone(), plan.targets.clone()));
        self.lift_plan = Some(plan);
        Ok(Some(self.enter(Phase::MovingRobots, reason)))
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

    fn moving_to_lift(&mut self) -> Option<Transition> {
        if !self.follow_rail_move() {
            return None;
        }
        self.lift = Some(LiftoffDetector::new(
            self.config.liftoff,
            self.own_weight(),
            self.scenario.robots.max_thrust,
        ));
        Some(self.enter(Phase::Lifting, Reason::RobotsInPlace))
    }

    fn lifting(
        &mut self,
        nav: &NavState,
        dt: f32,
        thrusts: &mut [f32; MAX_ROBOTS],
    ) -> Option<Transition> {
        let n = self.scenario.robots.count();
        let own = self.own_weight();
        thrusts[..n].iter_mut().for_each(|t| *t = own);
        let lift = self.lift.as_mut()?;
        let state = lift.step(nav.attitude.attitude, dt);
        let plan = self.lift_plan.as_ref()?;
        for &i in &plan.lifting {
            thrusts[i] = lift.pair_thrust();
        }
        let LiftState::Measured(reading) = state else {
            return None;
        };
        let group = plan.group;
        self.lift = None;
        self.request(JobRequest::Update { group, reading });
        Some(self.enter(Phase::Relaxing, Reason::LiftRead(reading)))
    }

    fn relaxing(&mut self) -> Result<Option<Transition>, AbortReason> {
        if let Some(result) = self.take_result()? {
            let JobResult::Updated(estimate) = result else {
                return Err(AbortReason::JobOverrun);
            };
            let estimate = estimate?;
            if let Status::OutsideGrid(why) = estimate.status {
                return Err(AbortReason::PayloadOutsideGrid(why));
            }
            self.converged_in_a_row = if estimate.status == Status::Converged {
                self.converged_in_a_row + 1
            } else {
                0
            };
            self.latest = Some(estimate);
        }
        if self.phase_time < self.config.relax_time || self.pending.is_some() {
            return Ok(None);
        }
        let Some(estimate) = self.latest else {
            return Ok(None);
        };
        let confirmed = self.converged_in_a_row >= self.config.confirmations;
        let transition = match estimate.status {
            Status::NotConverged => return Err(AbortReason::EstimationNotConverged),
            Status::OutsideGrid(why) => return Err(AbortReason::PayloadOutsideGrid(why)),
            Status::Converged if confirmed => {
                self.estimate = Some(estimate);
                self.request(JobRequest::DecideFormation {
                    robots: self.robots.clone(),
                });
                self.enter(Phase::DecidingFormation, Reason::Converged(estimate.theta))
            }
            Status::Converged | Status::Measuring => {
                self.request(JobRequest::SelectPair {
                    robots: self.robots.clone(),
                });
                self.enter(Phase::SelectingPair, Reason::NeedMoreLifts)
            }
        };
        Ok(Some(transition))
    }

    fn deciding_formation(&mut self) -> Result<Option<Transition>, AbortReason> {
        let Some(result) = self.take_result()? else {
            return Ok(None);
        };
        let JobResult::Formation(plan) = result else {
            return Err(AbortReason::JobOverrun);
        };
        let plan = plan?;
        self.formation = Some(plan.positions.clone());
        self.rail_move = Some((plan.rail_move, plan.positions));
        Ok(Some(self.enter(
            Phase::Rearranging,
            Reason::FormationChosen(plan.det),
        )))
    }

    fn rearranging(&mut self, nav: &NavState) -> Result<Option<Transition>, AbortReason> {
        if self.flight_built {
            return Ok(Some(self.enter(Phase::Arming, Reason::FlightReady)));
        }
        if self.rail_move.is_some() {
            if self.follow_rail_move() {
                self.request(JobRequest::BuildFlight {
                    robots: self.robots.clone(),
                });
            }
            return Ok(None);
        }
        let Some(result) = self.take_result()? else {
            return Ok(None);
        };
        let JobResult::Flight(model) = result else {
            return Err(AbortReason::JobOverrun);
        };
        let model = model?;
        let start = nav.position.position;
        // A route's flight: built for the payload description's target (or, without one, a
        // hover above the take-off point), then its plan filled with the route in place.
        let target = match self.scenario.flight {
            Some(f) => f.target,
            None if !self.route.is_empty() => [start.x, start.y, 0.0],
            None => return Err(AbortReason::NoFlightTarget),
        };
        let flight = self
            .flight
            .insert(FlightStack::new(self.config.flight, model, start, target));
        if !self.route.is_empty() {
            flight.follow_route(start, &self.route, usize::from(self.route_first));
        }
        self.adapter = self.estimate.map(|e| {
            let r = &self.scenario.robots;
            Adapter::new(
                self.config.adapt,
                Vec2::new(e.theta[0], e.theta[1]),
                e.theta[2],
                r.mass * r.count() as f32,
            )
        });
        self.flight_built = true;
        Ok(None)
    }

    fn fly(
        &mut self,
        nav: &NavState,
        dt: f32,
        command: Option<FlightCommand>,
        thrusts: &mut [f32; MAX_ROBOTS],
        cascade: &mut Option<CascadeSetpoints>,
    ) -> Option<Transition> {
        let flight = self.flight.as_mut()?;
        if let Some(item) = self.jump.take() {
            flight.follow_route(nav.position.position, &self.route, usize::from(item));
        }
        let out = flight.step(nav, command, dt);
        *cascade = out.cascade;
        let n = self.scenario.robots.count();
        thrusts[..n].copy_from_slice(&out.thrusts[..n]);
        if self.navigator.imu_dropped() {
            // Without the IMU the navigation predicts from what the rotors were told.
            let wrench = flight.mixer().wrench_of(&out.thrusts[..n]);
            let vehicle = flight.vehicle();
            let per = |torque: f32, inertia: f32| {
                if inertia > 0.0 { torque / inertia } else { 0.0 }
            };
            let i = vehicle.inertia;
            let alpha = Vec3::new(
                per(wrench.torque.x, i.x),
                per(wrench.torque.y, i.y),
                per(wrench.torque.z, i.z),
            );
            let force = Vec3::new(0.0, 0.0, -per(wrench.thrust, vehicle.mass));
            self.navigator.rotor_command(alpha, force);
        }
        self.adapt(nav, &out.thrusts[..n], dt);
        let event = out.event?;
        let (to, reason) = match event {
            FlightEvent::Advanced(phase) => (Phase::Flying(phase), Reason::PlanAdvanced),
            FlightEvent::Landing(cause) => {
                let reason = match cause {
                    LandingCause::PositionLost => Reason::Abort(AbortReason::PositionLost),
                    LandingCause::TrackingLost => Reason::Abort(AbortReason::TrackingLost),
                    LandingCause::RotorOut { robot } => {
                        Reason::Abort(AbortReason::RotorOut { robot })
                    }
                    LandingCause::Operator => match self.abort {
                        Some(
                            why @ (AbortReason::OperatorAbort
                            | AbortReason::ImuFault
                            | AbortReason::ImuStuck
                            | AbortReason::ImuNoisy
                            | AbortReason::RobotStalled { .. }
                            | AbortReason::GcsLost
                            | AbortReason::BatteryCritical { .. }),
                        ) => Reason::Abort(why),
                        _ => Reason::LandNow,
                    },
                };
                (Phase::Flying(FlightPhase::Land), reason)
            }
            FlightEvent::Stopped(FlightStop::Landed) => (Phase::Disarmed, Reason::Landed),
            FlightEvent::Stopped(FlightStop::TakeoffFailed { height }) => (
                Phase::Aborted,
                Reason::Abort(AbortReason::TakeoffFailed { height }),
            ),
            FlightEvent::Stopped(FlightStop::NoPosition) => {
                (Phase::Aborted, Reason::Abort(AbortReason::PositionLost))
            }
            // Landing asked for before the payload left the ground: the reason it was asked for.
            FlightEvent::Stopped(FlightStop::OperatorGrounded) => (
                Phase::Aborted,
                Reason::Abort(self.abort.unwrap_or(AbortReason::OperatorAbort)),
            ),
            FlightEvent::Stopped(FlightStop::Killed) => {
                (Phase::Aborted, Reason::Abort(AbortReason::Killed))
            }
        };
        Some(self.enter(to, reason))
    }

    /// After this tick's flight step: a rotor found stopped (or reported by its ESC) is flown
    /// without from the next tick and the flight lands; the formation is not re-solved for
    /// the rotors left (the adaptation gives up, a re-formation asked for is dropped).
    /// Says which rotors were found and whether the rotors left hold a level hover.
    fn watch_rotors(
        &mut self,
        input: &TickInput,
        nav: &NavState,
        thrusts: &[f32; MAX_ROBOTS],
        dt: f32,
    ) -> Option<Notice> {
        let flight = self.flight.as_mut()?;
        let n = self.scenario.robots.count();
        let reported = u16::from(input.faults.rotors_out);
        // A frozen or noisy IMU makes a residual no rotor caused: once it is found, only the
        // ESCs' word counts.
        let imu_trusted =
            !input.faults.imu && self.imu_detection.is_none() && !self.navigator.imu_dropped();
        let found = flight.watch_rotors(
            nav,
            input.imu.accel,
            &thrusts[..n],
            EscTelemetry {
                rpm: input.esc_rpm.as_ref().map(|r| &r[..n]),
                stopped: reported,
            },
            imu_trusted,
            dt,
        )?;
        if let Some(adapter) = self.adapter.as_mut() {
            adapter.give_up();
        }
        self.pending = None;
        Some(Notice::RotorsOut {
            newly: found.newly,
            earlier: found.out & !found.newly,
            left: found.left,
            holdable: found.holdable,
        })
    }

    /// The in-flight adaptation after this tick's flight step: measure in the hover, ask for a
    /// new formation when the load has shifted, take it at its deadline, move the robots and
    /// fly every tick with the mixer of where they are.
    fn adapt(&mut self, nav: &NavState, thrusts: &[f32], dt: f32) {
        let (Some(flight), Some(adapter)) = (self.flight.as_mut(), self.adapter.as_mut()) else {
            return;
        };
        let rail = &self.scenario.payload.rail;
        let mut event = None;
        if let Some((positions, arrived)) = adapter.move_step(rail, dt) {
            self.robots = positions;
            event = arrived;
            let (com, mass) = adapter.belief();
            // A layout the mixer cannot fly (it cannot happen between two balanced formations
            // of the same rail, but never on trust): keep the last mixer and stop adapting.
            match FlightModel::build(&self.scenario, &self.robots, com, mass, self.config.mixer) {
                Ok(model) => flight.set_model(model),
                Err(_) => {
                    adapter.give_up();
                    event = Some(AdaptEvent::GaveUp);
                }
            }
        } else if self.pending.is_some() {
            let taken = match &mut self.pending {
                Some(p) if self.tick >= p.due => {
                    let result = p.result.take();
                    self.pending = None;
                    Some(result)
                }
                _ => None,
            };
            if let Some(result) = taken {
                let solved = match result {
                    Some(JobResult::Reformed(Ok((positions, _det)))) => Some(positions),
                    _ => None,
                };
                event = Some(adapter.formation(
                    solved.as_ref(),
                    rail,
                    &self.robots,
                    self.scenario.robots.min_spacing,
                ));
            }
        } else if flight.airborne() && flight.landing_cause().is_none() {
            let phase = flight.phase();
            let cruising = matches!(phase, FlightPhase::Transit | FlightPhase::Hover);
            if cruising {
                let delivered = flight.mixer().wrench_of(thrusts);
                let hovering = phase == FlightPhase::Hover;
                if let Some(shifted) = adapter.observe(&delivered, nav, hovering, dt) {
                    if let AdaptEvent::Shifted { com, .. } = shifted {
                        let job = JobRequest::Reform {
                            robots: self.robots.clone(),
                            com,
                        };
                        self.pending = Some(PendingJob {
                            due: self.tick + u64::from(job.deadline_ticks()),
                            result: None,
                        });
                        self.outgoing = Some(job);
                    }
                    event = Some(shifted);
                }
            }
        }
        let holding = flight.landing_cause().is_none() && adapter.holds_hover();
        flight.hold_hover(holding);
        self.adaptation = event;
    }
}
