//! The mission's long computations, handed off the 400 Hz tick (docs/system.md#mission-phases: pair
//! selection by mutual information, the Bayes update, the formation decision, the mixer).
//!
//! The tick side ([`crate::mission::Mission`]) issues a [`JobRequest`]; the job side
//! ([`MissionPlanner`], which owns the estimator and its buffers) runs it and returns a
//! [`JobResult`]. On the flight controller the job side runs in thread mode while the control
//! loop keeps its period; the simulator runs the same jobs in line. Either way the tick side
//! takes the result at a fixed tick after the request, [`JobRequest::deadline_ticks`] later,
//! so a run does not depend on how fast the jobs happened to finish. Each deadline is the
//! job's worst case on the Cortex-M7 at 480 MHz (`.ci/target-bench`) with room for the
//! control loop's share of the processor.

use heapless::Vec;

use crate::control::allocation::{AllocationError, Mixer, MixerKind};
use crate::estimation::groups::lift_group;
use crate::estimation::{Estimate, Estimator, Measurement, Status};
use crate::flight::FlightModel;
use crate::flight::model::mixer_for;
use crate::formation::{FormationProblem, solve};
use crate::geometry::{ConvexHull, Rail, Vec2};
use crate::math;
use crate::mission::config::MissionConfig;
use crate::mission::phases::AbortReason;
use crate::rail::moves::{Positions, RailMove, lift_targets};
use crate::rail::stepper::MotionLimits;
use crate::scenario::{
    EstimationSetup, FormationSetup, GRAVITY, MAX_ROBOTS, Payload, Robots, Scenario,
};

/// A computation the tick side wants.
#[derive(Clone, Debug, PartialEq)]
pub enum JobRequest {
    /// Choose the next lift by mutual information and plan the robots' move to it.
    SelectPair {
        /// Where the robots are.
        robots: Positions,
    },
    /// Bayes update with a lift's reading.
    Update {
        /// The lifting group.
        group: usize,
        /// Its reading.
        reading: Measurement,
    },
    /// Check the thrust margin, solve the formation for the estimate, plan the move there.
    DecideFormation {
        /// Where the robots are.
        robots: Positions,
    },
    /// Build the flight's vehicle model and mixer for the robots where they are.
    BuildFlight {
        /// Where the robots are.
        robots: Positions,
    },
    /// In flight, the load has shifted: the formation about the COM measured in the hover.
    Reform {
        /// Where the robots are.
        robots: Positions,
        /// The measured COM, m.
        com: Vec2,
    },
    /// In flight, rotors were found stopped: the mixer of the robots where they are, about
    /// the COM flown, without those rotors ([`Mixer::without`]); the step flies the interim
    /// mixer until it comes ([`Mixer::leave_out`]).
    MixerWithout {
        /// Where the robots are.
        robots: Positions,
        /// The COM the flight's mixer is about, m.
        com: Vec2,
        /// The rotors left out, bit `i` for rotor `i`.
        out: u16,
        /// The thrust that holds the vehicle as the flight believes it, N: whether the rotors
        /// left hold it level ([`MixerLeft::holds_level`]).
        weight: f32,
    },
}

/// Ticks at 400 Hz.
const fn ticks_of_ms(ms: u32) -> u32 {
    (ms * crate::timing::CONTROL_RATE_HZ).div_ceil(1000)
}

impl JobRequest {
    /// Ticks after the request at which the tick side takes the result. Worst cases on the
    /// Cortex-M7 (`.ci/target-bench`, instructions at 480 MHz): pair selection 1.5 M
    /// (~3.2 ms), update with the grid's guard band 2.1 M (~4.5 ms), formation 6.2 M
    /// (~13 ms, L-sim1), mixer 3.6 k, a mixer without rotors 15 k at 16 rotors; each deadline
    /// leaves about three times that for the control loop's share of the processor and the
    /// link.
    pub fn deadline_ticks(&self) -> u32 {
        match self {
            Self::SelectPair { .. } | Self::Update { .. } => ticks_of_ms(20),
            Self::DecideFormation { .. } | Self::Reform { .. } => ticks_of_ms(40),
            Self::BuildFlight { .. } | Self::MixerWithout { .. } => ticks_of_ms(5),
        }
    }

    /// A short name for logs.
    pub fn name(&self) -> &'static str {
        match self {
            Self::SelectPair { .. } => "select-pair",
            Self::Update { .. } => "update",
            Self::DecideFormation { .. } => "decide-formation",
            Self::BuildFlight { .. } => "build-flight",
            Self::Reform { .. } => "reform",
            Self::MixerWithout { .. } => "mixer-without",
        }
    }
}

/// The next lift: the group, its robots and the move that brings them there.
#[derive(Clone, Debug, PartialEq)]
pub struct LiftPlan {
    /// Group index.
    pub group: usize,
    /// Its mutual information, nats.
    pub information: f32,
    /// Robots (indices in rail order) that lift.
    pub lifting: Vec<usize, MAX_ROBOTS>,
    /// Where every robot goes.
    pub targets: Positions,
    /// How they get there.
    pub rail_move: RailMove,
}

/// The flight formation and the move that brings the robots there.
#[derive(Clone, Debug, PartialEq)]
pub struct FormationPlan {
    /// Arc length of each robot.
    pub positions: Positions,
    /// Its `det(B B^T)`.
    pub det: f32,
    /// How the robots get there.
    pub rail_move: RailMove,
}

/// What a job produced.
// One at a time crosses from the job task to the control task; without an allocator there is
// nothing to box the mixer into, and the largest variant (~550 bytes) is small enough to copy.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum JobResult {
    /// Answer to [`JobRequest::SelectPair`].
    Pair(Result<LiftPlan, AbortReason>),
    /// Answer to [`JobRequest::Update`]: the estimate after it (with its status).
    Updated(Result<Estimate, AbortReason>),
    /// Answer to [`JobRequest::DecideFormation`].
    Formation(Result<FormationPlan, AbortReason>),
    /// Answer to [`JobRequest::BuildFlight`].
    Flight(Result<FlightModel, AbortReason>),
    /// Answer to [`JobRequest::Reform`]: the new formation's positions and `det(B B^T)`.
    Reformed(Result<(Positions, f32), AbortReason>),
    /// Answer to [`JobRequest::MixerWithout`].
    MixerWithout(Result<MixerLeft, AllocationError>),
}

/// The full mixer without rotors found stopped ([`JobRequest::MixerWithout`]), and what it
/// can do: both worked out off the control step.
#[derive(Clone, Debug, PartialEq)]
pub struct MixerLeft {
    /// The mixer of the rotors left.
    pub mixer: Mixer,
    /// It allocates the hover (the vehicle's weight, no torque) within every rotor's range.
    /// When it cannot, the allocation keeps the payload level and gives up collective thrust
    /// (docs/failures.md#rotors-that-stop-in-flight): the vehicle comes down faster than
    /// planned.
    pub holds_level: bool,
}

/// What of the mission's configuration the job side uses.
///
/// Kept apart from [`MissionConfig`] so that the unloaded planner is all zero bytes: the
/// flight controller's static of it (with the estimator's ~70 KB of buffers) then costs RAM
/// only (`.bss`), not the same again in flash as an initialiser (`.data`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct PlannerConfig {
    rail_limits: MotionLimits,
    max_hover_fraction: f32,
    mixer: MixerKind,
    refuse_weak_formation: bool,
}

impl PlannerConfig {
    /// Nothing loaded: zeros (no move, no margin; `load` sets the real values first).
    const UNLOADED: Self = Self {
        rail_limits: MotionLimits {
            max_speed: 0.0,
            max_acceleration: 0.0,
        },
        max_hover_fraction: 0.0,
        mixer: MixerKind::EqualSplit,
        refuse_weak_formation: false,
    };

    fn of(config: &MissionConfig) -> Self {
        Self {
            rail_limits: config.rail_limits,
            max_hover_fraction: config.max_hover_fraction,
            mixer: config.mixer,
            refuse_weak_formation: config.refuse_weak_formation,
        }
    }
}

/// The job side: the estimator (with its grid-sized buffers) and the decisions made on it.
#[derive(Clone, Debug)]
pub struct MissionPlanner {
    scenario: Scenario,
    config: PlannerConfig,
    estimator: Estimator,
}

/// The payload description of an unloaded mission: nothing at all.
pub(crate) const NO_SCENARIO: Scenario = Scenario {
    payload: Payload {
        footprint: Vec::new(),
        hull: ConvexHull::EMPTY,
        rail: Rail::EMPTY,
        candidates: Vec::new(),
    },
    robots: Robots {
        mass: 0.0,
        max_thrust: 0.0,
        torque_per_thrust: 0.0,
        spin: Vec::new(),
        min_spacing: 0.0,
        pair_size: 0,
        initial: Vec::new(),
    },
    estimation: EstimationSetup {
        grid_min: [0.0; 3],
        grid_max: [0.0; 3],
        resolution: [0.0; 3],
        threshold: 0.0,
        noise_sigma: 0.0,
        max_measurements: 0,
    },
    formation: FormationSetup { balance_eps: 0.0 },
    truth: None,
    flight: None,
};

impl MissionPlanner {
    /// A planner for `scenario`, the estimator on a uniform prior.
    pub fn new(scenario: &Scenario, config: MissionConfig) -> Result<Self, AbortReason> {
        let mut planner = Self::UNLOADED;
        planner.load(scenario, config)?;
        Ok(planner)
    }

    /// A planner with no payload description: a constant, so the flight controller can place
    /// it (with the estimator's grid-sized buffers) in a static; [`Self::load`] fills it.
    pub const UNLOADED: Self = Self {
        scenario: NO_SCENARIO,
        config: PlannerConfig::UNLOADED,
        estimator: Estimator::UNLOADED,
    };

    /// In place: the planner of `scenario`, as [`Self::new`] builds it.
    pub fn load(&mut self, scenario: &Scenario, config: MissionConfig) -> Result<(), AbortReason> {
        self.scenario.clone_from(scenario);
        self.config = PlannerConfig::of(&config);
        if let Some(sigma) = config.lift_noise_sigma {
            if !(sigma.is_finite() && sigma > 0.0) {
                return Err(AbortReason::EstimationFailed(
                    crate::estimation::EstimationError::BadNoiseModel,
                ));
            }
            // The estimator's noise model for the lifts (see MissionConfig::lift_noise_sigma).
            self.scenario.estimation.noise_sigma = sigma;
        }
        let loaded = self.estimator.load(&self.scenario, config.estimator);
        self.scenario.estimation.noise_sigma = scenario.estimation.noise_sigma;
        loaded.map_err(AbortReason::EstimationFailed)
    }

    /// The estimator (its posterior, for reports).
    pub fn estimator(&self) -> &Estimator {
        &self.estimator
    }

    /// Runs one job.
    pub fn run(&mut self, request: &JobRequest) -> JobResult {
        match request {
            JobRequest::SelectPair { robots } => JobResult::Pair(self.select_pair(robots)),
            JobRequest::Update { group, reading } => JobResult::Updated(
                self.estimator
                    .update(*group, *reading)
                    .map(|_| self.estimator.estimate())
                    .map_err(AbortReason::EstimationFailed),
            ),
            JobRequest::DecideFormation { robots } => {
                JobResult::Formation(self.decide_formation(robots))
            }
            JobRequest::BuildFlight { robots } => JobResult::Flight(self.build_flight(robots)),
            JobRequest::Reform { robots, com } => JobResult::Reformed(self.reform(robots, *com)),
            JobRequest::MixerWithout {
                robots,
                com,
                out,
                weight,
            } => JobResult::MixerWithout(
                mixer_for(&self.scenario, robots, *com, self.config.mixer)
                    .and_then(|m| m.without(*out))
                    .map(|mixer| MixerLeft {
                        holds_level: mixer.holds_hover(*weight),
                        mixer,
                    }),
            ),
        }
    }

    fn select_pair(&mut self, robots: &[f32]) -> Result<LiftPlan, AbortReason> {
        let choice = self
            .estimator
            .select_group()
            .map_err(|_| AbortReason::NoReachablePair)?;
        let group = lift_group(&self.scenario, choice.group).ok_or(AbortReason::NoReachablePair)?;
        let candidates: Vec<f32, MAX_ROBOTS> = group
            .candidates
            .iter()
            .map(|&c| self.scenario.payload.candidates[c])
            .collect();
        let rail = &self.scenario.payload.rail;
        let spacing = self.scenario.robots.min_spacing;
        let targets =
            lift_targets(rail, robots, &candidates, spacing).ok_or(AbortReason::NoReachablePair)?;
        let rail_move = RailMove::plan(rail, robots, &targets, spacing, self.config.rail_limits)
            .map_err(AbortReason::RailMove)?;
        let lifting = candidates
            .iter()
            .filter_map(|c| targets.iter().position(|t| math::abs(t - c) < 1e-5))
            .collect();
        Ok(LiftPlan {
            group: choice.group,
            information: choice.information,
            lifting,
            targets,
            rail_move,
        })
    }

    fn decide_formation(&mut self, robots: &[f32]) -> Result<FormationPlan, AbortReason> {
        let e = self.estimator.estimate();
        let r = &self.scenario.robots;
        let n = r.count() as f32;
        // The heaviest payload the posterior allows (95 % upper bound of the mass).
        let heaviest = math::max(e.mass_upper_95, e.theta[2]);
        let needed = (heaviest + n * r.mass) * GRAVITY;
        let allowed = self.config.max_hover_fraction * n * r.max_thrust;
        if needed > allowed {
            return Err(AbortReason::ThrustMarginTooSmall { needed, allowed });
        }
        let com = Vec2::new(e.theta[0], e.theta[1]);
        let problem = FormationProblem::for_scenario(&self.scenario, com, Some(robots));
        let formation = solve(&problem).map_err(AbortReason::NoBalancedFormation)?;
        if self.config.refuse_weak_formation {
            self.check_authority(&formation.positions, com, heaviest)?;
        }
        let rail_move = RailMove::plan(
            &self.scenario.payload.rail,
            robots,
            &formation.positions,
            r.min_spacing,
            self.config.rail_limits,
        )
        .map_err(AbortReason::RailMove)?;
        Ok(FormationPlan {
            positions: formation.positions.iter().copied().collect(),
            det: formation.figures.det,
            rail_move,
        })
    }

    /// Refuses a formation (rail positions `positions`, about `com`) whose rotors, hovering
    /// the heaviest payload the estimate allows (`heaviest`, kg), cannot add the flight's
    /// design torque about every axis ([`design_torque`]).
    fn check_authority(
        &self,
        positions: &[f32],
        com: Vec2,
        heaviest: f32,
    ) -> Result<(), AbortReason> {
        let r = &self.scenario.robots;
        let model = FlightModel::build(&self.scenario, positions, com, heaviest, self.config.mixer)
            .map_err(AbortReason::Uncontrollable)?;
        let weight = (heaviest + r.count() as f32 * r.mass) * GRAVITY;
        let available = model.mixer.authority(weight).to_array();
        let e = self.estimator.estimate();
        let needed =
            design_torque(&self.scenario, weight, com_error(&self.scenario, &e)).to_array();
        for axis in 0..3 {
            if available[axis] < needed[axis] {
                return Err(AbortReason::FormationTooWeak {
                    axis: axis as u8,
                    available: available[axis],
                    needed: needed[axis],
                    mass: heaviest,
                });
            }
        }
        Ok(())
    }

    fn reform(&self, robots: &[f32], com: Vec2) -> Result<(Positions, f32), AbortReason> {
        let problem = FormationProblem::for_scenario(&self.scenario, com, Some(robots));
        let formation = solve(&problem).map_err(AbortReason::NoBalancedFormation)?;
        Ok((
            formation.positions.iter().copied().collect(),
            formation.figures.det,
        ))
    }

    fn build_flight(&self, robots: &[f32]) -> Result<FlightModel, AbortReason> {
        let e = self.estimator.estimate();
        let com = Vec2::new(e.theta[0], e.theta[1]);
        FlightModel::build(&self.scenario, robots, com, e.theta[2], self.config.mixer)
            .map_err(AbortReason::Uncontrollable)
    }
}

/// Spread of the rotors' thrust about the model's that the yaw axis must absorb (each rotor
/// within 10 % of its model; the campaign's plants spread theirs by up to 8 %).
pub const THRUST_SPREAD: f32 = 0.1;

/// How far the payload's COM may lie from `estimate` on each axis (x, y), m, for the design
/// torque: half a grid cell when the stopping rule passed (it leaves the truth within the
/// MAP's cell), twice the posterior's spread when the lifts ran out and the estimate settled
/// (docs/models.md#grid-posterior-and-stopping-rule).
pub fn com_error(scenario: &Scenario, estimate: &Estimate) -> [f32; 2] {
    let res = scenario.estimation.resolution;
    let half = [0.5 * res[0], 0.5 * res[1]];
    if estimate.status == Status::Settled {
        [
            math::max(half[0], 2.0 * estimate.spread[0]),
            math::max(half[1], 2.0 * estimate.spread[1]),
        ]
    } else {
        half
    }
}

/// The torque a formation must be able to add about each body axis (roll, pitch, yaw), N m, on
/// top of the hover of `weight`, N (docs/failures.md#refused-before-take-off): on roll and
/// pitch the scenario's disturbance torque (which acts on those axes) and the torque of a COM
/// `com_error` (x, y, m: [`com_error`]) from the estimate; on yaw the drag torque of the rotors
/// of one spin all [`THRUST_SPREAD`] strong.
pub fn design_torque(
    scenario: &Scenario,
    weight: f32,
    com_error: [f32; 2],
) -> crate::control::vector::Vec3 {
    let disturbance = scenario.flight.map_or(0.0, |f| f.disturbance_torque);
    crate::control::vector::Vec3::new(
        disturbance + weight * com_error[1],
        disturbance + weight * com_error[0],
        THRUST_SPREAD * 0.5 * weight * scenario.robots.torque_per_thrust,
    )
}
