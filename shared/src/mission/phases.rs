//! The mission's phases and the reasons it moves between them (docs/system.md#mission-phases;
//! the paper built it as a Stateflow chart). Every transition carries its reason so
//! the caller can log it.

use crate::control::allocation::AllocationError;
use crate::control::imu_monitor::ImuFailure;
use crate::control::trajectory::FlightPhase;
use crate::estimation::estimator::OutsideGrid;
use crate::estimation::{EstimationError, Measurement};
use crate::formation::FormationError;
use crate::math;
use crate::numbers::{Fixed, Sci};
use crate::rail::moves::MoveError;

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
    /// Stopped for a reason, rotors off: on the ground, or by the operator's kill. (In flight
    /// nothing else stops the rotors: a lost position or an operator's abort switches the plan
    /// to a landing in place, recorded as an abort reason.)
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

/// Why the mission stopped, or (in flight) why it lands where it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AbortReason {
    /// No valid position or attitude in time, or the payload not resting level.
    SensorsNotReady,
    /// No lifting pair can be reached by the robots.
    NoReachablePair,
    /// The robots cannot be moved to the positions a lift or the formation needs.
    RailMove(MoveError),
    /// `max_measurements` lifts without converging.
    EstimationNotConverged,
    /// The readings say the payload lies outside the estimation grid (heavier, or its COM
    /// elsewhere, than the grid allows).
    PayloadOutsideGrid(OutsideGrid),
    /// The heaviest payload the estimate allows needs more than the allowed share of thrust.
    ThrustMarginTooSmall {
        /// Hover thrust of the heaviest payload the posterior allows (95 % bound), N.
        needed: f32,
        /// Thrust allowed for hover, N.
        allowed: f32,
    },
    /// Refused before take-off: the formation, hovering the heaviest payload the estimate
    /// allows, cannot add the flight's design torque about one axis
    /// (docs/failures.md#refused-before-take-off).
    FormationTooWeak {
        /// The axis: 0 roll, 1 pitch, 2 yaw.
        axis: u8,
        /// Torque the rotors can add about it at that hover, N m.
        available: f32,
        /// Torque the flight must hold about it, N m.
        needed: f32,
        /// The heaviest payload the estimate allows, kg.
        mass: f32,
    },
    /// No balanced formation exists for the estimated COM.
    NoBalancedFormation(FormationError),
    /// The formation's rotors cannot control every axis.
    Uncontrollable(AllocationError),
    /// The estimator rejected a reading or the set-up.
    EstimationFailed(EstimationError),
    /// The payload did not leave the ground under take-off thrust: the rotors stopped.
    TakeoffFailed {
        /// Greatest height reached, m.
        height: f32,
    },
    /// The position estimate was lost (in flight: the mission lands in place, then disarms).
    PositionLost,
    /// The vehicle did not reach its plan's next point in time: it lands where it is.
    TrackingLost,
    /// The operator aborted (on the ground: rotors off; in flight: landing where it is).
    OperatorAbort,
    /// The operator stopped the rotors.
    Killed,
    /// A computation handed off the control tick did not finish by its deadline.
    JobOverrun,
    /// The payload description has no flight target.
    NoFlightTarget,
    /// The IMU failed (stalled, saturated or implausible): on the ground the mission stops,
    /// in flight it lands where it is.
    ImuFault,
    /// The IMU repeats one sample ([`crate::control::imu_monitor`]): on the ground the
    /// mission stops, in flight it lands on motion capture alone.
    ImuStuck,
    /// The IMU's samples jump far beyond sensor noise and the vehicle's motion
    /// ([`crate::control::imu_monitor`]): on the ground the mission stops, in flight it lands
    /// on motion capture alone.
    ImuNoisy,
    /// The vehicle left its geofence in flight (`GF_ACTION` land): it lands where it is.
    GeofenceBreached {
        /// Its distance from the take-off point across the ground, m.
        distance: f32,
        /// Its height above the take-off point, m.
        height: f32,
    },
    /// The payload did not come to rest for a lift within the detector's wait
    /// ([`crate::liftoff_detector::REST_TIMEOUT`]).
    PayloadRestless {
        /// How far its down axis moved over the last settle window, rad.
        moved: f32,
    },
    /// A robot's stepper stalled on the rail: the robot is not where the plan put it.
    RobotStalled {
        /// The robot, counted from 0.
        robot: u8,
    },
    /// The ground link was lost (no ground station's heartbeat for `FS_GCS_LOSS_T`): on the
    /// ground after the start the mission stops; in flight, after the hold, it lands in place.
    GcsLost,
    /// The battery fell below its low threshold before take-off: the mission stops.
    BatteryLow {
        /// The filtered pack voltage, V.
        volts: f32,
    },
    /// The battery fell below its critical threshold: in flight the vehicle lands in place,
    /// on the ground the mission stops.
    BatteryCritical {
        /// The filtered pack voltage, V.
        volts: f32,
    },
    /// A robot's rotor stopped in flight: the flight goes on with the other rotors and lands
    /// where it is.
    RotorOut {
        /// The robot, counted from 0.
        robot: u8,
    },
    /// Manual control was lost in Position mode: after the hold, the vehicle lands in place
    /// (`NAV_RCL_ACT`).
    ManualLost,
}

impl core::fmt::Display for AbortReason {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::SensorsNotReady => write!(
                f,
                "sensors not ready: no valid position, or the payload is not resting level"
            ),
            Self::NoReachablePair => write!(f, "no lifting pair can be reached by the robots"),
            Self::RailMove(e) => write!(f, "the robots cannot move there: {e}"),
            Self::EstimationNotConverged => {
                write!(f, "the estimate did not converge within the allowed lifts")
            }
            Self::PayloadOutsideGrid(why) => {
                write!(f, "payload outside the estimation grid: {why}")
            }
            Self::ThrustMarginTooSmall { needed, allowed } => write!(
                f,
                "not enough thrust margin: the heaviest payload the estimate allows needs {} N to hover, {} N allowed",
                Fixed(needed, 1),
                Fixed(allowed, 1)
            ),
            Self::FormationTooWeak {
                axis,
                available,
                needed,
                mass,
            } => write!(
                f,
                "formation too weak: hovering {} kg (the heaviest the estimate allows) its rotors can add {} N m of {} torque, the flight must hold {} N m",
                Fixed(mass, 2),
                Fixed(available, 2),
                match axis {
                    0 => "roll",
                    1 => "pitch",
                    _ => "yaw",
                },
                Fixed(needed, 2)
            ),
            Self::NoBalancedFormation(e) => write!(f, "no balanced formation: {e}"),
            Self::Uncontrollable(e) => write!(f, "the formation cannot be flown: {e}"),
            Self::EstimationFailed(e) => write!(f, "estimation failed: {e}"),
            Self::TakeoffFailed { height } => write!(
                f,
                "take-off failed: the payload did not leave the ground (greatest height {} m); rotors stopped",
                Fixed(height, 3)
            ),
            Self::PositionLost => write!(f, "position lost"),
            Self::TrackingLost => {
                write!(f, "the vehicle did not reach its plan's next point in time")
            }
            Self::OperatorAbort => write!(f, "aborted by the operator"),
            Self::Killed => write!(f, "rotors stopped by the operator"),
            Self::JobOverrun => write!(f, "a computation did not finish by its deadline"),
            Self::NoFlightTarget => write!(f, "the payload description has no flight target"),
            Self::ImuFault => write!(f, "IMU fault (stalled, saturated or implausible)"),
            Self::ImuStuck => write!(f, "{}", ImuFailure::Stuck),
            Self::ImuNoisy => write!(f, "{}", ImuFailure::Noisy),
            Self::GeofenceBreached { distance, height } => write!(
                f,
                "geofence breached: {} m from the take-off point, {} m above it (GF_MAX_HOR_DIST, GF_MAX_VER_DIST); landing where it is",
                Fixed(distance, 1),
                Fixed(height, 1)
            ),
            Self::PayloadRestless { moved } => write!(
                f,
                "the payload did not come to rest for a lift in {} s (it still moved {} deg within a settle window)",
                Fixed(crate::liftoff_detector::REST_TIMEOUT, 0),
                Fixed(moved.to_degrees(), 2)
            ),
            Self::RobotStalled { robot } => write!(
                f,
                "robot {} stalled on the rail: it is not where the plan put it",
                u32::from(robot) + 1
            ),
            Self::GcsLost => write!(f, "ground link lost (no ground-station heartbeat)"),
            Self::BatteryLow { volts } => write!(
                f,
                "battery low before take-off: {} V, below BAT_LOW_V",
                Fixed(crate::mission::supervision::hundredths_down(volts), 2)
            ),
            Self::BatteryCritical { volts } => write!(
                f,
                "battery critical: {} V, below BAT_CRIT_V",
                Fixed(crate::mission::supervision::hundredths_down(volts), 2)
            ),
            Self::RotorOut { robot } => write!(
                f,
                "rotor {} stopped in flight: flying on the other rotors and landing where it is",
                u32::from(robot) + 1
            ),
            Self::ManualLost => write!(
                f,
                "manual control lost in Position mode (NAV_RCL_ACT): landing where it is"
            ),
        }
    }
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
    /// The lifts ran out with the posterior tight enough to fly on (not past the threshold):
    /// the estimate [COM x, COM y, mass] and its spread on each axis.
    Settled {
        /// The estimate: COM x, COM y (m), mass (kg).
        theta: [f32; 3],
        /// Its standard deviation on each axis.
        spread: [f32; 3],
    },
    /// The flight formation was chosen; its `det(B B^T)`.
    FormationChosen(f32),
    /// The flight's model and mixer are built.
    FlightReady,
    /// The arming delay passed.
    Armed,
    /// The plan moved on.
    PlanAdvanced,
    /// The operator asked to land where the vehicle is.
    LandNow,
    /// Touchdown detected and rotors stopped.
    Landed,
    /// Stopped, or landing in place.
    Abort(AbortReason),
}

impl core::fmt::Display for Reason {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Started => write!(f, "started"),
            Self::ChecksPassed => write!(f, "sensors valid, payload level"),
            Self::PairChosen { group, information } => {
                write!(
                    f,
                    "pair {group} (information {} nats)",
                    Fixed(information, 2)
                )
            }
            Self::RobotsInPlace => write!(f, "robots in place"),
            Self::LiftRead(Measurement::Lifted { thrust }) => {
                write!(f, "lifted at {} N per robot", Fixed(thrust, 2))
            }
            Self::LiftRead(Measurement::CouldNotLift) => {
                write!(f, "could not lift at full thrust")
            }
            Self::NeedMoreLifts => write!(f, "more lifts needed"),
            Self::Converged(t) => write!(
                f,
                "estimate COM ({}, {}) m, mass {} kg",
                Fixed(t[0], 3),
                Fixed(t[1], 3),
                Fixed(t[2], 2)
            ),
            Self::Settled { theta, spread } => write!(
                f,
                "estimate COM ({}, {}) m, mass {} kg, settled at +-{} m, +-{} kg: the lifts cannot narrow it",
                Fixed(theta[0], 3),
                Fixed(theta[1], 3),
                Fixed(theta[2], 2),
                Fixed(math::max(spread[0], spread[1]), 3),
                Fixed(spread[2], 2)
            ),
            Self::FormationChosen(det) => write!(f, "formation det(BB^T) {}", Sci(det, 3)),
            Self::FlightReady => write!(f, "mixer built"),
            Self::Armed => write!(f, "armed"),
            Self::PlanAdvanced => write!(f, "plan advanced"),
            Self::LandNow => write!(f, "landing now, as commanded"),
            Self::Landed => write!(f, "landed, rotors stopped"),
            Self::Abort(why) => write!(f, "ABORT: {why}"),
        }
    }
}

impl From<ImuFailure> for AbortReason {
    fn from(failure: ImuFailure) -> Self {
        match failure {
            ImuFailure::Stuck => Self::ImuStuck,
            ImuFailure::Noisy => Self::ImuNoisy,
        }
    }
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
