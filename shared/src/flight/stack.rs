//! One flight at 400 Hz (docs/system.md#flight): take-off, transit, hover and landing
//! with the cascade and the formation's mixer, from the moment the rotors may spin until they
//! stop again.
//!
//! The plan's segments advance on the vehicle's state, not on the clock alone: a segment ends
//! when its time is up *and* the vehicle is within [`FlightConfig::arrival_tolerance`] of its
//! end point (a landing segment ends on time; the land detector then decides). Nets, each an
//! event with its reason:
//! - take-off: if the payload has not left the ground after
//!   [`FlightConfig::takeoff_timeout`] seconds of a collective at or above the believed
//!   weight, the rotors stop ([`FlightStop::TakeoffFailed`]): a payload heavier than believed,
//!   or a formation that pivots it on an edge, never flies on the clock alone;
//! - a segment not reached [`FlightConfig::arrival_timeout`] seconds after its end: land where
//!   the vehicle is ([`LandingCause::TrackingLost`]);
//! - position lost in the air: never cut the rotors there; descend on velocity alone and stop
//!   the rotors once the descent from the last known height has reached the ground
//!   ([`LandingCause::PositionLost`]); lost on the ground: the rotors stop;
//! - touchdown: the land detector stops the rotors ([`FlightStop::Landed`]); a plan over for
//!   [`FlightConfig::touchdown_timeout`] near the ground stops them too;
//! - a rotor that stops in the air ([`FlightStack::watch_rotors`]: found by
//!   [`crate::flight::rotor_monitor`] or reported by its ESC): the mixer is rebuilt without
//!   it ([`Mixer::without`]: the others take the wrench, yaw given up first if they cannot
//!   fly every axis) and the vehicle lands at once straight below where it is
//!   ([`LandingCause::RotorOut`]). Straight below is the nearest safe point: the flight area
//!   is a clear floor (the take-off point and the target are on it), a vertical descent asks
//!   the least of the remaining rotors, and every metre flown on them is risk.
//!
//! Operator commands: [`FlightCommand::LandNow`] lands where the vehicle is (or stops the
//! rotors if it never left the ground); [`FlightCommand::Kill`] stops the rotors at once.

use super::rotor_findings::MAX_ROTORS_OUT;
pub use super::rotor_findings::{EscTelemetry, RotorFinding, RotorOut};
use crate::control::allocation::{Mixer, Saturation};
use crate::control::controller::{ControlInputs, FlightController};
use crate::control::land_detector::{Contact, LandDetector};
use crate::control::navigator::NavState;
use crate::control::params::ControlParams;
#[cfg(doc)]
use crate::control::trajectory::PlanSegment;
use crate::control::trajectory::{FlightPhase, FlightPlan, PlanLimits, Setpoint};
use crate::control::vector::{Quat, Vec3};
use crate::control::vehicle::VehicleModel;
use crate::flight::manual::{ManualSetpoint, ManualVelocity};
use crate::flight::model::FlightModel;
use crate::flight::rotor_monitor::RotorMonitor;
use crate::flight::route::Route;
use crate::geometry::Vec2;
use crate::math;
use crate::scenario::MAX_ROBOTS;

mod rotors;
use rotors::RotorsMixer;

/// Tuning of a flight beyond the cascade's gains.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlightConfig {
    /// The cascade's gains and limits.
    pub control: ControlParams,
    /// Speeds and hover time of the plan.
    pub plan: PlanLimits,
    /// Time on the ground with the collective at or above the believed weight after which the
    /// take-off counts as failed and the rotors stop, s.
    pub takeoff_timeout: f32,
    /// Distance from a segment's end point within which the vehicle has arrived, m.
    pub arrival_tolerance: f32,
    /// Time past a segment's planned end without arriving before the vehicle lands where it
    /// is, s.
    pub arrival_timeout: f32,
    /// Time after the plan's end, near the ground, after which the rotors stop even if the
    /// land detector has not seen the touchdown, s.
    pub touchdown_timeout: f32,
    /// Time past the expected touchdown of a descent without position before the rotors stop,
    /// s.
    pub failsafe_margin: f32,
    /// Whether the rotor monitor judges (its tuning is
    /// [`crate::flight::rotor_monitor::RotorMonitorConfig::DEFAULT`], kept in flash: every copy
    /// of this configuration is static RAM on the flight controller). Rotors their ESCs report
    /// stopped are heeded either way.
    pub watch_rotors: bool,
}

impl FlightConfig {
    /// The defaults.
    pub const DEFAULT: Self = Self {
        control: ControlParams::DEFAULT,
        plan: PlanLimits::DEFAULT,
        takeoff_timeout: 3.0,
        arrival_tolerance: 0.15,
        arrival_timeout: 10.0,
        touchdown_timeout: 5.0,
        failsafe_margin: 1.0,
        watch_rotors: true,
    };
}

impl Default for FlightConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// An operator's command to a flight.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlightCommand {
    /// Land where the vehicle is now.
    LandNow,
    /// Stop the rotors now, wherever the vehicle is (flight termination).
    Kill,
}

/// Why the flight switched to a landing where the vehicle is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LandingCause {
    /// The position estimate was lost in the air: descending on velocity alone.
    PositionLost,
    /// A segment's end was not reached in time.
    TrackingLost,
    /// The operator asked for it.
    Operator,
    /// A rotor stopped in the air: flying on the others.
    RotorOut {
        /// The robot whose rotor stopped, from 0.
        robot: u8,
    },
}

/// Why the rotors stopped: the flight is over.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FlightStop {
    /// Touchdown detected (or, descending without position, the descent's time is up).
    Landed,
    /// The payload did not leave the ground under take-off thrust.
    TakeoffFailed {
        /// Greatest height above the take-off point seen, m.
        height: f32,
    },
    /// No position estimate before the payload left the ground.
    NoPosition,
    /// The operator asked to land before the payload left the ground.
    OperatorGrounded,
    /// The operator stopped the rotors.
    Killed,
}

/// Something the flight did this tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FlightEvent {
    /// The plan moved on to this phase.
    Advanced(FlightPhase),
    /// The flight now lands where the vehicle is.
    Landing(LandingCause),
    /// The rotors stopped.
    Stopped(FlightStop),
}

/// What the cascade asked of the vehicle in one tick: the attitude and body-rate setpoints
/// beside the estimate, and the collective (docs/formats.md#flight-logs logs them as PX4's
/// `vehicle_attitude_setpoint` and `vehicle_rates_setpoint`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CascadeSetpoints {
    /// Attitude the vehicle should have, body to NED.
    pub attitude: Quat,
    /// Body rate the vehicle should have, rad/s (FRD).
    pub rate: Vec3,
    /// Collective thrust commanded, N.
    pub collective: f32,
}

/// What one tick of the flight commands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlightOutput {
    /// Thrust of each rotor, N (zero once stopped).
    pub thrusts: [f32; MAX_ROBOTS],
    /// Collective thrust commanded, N.
    pub collective: f32,
    /// What the allocation cut.
    pub saturation: Saturation,
    /// The setpoint followed.
    pub setpoint: Setpoint,
    /// The cascade's setpoints this tick (`None` once the rotors are stopped).
    pub cascade: Option<CascadeSetpoints>,
    /// The plan's phase after this tick.
    pub phase: FlightPhase,
    /// What happened this tick, if anything.
    pub event: Option<FlightEvent>,
}

/// The flight.
#[derive(Clone, Debug)]
pub struct FlightStack {
    config: FlightConfig,
    mixer: Mixer,
    controller: FlightController,
    /// Collective that holds the believed weight, N.
    weight: f32,
    plan: FlightPlan,
    segment: usize,
    segment_time: f32,
    phase: FlightPhase,
    land: LandDetector,
    saturation: Saturation,
    collective: f32,
    ground_z: f32,
    max_height: f32,
    clock: f32,
    thrust_on_ground: f32,
    after_plan: f32,
    failsafe_until: Option<f32>,
    landing: Option<LandingCause>,
    stopped: Option<FlightStop>,
    /// Hold the hover past its planned time (an in-flight adaptation is under way).
    hold_hover: bool,
    /// Hold where the plan is now, whatever its segment (the ground link is lost).
    hold_here: bool,
    /// The COM the mixer's torques are about, m.
    com: Vec2,
    /// The last route item reached ([`PlanSegment::ends_item`]), if any.
    reached: Option<u8>,
    monitor: RotorMonitor,
    /// Rotors found stopped, in order (the first [`MAX_ROTORS_OUT`]).
    rotors_lost: heapless::Vec<RotorOut, MAX_ROTORS_OUT>,
    /// A rotor found stopped whose landing has not begun yet.
    rotor_landing: Option<u8>,
    /// Where the mixer stands with the rotors found stopped.
    rotors_mixer: RotorsMixer,
    /// Position mode: the setpoint the sticks steer and what they ask this tick.
    manual: Option<(ManualSetpoint, ManualVelocity)>,
}

impl FlightStack {
    /// A flight of `model` from `start` (on the ground, NED) to `target` = [x, y, height
    /// above ground].
    pub fn new(config: FlightConfig, model: FlightModel, start: Vec3, target: [f32; 3]) -> Self {
        Self {
            config,
            weight: model.vehicle.hover_thrust(),
            controller: FlightController::new(config.control, model.vehicle),
            mixer: model.mixer,
            plan: FlightPlan::new(start, target, 0.0, config.plan),
            segment: 0,
            segment_time: 0.0,
            phase: FlightPhase::Takeoff,
            land: LandDetector::new(start.z, model.reach),
            saturation: Saturation::default(),
            collective: 0.0,
            ground_z: start.z,
            max_height: 0.0,
            clock: 0.0,
            thrust_on_ground: 0.0,
            after_plan: 0.0,
            failsafe_until: None,
            landing: None,
            stopped: None,
            hold_hover: false,
            hold_here: false,
            com: model.com,
            reached: None,
            monitor: RotorMonitor::new(),
            rotors_lost: heapless::Vec::new(),
            rotor_landing: None,
            rotors_mixer: RotorsMixer::Whole,
            manual: None,
        }
    }

    /// The mixer flown.
    pub fn mixer(&self) -> &Mixer {
        &self.mixer
    }

    /// The vehicle model flown (mass, inertia).
    pub fn vehicle(&self) -> &VehicleModel {
        self.controller.model()
    }

    /// Flies on with `model` (the robots moved, or the payload is believed otherwise): the
    /// mixer and the controller's vehicle model change, the controller's integrators and the
    /// plan carry on. Rotors found stopped stay out of the new mixer; the rotor monitor
    /// measures a rotor's fading from the new model on ([`RotorMonitor::model_changed`]).
    pub fn set_model(&mut self, model: FlightModel) {
        self.monitor.model_changed();
        self.weight = model.vehicle.hover_thrust();
        self.controller.set_model(model.vehicle);
        self.com = model.com;
        let out = self.monitor.out();
        self.mixer = model.mixer;
        if out != 0 {
            self.fly_without(out);
        }
    }

    /// Holds the hover past its planned time while `hold` is set (the plan then goes on from
    /// where it was).
    pub fn hold_hover(&mut self, hold: bool) {
        self.hold_hover = hold;
    }

    /// Holds where the plan is now while `hold` is set: the plan's clock stops and the
    /// setpoint stays at its point with no feed-forward (a take-off, a transit or a hover
    /// stops where it is; a landing goes on). The plan then goes on from there.
    pub fn hold_position(&mut self, hold: bool) {
        self.hold_here = hold;
    }

    /// Position mode (docs/manual-control.md#position-mode): with `Some`, the sticks' velocity
    /// steers the setpoint from this tick on (taken over where the setpoint is now), the plan
    /// stopped where it was; with `None` after it, the plan goes on from where the pilot left
    /// the vehicle ([`FlightPlan::resume_from`]). Refused (returns false) once stopped, before
    /// the payload has left the ground, or while landing without position or on a rotor
    /// that stopped; a landing for any other cause is the pilot's to take over.
    pub fn steer(&mut self, command: Option<ManualVelocity>, nav: &NavState) -> bool {
        let Some(command) = command else {
            if let Some((manual, _)) = self.manual.take() {
                let here = manual.setpoint().position;
                let limits = self.config.plan;
                self.plan.resume_from(self.segment, here, limits);
                self.segment = 0;
                self.segment_time = 0.0;
                self.after_plan = 0.0;
                self.phase = self.plan.segment(0).map_or(FlightPhase::Done, |s| s.phase);
            }
            return true;
        };
        let refused = self.stopped.is_some()
            || !self.land.airborne()
            || self.failsafe_until.is_some()
            || matches!(
                self.landing,
                Some(LandingCause::PositionLost | LandingCause::RotorOut { .. })
            )
            || self.rotor_landing.is_some();
        if refused {
            return false;
        }
        match self.manual.as_mut() {
            Some((_, now)) => *now = command,
            None => {
                let from = self.setpoint(nav);
                self.landing = None;
                self.manual = Some((ManualSetpoint::new(from), command));
            }
        }
        true
    }

    /// Whether the sticks steer the vehicle (Position mode, not landing for a rotor or without
    /// position).
    pub fn steered(&self) -> bool {
        self.manual.is_some() && self.landing.is_none() && self.stopped.is_none()
    }

    /// Whether the vehicle holds where it is ([`Self::hold_position`], and not landing).
    pub fn holding(&self) -> bool {
        self.hold_here
            && self.landing.is_none()
            && self
                .plan
                .segment(self.segment)
                .is_some_and(|s| s.phase != FlightPhase::Land)
    }

    /// The plan's phase.
    pub fn phase(&self) -> FlightPhase {
        self.phase
    }

    /// Why the rotors stopped, once they have.
    pub fn stopped(&self) -> Option<FlightStop> {
        self.stopped
    }

    /// Why the flight lands where it is, if it does.
    pub fn landing_cause(&self) -> Option<LandingCause> {
        self.landing
    }

    /// Whether the payload is flying (left the ground, not landed).
    pub fn airborne(&self) -> bool {
        self.land.airborne()
    }

    /// Greatest height above the take-off point so far, m.
    pub fn max_height(&self) -> f32 {
        self.max_height
    }

    /// The ground's NED height at the take-off point, m.
    pub fn ground_z(&self) -> f32 {
        self.ground_z
    }

    /// Time since the flight began, s.
    pub fn clock(&self) -> f32 {
        self.clock
    }

    /// The plan being followed.
    pub fn plan(&self) -> &FlightPlan {
        &self.plan
    }

    /// Flies `route` from item `first` on, from `here` (NED; the take-off point before the
    /// take-off, or in the air: a jump along the route), the plan filled in place
    /// ([`FlightPlan::fill_from_route`]); not once landing or stopped. Returns whether it
    /// was taken.
    pub fn follow_route(&mut self, here: Vec3, route: &Route, first: usize) -> bool {
        if self.landing.is_some() || self.stopped.is_some() {
            return false;
        }
        let limits = self.config.plan;
        self.plan
            .fill_from_route(here, self.ground_z, route, first, 0.0, limits);
        self.phase = self.plan.segment(0).map_or(FlightPhase::Done, |s| s.phase);
        self.segment = 0;
        self.segment_time = 0.0;
        self.after_plan = 0.0;
        true
    }

    /// The route item being flown (from 0; the last one once landing) and the last one
    /// reached, if any.
    pub fn route_progress(&self) -> (u8, Option<u8>) {
        let current = match self.plan.segment(self.segment) {
            Some(s) if self.landing.is_none() => s.item,
            _ => self.reached.unwrap_or(0),
        };
        (current.max(self.reached.unwrap_or(0)), self.reached)
    }

    fn stop(&mut self, why: FlightStop) -> Option<FlightEvent> {
        self.stopped = Some(why);
        Some(FlightEvent::Stopped(why))
    }

    fn begin_landing(&mut self, cause: LandingCause, nav: &NavState) -> Option<FlightEvent> {
        if self.landing.is_some() {
            return None;
        }
        self.landing = Some(cause);
        let yaw = match self.manual.take() {
            Some((manual, _)) => manual.setpoint().yaw,
            None => self.plan.settled().yaw,
        };
        let limits = self.config.plan;
        self.plan
            .fill_landing(nav.position.position, self.ground_z, yaw, limits);
        self.segment = 0;
        self.segment_time = 0.0;
        self.phase = FlightPhase::Land;
        Some(FlightEvent::Landing(cause))
    }

    /// One tick with the state estimate `nav`, an operator command if one came, `dt` seconds
    /// after the previous tick.
    pub fn step(
        &mut self,
        nav: &NavState,
        command: Option<FlightCommand>,
        dt: f32,
    ) -> FlightOutput {
        let event = if self.stopped.is_some() {
            None
        } else {
            self.clock += dt;
            self.leave_out_found();
            self.advance(nav, command, dt)
        };
        let setpoint = self.setpoint(nav);
        let mut out = FlightOutput {
            thrusts: [0.0; MAX_ROBOTS],
            collective: 0.0,
            saturation: Saturation::default(),
            setpoint,
            cascade: None,
            phase: self.phase,
            event,
        };
        if self.stopped.is_some() {
            self.collective = 0.0;
            return out;
        }
        let inputs = ControlInputs {
            setpoint,
            attitude: nav.attitude,
            position: nav.position,
            airborne: self.land.airborne(),
            saturation: self.saturation,
        };
        let command = self.controller.step(&inputs, dt);
        let allocation = self.mixer.allocate(&command.wrench);
        self.saturation = allocation.saturation;
        self.collective = command.wrench.thrust;
        let n = self.mixer.count();
        out.thrusts[..n].copy_from_slice(&allocation.thrusts[..n]);
        out.collective = self.collective;
        out.saturation = allocation.saturation;
        out.cascade = Some(CascadeSetpoints {
            attitude: command.attitude_setpoint,
            rate: command.rate_setpoint,
            collective: self.collective,
        });
        out
    }

    /// The nets, the plan's progress and the commands; the event of this tick.
    fn advance(
        &mut self,
        nav: &NavState,
        command: Option<FlightCommand>,
        dt: f32,
    ) -> Option<FlightEvent> {
        let height = nav.height_above(self.ground_z);
        self.max_height = math::max(self.max_height, height);
        match command {
            Some(FlightCommand::Kill) => return self.stop(FlightStop::Killed),
            Some(FlightCommand::LandNow) if !self.land.airborne() => {
                return self.stop(FlightStop::OperatorGrounded);
            }
            Some(FlightCommand::LandNow) => {
                if let Some(event) = self.begin_landing(LandingCause::Operator, nav) {
                    return Some(event);
                }
            }
            None => {}
        }
        if let Some(robot) = self.rotor_landing.take()
            && self.land.airborne()
            && self.failsafe_until.is_none()
        {
            self.landing = None;
            if let Some(event) = self.begin_landing(LandingCause::RotorOut { robot }, nav) {
                return Some(event);
            }
        }
        let position = nav.position;
        let steered_down = self
            .manual
            .as_ref()
            .is_some_and(|(_, command)| command.velocity.z > 0.0);
        let descending = matches!(self.phase, FlightPhase::Land | FlightPhase::Done)
            || self.landing.is_some()
            || steered_down;
        let contact = self.land.update(
            position.position,
            position.velocity,
            nav.sin2_tilt(),
            descending,
            dt,
        );
        if let Some(until) = self.failsafe_until {
            if self.clock >= until {
                return self.stop(FlightStop::Landed);
            }
            return None;
        }
        if contact == Contact::Landed {
            // A route's landing item is reached at its touchdown.
            if let Some(s) = self.plan.segment(self.segment)
                && s.phase == FlightPhase::Land
                && s.ends_item
                && self.landing.is_none()
            {
                self.reached = Some(s.item);
            }
            return self.stop(FlightStop::Landed);
        }
        if !position.valid {
            if contact == Contact::OnGround {
                return self.stop(FlightStop::NoPosition);
            }
            let descent = math::max(self.config.plan.descent_speed, 0.05);
            self.failsafe_until =
                Some(self.clock + math::max(height, 0.0) / descent + self.config.failsafe_margin);
            self.landing = None;
            return self.begin_landing(LandingCause::PositionLost, nav);
        }
        if contact == Contact::OnGround && self.phase == FlightPhase::Takeoff {
            if self.collective >= 0.95 * self.weight {
                self.thrust_on_ground += dt;
            }
            if self.thrust_on_ground >= self.config.takeoff_timeout {
                return self.stop(FlightStop::TakeoffFailed {
                    height: self.max_height,
                });
            }
        }
        if let Some((manual, command)) = self.manual.as_mut() {
            manual.step(command, position.position, self.ground_z, dt);
            return None;
        }
        self.walk_plan(nav, dt)
    }

    /// Moves along the plan: a segment ends when its time is up and the vehicle is there.
    fn walk_plan(&mut self, nav: &NavState, dt: f32) -> Option<FlightEvent> {
        let Some(segment) = self.plan.segment(self.segment).copied() else {
            self.after_plan += dt;
            if self.after_plan < self.config.touchdown_timeout {
                return None;
            }
            let near_ground = !self.land.clear_of_ground(
                nav.position.position,
                nav.sin2_tilt(),
                3.0 * LandDetector::LAND_HEIGHT,
            );
            return if near_ground {
                self.stop(FlightStop::Landed)
            } else {
                self.after_plan = 0.0;
                self.landing = None;
                self.begin_landing(LandingCause::TrackingLost, nav)
            };
        };
        if self.holding() {
            return None;
        }
        self.segment_time += dt;
        if self.hold_hover && segment.phase == FlightPhase::Hover && self.landing.is_none() {
            self.segment_time = math::min(self.segment_time, segment.duration);
            return None;
        }
        if self.segment_time < segment.duration {
            return None;
        }
        let arrived = segment.phase == FlightPhase::Land
            || (nav.position.position - segment.to).norm() <= self.config.arrival_tolerance;
        if arrived {
            if segment.ends_item && self.landing.is_none() {
                self.reached = Some(segment.item);
            }
            self.segment += 1;
            self.segment_time = 0.0;
            self.phase = self
                .plan
                .segment(self.segment)
                .map_or(FlightPhase::Done, |s| s.phase);
            return Some(FlightEvent::Advanced(self.phase));
        }
        let late = self.segment_time > segment.duration + self.config.arrival_timeout;
        if late && self.land.airborne() {
            return self.begin_landing(LandingCause::TrackingLost, nav);
        }
        None
    }

    /// What the cascade follows now.
    fn setpoint(&self, nav: &NavState) -> Setpoint {
        if let Some((manual, _)) = &self.manual
            && self.failsafe_until.is_none()
        {
            return manual.setpoint();
        }
        let mut planned = match self.plan.segment(self.segment) {
            Some(segment) => segment.sample(self.segment_time),
            None => self.plan.settled(),
        };
        if self.holding() {
            planned.velocity = Vec3::ZERO;
            planned.acceleration = Vec3::ZERO;
        }
        if self.failsafe_until.is_some() {
            // Without position, hold a descent rate; the position loop's error stays zero.
            return Setpoint {
                position: nav.position.position,
                velocity: Vec3::new(0.0, 0.0, self.config.plan.descent_speed),
                acceleration: Vec3::ZERO,
                yaw: planned.yaw,
            };
        }
        planned
    }
}
