//! The autonomous mission as the flight controller runs it at 400 Hz (SPEC.md section 2):
//! pre-flight checks, the estimation loop (choose a pair, move the robots, ramp and read the
//! lift-off, update, check convergence), the formation decision with a thrust-margin check,
//! the rearrangement, arming, take-off, trajectory, hover, landing and disarm.
//!
//! Each step takes the sensor readings and returns every rotor's thrust and every robot's rail
//! setpoint (the stepper drivers follow them with [`crate::rail::stepper`] profiles). It calls
//! the crate's estimators, estimation, formation, rail, lift-off and control pieces; nothing
//! else decides.

use heapless::Vec;

use crate::control::allocation::{Mixer, MixerKind, RotorLayout, Saturation};
use crate::control::attitude_estimator::{AttitudeEstimator, AttitudeEstimatorGains};
use crate::control::controller::{ControlInputs, FlightController};
use crate::control::land_detector::{Contact, LandDetector};
use crate::control::params::ControlParams;
use crate::control::position_estimator::{PositionEstimator, PositionEstimatorGains};
use crate::control::trajectory::{FlightPhase, FlightPlan, PlanLimits};
use crate::control::vector::{Quat, Vec3};
use crate::control::vehicle::VehicleModel;
use crate::estimation::groups::lift_group;
use crate::estimation::{Estimate, Estimator, EstimatorOptions, Status};
use crate::formation::{FormationProblem, solve};
use crate::geometry::Vec2;
use crate::liftoff::{LiftState, LiftoffConfig, LiftoffDetector};
use crate::math;
use crate::mission::phases::{AbortReason, Phase, Reason, Transition};
use crate::rail::moves::{Positions, RailMove, lift_targets};
use crate::rail::stepper::MotionLimits;
use crate::scenario::{GRAVITY, MAX_ROBOTS, Scenario};

/// Default standard deviation of a lift reading, N (see [`MissionConfig::lift_noise_sigma`]).
pub const DETECTOR_SIGMA: f32 = 0.5;

/// Everything the mission may be tuned with beyond the scenario.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MissionConfig {
    /// Estimator options (the thrust-scale bias term).
    pub estimator: EstimatorOptions,
    /// Standard deviation of a lift reading from this vehicle's detector, N: the estimator's
    /// noise model for the lifts. `None` uses the scenario's `noise_sigma` (the paper's
    /// simulated measurement noise). A real vehicle sets it from bench lifts of a known load.
    /// The default, 0.5 N, bounds what the detector showed in the simulated vehicle: 63 lifts
    /// over 18 missions read the model's lift-off with an RMS error of 0.14 N, worst 0.77 N.
    pub lift_noise_sigma: Option<f32>,
    /// Lift-off detection.
    pub liftoff: LiftoffConfig,
    /// Rail motion limits.
    pub rail_limits: MotionLimits,
    /// Flight control gains.
    pub control: ControlParams,
    /// Mixer for the flight.
    pub mixer: MixerKind,
    /// Reference trajectory limits.
    pub plan: PlanLimits,
    /// Largest share of the rotors' total thrust the heaviest plausible payload (the
    /// posterior's 95 % upper bound on the mass) may need to hover; above it the mission
    /// refuses to take off.
    pub max_hover_fraction: f32,
    /// Time on the ground, rotors off, before the estimation starts (the attitude estimator
    /// learns the gyro bias meanwhile), s.
    pub checks_time: f32,
    /// Time with rotors off after each lift, s.
    pub relax_time: f32,
    /// Consecutive lifts after which the stopping rule must hold before the estimate is taken
    /// (1: the paper's rule; 2: one confirmation lift after it first holds).
    pub confirmations: u32,
    /// Time armed on the ground before take-off, s.
    pub arm_time: f32,
}

impl Default for MissionConfig {
    fn default() -> Self {
        Self {
            estimator: EstimatorOptions::default(),
            lift_noise_sigma: Some(DETECTOR_SIGMA),
            liftoff: LiftoffConfig::default(),
            rail_limits: MotionLimits::default(),
            control: ControlParams::default(),
            mixer: MixerKind::EqualSplit,
            plan: PlanLimits::default(),
            max_hover_fraction: 0.7,
            checks_time: 5.0,
            relax_time: 2.0,
            confirmations: 1,
            arm_time: 1.0,
        }
    }
}

/// One IMU sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuReading {
    /// Body rate, rad/s.
    pub gyro: Vec3,
    /// Specific force, body frame, m/s^2.
    pub accel: Vec3,
}

/// What the mission commands for one tick.
#[derive(Clone, Debug, PartialEq)]
pub struct MissionOutputs {
    /// Thrust of each robot's rotor, N (commanded units).
    pub thrusts: [f32; MAX_ROBOTS],
    /// Where each robot should be on the rail now (arc lengths).
    pub robots: Positions,
    /// The phase after this tick.
    pub phase: Phase,
    /// The transition this tick made, if any.
    pub transition: Option<Transition>,
    /// The attitude estimate (for telemetry).
    pub attitude: Quat,
}

/// The flight part, built once the formation is known.
#[derive(Clone, Debug)]
struct Flight {
    mixer: Mixer,
    controller: FlightController,
    plan: FlightPlan,
    land: LandDetector,
    saturation: Saturation,
    /// Height of the ground (NED z) the flight took off from.
    ground_z: f32,
    /// The position was lost: descending on velocity alone until this flight-clock time, s.
    failsafe_until: Option<f32>,
}

/// Failsafe: time past the expected touchdown before the rotors stop, s.
const FAILSAFE_MARGIN: f32 = 1.0;

/// The mission.
#[derive(Clone, Debug)]
pub struct Mission {
    scenario: Scenario,
    config: MissionConfig,
    estimator: Estimator,
    attitude: AttitudeEstimator,
    position: PositionEstimator,
    phase: Phase,
    phase_time: f32,
    robots: Positions,
    rail_move: Option<(RailMove, Positions)>,
    group: usize,
    pair_robots: Vec<usize, MAX_ROBOTS>,
    lift: Option<LiftoffDetector>,
    last_status: Status,
    converged_in_a_row: u32,
    estimate: Option<Estimate>,
    formation: Option<Positions>,
    flight: Option<Flight>,
    abort: Option<AbortReason>,
    /// Time since take-off began (runs across the flight's phases), s.
    flight_clock: f32,
}

impl Mission {
    /// A mission for `scenario` with the robots at their initial positions.
    pub fn new(scenario: &Scenario, config: MissionConfig) -> Result<Self, AbortReason> {
        let mut measured = scenario.clone();
        if let Some(sigma) = config.lift_noise_sigma {
            if !(sigma.is_finite() && sigma > 0.0) {
                return Err(AbortReason::EstimationFailed);
            }
            measured.estimation.noise_sigma = sigma;
        }
        let estimator = Estimator::new(&measured, config.estimator)
            .map_err(|_| AbortReason::EstimationFailed)?;
        Ok(Self {
            scenario: scenario.clone(),
            config,
            estimator,
            attitude: AttitudeEstimator::new(AttitudeEstimatorGains::default()),
            position: PositionEstimator::new(PositionEstimatorGains::default()),
            phase: Phase::Idle,
            phase_time: 0.0,
            robots: scenario.robots.initial.clone(),
            rail_move: None,
            group: 0,
            pair_robots: Vec::new(),
            lift: None,
            last_status: Status::Measuring,
            converged_in_a_row: 0,
            estimate: None,
            formation: None,
            flight: None,
            abort: None,
            flight_clock: 0.0,
        })
    }

    /// The phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The estimate once estimation has converged.
    pub fn estimate(&self) -> Option<Estimate> {
        self.estimate
    }

    /// Lifts taken so far.
    pub fn measurements(&self) -> u32 {
        self.estimator.estimate().measurements
    }

    /// The flight formation once chosen.
    pub fn formation(&self) -> Option<&Positions> {
        self.formation.as_ref()
    }

    /// Why the mission aborted, if it did.
    pub fn abort_reason(&self) -> Option<AbortReason> {
        self.abort
    }

    /// A motion-capture fix of the payload frame (NED position, attitude) taken at `stamp_us`.
    pub fn motion_capture(&mut self, position: Vec3, attitude: Quat, stamp_us: u64) {
        self.attitude.set_reference(attitude, stamp_us);
        self.position.correct(position, stamp_us);
    }

    /// Starts the mission (from idle).
    pub fn start(&mut self) -> Option<Transition> {
        (self.phase == Phase::Idle).then(|| self.enter(Phase::PreflightChecks, Reason::Started))
    }

    fn enter(&mut self, to: Phase, reason: Reason) -> Transition {
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
        self.enter(Phase::Aborted, Reason::Abort(why))
    }

    fn own_weight(&self) -> f32 {
        self.scenario.robots.mass * GRAVITY
    }

    /// One tick at `now_us` with an IMU sample; `dt` seconds since the previous tick.
    pub fn step(&mut self, imu: ImuReading, now_us: u64, dt: f32) -> MissionOutputs {
        self.phase_time += dt;
        let a = self.attitude.update(imu.gyro, imu.accel, dt, now_us);
        self.position.predict(
            a.attitude.rotate(imu.accel) + Vec3::DOWN * GRAVITY,
            dt,
            now_us,
        );
        let mut thrusts = [0.0f32; MAX_ROBOTS];
        let n = self.scenario.robots.count();
        let transition = match self.phase {
            Phase::Idle | Phase::Disarmed | Phase::Aborted => None,
            Phase::PreflightChecks => self.checks(a.attitude),
            Phase::SelectingPair => Some(self.select_pair()),
            Phase::MovingRobots | Phase::Rearranging => self.move_robots(),
            Phase::Lifting => self.lifting(a.attitude, dt, &mut thrusts),
            Phase::Relaxing => self.relaxing(),
            Phase::DecidingFormation => Some(self.decide_formation()),
            Phase::Arming => (self.phase_time >= self.config.arm_time)
                .then(|| self.enter(Phase::Flying(FlightPhase::Takeoff), Reason::Armed)),
            Phase::Flying(_) => self.fly(a, dt, &mut thrusts),
        };
        if !matches!(self.phase, Phase::Lifting | Phase::Flying(_)) {
            thrusts[..n].iter_mut().for_each(|t| *t = 0.0);
        }
        MissionOutputs {
            thrusts,
            robots: self.robots.clone(),
            phase: self.phase,
            transition,
            attitude: a.attitude,
        }
    }

    fn checks(&mut self, attitude: Quat) -> Option<Transition> {
        if self.phase_time < self.config.checks_time {
            return None;
        }
        let level = attitude.rotate(Vec3::DOWN).z > math::cos(0.17);
        if self.position.state().valid && level {
            Some(self.enter(Phase::SelectingPair, Reason::ChecksPassed))
        } else if self.phase_time > 5.0 * self.config.checks_time {
            Some(self.abort(AbortReason::SensorsNotReady))
        } else {
            None
        }
    }

    fn select_pair(&mut self) -> Transition {
        let Ok(choice) = self.estimator.select_group() else {
            return self.abort(AbortReason::NoReachablePair);
        };
        let Some(group) = lift_group(&self.scenario, choice.group) else {
            return self.abort(AbortReason::NoReachablePair);
        };
        let candidates: Vec<f32, MAX_ROBOTS> = group
            .candidates
            .iter()
            .map(|&c| self.scenario.payload.candidates[c])
            .collect();
        let rail = &self.scenario.payload.rail;
        let spacing = self.scenario.robots.min_spacing;
        let Some(targets) = lift_targets(rail, &self.robots, &candidates, spacing) else {
            return self.abort(AbortReason::NoReachablePair);
        };
        let Ok(mv) = RailMove::plan(
            rail,
            &self.robots,
            &targets,
            spacing,
            self.config.rail_limits,
        ) else {
            return self.abort(AbortReason::NoReachablePair);
        };
        self.pair_robots = candidates
            .iter()
            .filter_map(|c| targets.iter().position(|t| math::abs(t - c) < 1e-5))
            .collect();
        self.group = choice.group;
        self.rail_move = Some((mv, targets));
        self.enter(
            Phase::MovingRobots,
            Reason::PairChosen {
                group: choice.group,
                information: choice.information,
            },
        )
    }

    fn move_robots(&mut self) -> Option<Transition> {
        let (mv, targets) = self.rail_move.as_ref()?;
        if self.phase_time < mv.duration() {
            self.robots = mv.positions_at(&self.scenario.payload.rail, self.phase_time);
            return None;
        }
        self.robots = targets.clone();
        self.rail_move = None;
        if self.phase == Phase::MovingRobots {
            self.lift = Some(LiftoffDetector::new(
                self.config.liftoff,
                self.own_weight(),
                self.scenario.robots.max_thrust,
            ));
            Some(self.enter(Phase::Lifting, Reason::RobotsInPlace))
        } else {
            Some(self.build_flight())
        }
    }

    fn lifting(
        &mut self,
        attitude: Quat,
        dt: f32,
        thrusts: &mut [f32; MAX_ROBOTS],
    ) -> Option<Transition> {
        let n = self.scenario.robots.count();
        let own = self.own_weight();
        thrusts[..n].iter_mut().for_each(|t| *t = own);
        let lift = self.lift.as_mut()?;
        let state = lift.step(attitude, dt);
        for &i in &self.pair_robots {
            thrusts[i] = lift.pair_thrust();
        }
        let LiftState::Measured(m) = state else {
            return None;
        };
        self.lift = None;
        match self.estimator.update(self.group, m) {
            Ok(status) => {
                self.last_status = status;
                self.converged_in_a_row = if status == Status::Converged {
                    self.converged_in_a_row + 1
                } else {
                    0
                };
                Some(self.enter(Phase::Relaxing, Reason::LiftRead(m)))
            }
            Err(_) => Some(self.abort(AbortReason::EstimationFailed)),
        }
    }

    fn relaxing(&mut self) -> Option<Transition> {
        if self.phase_time < self.config.relax_time {
            return None;
        }
        Some(match self.last_status {
            Status::Measuring => self.enter(Phase::SelectingPair, Reason::NeedMoreLifts),
            Status::Converged if self.converged_in_a_row < self.config.confirmations => {
                self.enter(Phase::SelectingPair, Reason::NeedMoreLifts)
            }
            Status::Converged => {
                let e = self.estimator.estimate();
                self.estimate = Some(e);
                self.enter(Phase::DecidingFormation, Reason::Converged(e.theta))
            }
            Status::NotConverged => self.abort(AbortReason::EstimationNotConverged),
        })
    }

    fn decide_formation(&mut self) -> Transition {
        let Some(e) = self.estimate else {
            return self.abort(AbortReason::EstimationFailed);
        };
        let robots = &self.scenario.robots;
        let n = robots.count() as f32;
        // The heaviest payload the posterior allows (95 % upper bound of the mass).
        let heaviest = e.mass_upper_95.max(e.theta[2]);
        let needed = (heaviest + n * robots.mass) * GRAVITY;
        let allowed = self.config.max_hover_fraction * n * robots.max_thrust;
        if needed > allowed {
            return self.abort(AbortReason::ThrustMarginTooSmall { needed, allowed });
        }
        let rail = &self.scenario.payload.rail;
        let com = Vec2::new(e.theta[0], e.theta[1]);
        let problem = FormationProblem::for_scenario(&self.scenario, com, Some(&self.robots));
        let Ok(formation) = solve(&problem) else {
            return self.abort(AbortReason::NoBalancedFormation);
        };
        let Ok(mv) = RailMove::plan(
            rail,
            &self.robots,
            &formation.positions,
            robots.min_spacing,
            self.config.rail_limits,
        ) else {
            return self.abort(AbortReason::NoBalancedFormation);
        };
        self.formation = Some(formation.positions.clone());
        self.rail_move = Some((mv, formation.positions));
        self.enter(
            Phase::Rearranging,
            Reason::FormationChosen(formation.figures.det),
        )
    }

    fn build_flight(&mut self) -> Transition {
        let (Some(e), Some(flight)) = (self.estimate, self.scenario.flight) else {
            return self.abort(AbortReason::EstimationFailed);
        };
        let robots = &self.scenario.robots;
        let rail = &self.scenario.payload.rail;
        let points: Vec<Vec2, MAX_ROBOTS> = self.robots.iter().map(|&s| rail.point_at(s)).collect();
        let com = Vec2::new(e.theta[0], e.theta[1]);
        let model = VehicleModel::from_payload(
            &self.scenario.payload.footprint,
            com,
            e.theta[2],
            &points,
            robots.mass,
            robots.max_thrust,
        );
        let layout = RotorLayout {
            points: &points,
            spin: &robots.spin,
            com,
            torque_per_thrust: robots.torque_per_thrust,
            max_thrust: robots.max_thrust,
        };
        let Ok(mixer) = Mixer::build(self.config.mixer, &layout) else {
            return self.abort(AbortReason::Uncontrollable);
        };
        let start = self.position.state().position;
        self.flight = Some(Flight {
            mixer,
            controller: FlightController::new(self.config.control, model),
            plan: FlightPlan::new(start, flight.target, 0.0, self.config.plan),
            land: LandDetector::new(start.z),
            saturation: Saturation::default(),
            ground_z: start.z,
            failsafe_until: None,
        });
        self.enter(Phase::Arming, Reason::RobotsInPlace)
    }

    fn fly(
        &mut self,
        attitude: crate::control::attitude_estimator::AttitudeState,
        dt: f32,
        thrusts: &mut [f32; MAX_ROBOTS],
    ) -> Option<Transition> {
        let Phase::Flying(current) = self.phase else {
            return None;
        };
        let estimate = self.position.state();
        self.flight_clock += dt;
        let descent_speed = self.config.plan.descent_speed;
        let flight = self.flight.as_mut()?;
        let (mut setpoint, plan_phase) = flight.plan.sample(self.flight_clock);
        let descending = matches!(plan_phase, FlightPhase::Land | FlightPhase::Done);
        let contact = flight
            .land
            .update(estimate.position, estimate.velocity, descending, dt);
        if contact == Contact::Landed && flight.failsafe_until.is_none() {
            return Some(self.enter(Phase::Disarmed, Reason::Landed));
        }
        if !estimate.valid && contact == Contact::Airborne && flight.failsafe_until.is_none() {
            // Position lost in the air: never cut the rotors there. Descend on velocity alone
            // (the IMU-propagated velocity drifts slowly) and stop the rotors once the descent
            // from the last known height has reached the ground, before the IMU-only estimate
            // has had time to wander.
            let height = (flight.ground_z - estimate.position.z).max(0.0);
            flight.failsafe_until =
                Some(self.flight_clock + height / descent_speed.max(0.05) + FAILSAFE_MARGIN);
            return Some(self.enter(
                Phase::Flying(FlightPhase::Land),
                Reason::Abort(AbortReason::PositionLost),
            ));
        }
        if let Some(until) = flight.failsafe_until {
            if self.flight_clock >= until {
                return Some(self.enter(Phase::Disarmed, Reason::Landed));
            }
            setpoint = crate::control::trajectory::Setpoint {
                position: estimate.position,
                velocity: Vec3::new(0.0, 0.0, descent_speed),
                acceleration: Vec3::ZERO,
                yaw: setpoint.yaw,
            };
        }
        let inputs = ControlInputs {
            setpoint,
            attitude,
            position: estimate,
            airborne: flight.land.airborne(),
            saturation: flight.saturation,
        };
        let out = flight.controller.step(&inputs, dt);
        let alloc = flight.mixer.allocate(&out.wrench);
        flight.saturation = alloc.saturation;
        let n = self.scenario.robots.count();
        thrusts[..n].copy_from_slice(&alloc.thrusts[..n]);
        if flight.failsafe_until.is_some() {
            return None;
        }
        (plan_phase != current).then(|| self.enter(Phase::Flying(plan_phase), Reason::PlanAdvanced))
    }
}
