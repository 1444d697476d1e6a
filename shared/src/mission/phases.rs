//! The mission's phases and the reasons it moves between them (SPEC.md section 2: the whole
//! pipeline; the paper built it as a Stateflow chart). Every transition carries its reason so
//! the caller can log it.

use crate::control::trajectory::FlightPhase;
use crate::estimation::Measurement;

/// Where the mission is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Phase {
    /// Waiting for the start command.
    Idle,
    /// Sensors settling, the payload resting level, rotors off.
    PreflightChecks,
    /// Scoring the adjacent pairs and choosing the next lift.
    SelectingPair,
    /// Steppers bringing the robots to the lift's positions.
    MovingRobots,
    /// Ramping the pair's thrust, watching for lift-off.
    Lifting,
    /// Rotors off, the payload settling back after a lift.
    Relaxing,
    /// Choosing the flight formation from the estimate.
    DecidingFormation,
    /// Steppers bringing the robots to the flight formation.
    Rearranging,
    /// Armed on the ground, rotors idle, before take-off.
    Arming,
    /// Flying the plan.
    Flying(FlightPhase),
    /// Landed and disarmed: the mission is over.
    Disarmed,
    /// Stopped on the ground for a reason, rotors off. (In flight nothing stops the rotors: a
    /// lost position switches the plan to a landing in place, recorded as an abort reason.)
    Aborted,
}

impl Phase {
    /// A short name for logs and reports.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Idle => "idle",
            Self::PreflightChecks => "preflight-checks",
            Self::SelectingPair => "select-pair",
            Self::MovingRobots => "move-robots",
            Self::Lifting => "lift",
            Self::Relaxing => "relax",
            Self::DecidingFormation => "decide-formation",
            Self::Rearranging => "rearrange",
            Self::Arming => "arming",
            Self::Flying(FlightPhase::Takeoff) => "takeoff",
            Self::Flying(FlightPhase::Transit) => "trajectory",
            Self::Flying(FlightPhase::Hover) => "hover",
            Self::Flying(FlightPhase::Land) => "landing",
            Self::Flying(FlightPhase::Done) => "touchdown",
            Self::Disarmed => "disarmed",
            Self::Aborted => "aborted",
        }
    }
}

/// Why the mission stopped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AbortReason {
    /// No valid position or attitude in time, or the payload not resting level.
    SensorsNotReady,
    /// No lifting pair can be reached by the robots.
    NoReachablePair,
    /// `max_measurements` lifts without converging.
    EstimationNotConverged,
    /// The heaviest payload the estimate allows needs more than the allowed share of thrust.
    ThrustMarginTooSmall {
        /// Hover thrust of the heaviest payload the posterior allows (95 % bound), N.
        needed: f32,
        /// Thrust allowed for hover, N.
        allowed: f32,
    },
    /// No balanced formation exists for the estimated COM.
    NoBalancedFormation,
    /// The formation's rotors cannot control every axis.
    Uncontrollable,
    /// The position estimate was lost in flight (the mission lands in place, then disarms).
    PositionLost,
    /// The estimator rejected a reading or the set-up.
    EstimationFailed,
}

/// Why a transition happened.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reason {
    /// The start command.
    Started,
    /// Sensors valid and the payload level.
    ChecksPassed,
    /// A pair was chosen for the next lift.
    PairChosen {
        /// Group index.
        group: usize,
        /// Its mutual information, nats.
        information: f32,
    },
    /// The robots reached their positions.
    RobotsInPlace,
    /// The lift produced a reading.
    LiftRead(Measurement),
    /// The payload settled after a lift; more lifts are needed.
    NeedMoreLifts,
    /// The posterior is concentrated enough: [COM x, COM y, mass].
    Converged([f32; 3]),
    /// The flight formation was chosen; its `det(B B^T)`.
    FormationChosen(f32),
    /// The arming delay passed.
    Armed,
    /// The plan moved on.
    PlanAdvanced,
    /// Touchdown detected and rotors stopped.
    Landed,
    /// Stopped.
    Abort(AbortReason),
}

/// One change of phase.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transition {
    /// Left.
    pub from: Phase,
    /// Entered.
    pub to: Phase,
    /// Why.
    pub reason: Reason,
}
