//! The estimation loop as the flight controller runs it (docs/system.md#estimation-loop): choose
//! the lifting group with the most information, take its reading, update, check convergence.
//!
//! The estimator does not move robots or ramp thrust; the mission does that and hands back the
//! [`Measurement`]. Everything here is bounded: fixed-size buffers, one pass over the grid per
//! group per selection.

use heapless::Vec;

use crate::estimation::grid::{Grid, GridError, ThrustScaleAxis};
use crate::estimation::groups::{group_count, lift_group};
use crate::estimation::guard::GuardBand;
use crate::estimation::information::{InformationScratch, mutual_information};
use crate::estimation::likelihood::{LiftLikelihood, Measurement};
use crate::estimation::posterior::{CellModel, Concentration, Posterior, concentration};
use crate::geometry::{ConvexHull, Vec2};
use crate::liftoff_thrust::{lift_fraction, thrust_from_fraction};
use crate::math;
use crate::numbers::Fixed;
use crate::scenario::{MAX_CANDIDATES, MAX_GRID_POINTS, Scenario};

/// Choices of the estimator beyond the scenario.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EstimatorOptions {
    /// Estimate an unknown thrust-scale factor alongside theta (the bias term); off by default.
    pub thrust_scale: Option<ThrustScaleAxis>,
}

/// Why estimation cannot start or go on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EstimationError {
    /// The grid cannot be built.
    Grid(GridError),
    /// No grid COM lies inside the footprint's hull: the prior is empty.
    NoSupport,
    /// No lifting group can be reached by the robots.
    NoReachableGroup,
    /// A group index that does not exist.
    UnknownGroup(usize),
    /// A reading that is not a finite, non-negative thrust.
    BadReading,
    /// The estimation has ended (outside the grid, or out of lifts): no more readings.
    Finished,
    /// The lift readings' standard deviation is not a positive number.
    BadNoiseModel,
}

impl core::fmt::Display for EstimationError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Grid(e) => write!(f, "{e}"),
            Self::NoSupport => write!(f, "no grid COM lies inside the footprint's convex hull"),
            Self::NoReachableGroup => write!(
                f,
                "no lifting group is reachable: adjacent candidates are closer than min_spacing"
            ),
            Self::UnknownGroup(i) => write!(f, "lifting group {i} does not exist"),
            Self::BadReading => write!(f, "a lift reading must be a finite, non-negative thrust"),
            Self::Finished => write!(f, "the estimation has ended; no more readings are taken"),
            Self::BadNoiseModel => write!(
                f,
                "the lift readings' standard deviation must be a positive number of N"
            ),
        }
    }
}

impl core::error::Error for EstimationError {}

/// Whether the readings have put the payload outside the grid. Tagged explicitly with the
/// inside case as tag 0 (an `Option<OutsideGrid>` would code `None` in a spare value of its
/// payload): the unloaded estimator is then all zero bytes, and the flight controller's static
/// of it costs no flash initialiser.
#[repr(u8)]
#[derive(Clone, Copy, Debug, PartialEq)]
enum GridVerdict {
    /// Nothing says otherwise.
    Inside,
    /// Outside, and why.
    Outside(OutsideGrid),
}

/// Why the estimator concluded that the payload lies outside its grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OutsideGrid {
    /// A reading that no grid point explains (see
    /// [`crate::estimation::likelihood::UNEXPLAINED_SIGMAS`]); for a censored reading: every
    /// grid point would have lifted, so the payload is heavier (or its COM further from the
    /// group) than the grid allows.
    Unexplained {
        /// The lifting group.
        group: usize,
        /// Its reading.
        reading: Measurement,
    },
    /// The readings put far more posterior mass on the layer one resolution beyond a face of
    /// the grid than on the whole grid ([`BEYOND_EDGE_LN_RATIO`]; see
    /// [`crate::estimation::guard`]).
    BeyondEdge {
        /// Axis (0: COM x, 1: COM y, 2: mass).
        axis: usize,
        /// True beyond the grid's maximum, false below its minimum.
        above: bool,
    },
}

impl core::fmt::Display for OutsideGrid {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        const AXES: [&str; 3] = ["COM x", "COM y", "mass"];
        match *self {
            Self::Unexplained {
                group,
                reading: Measurement::CouldNotLift,
            } => write!(
                f,
                "pair {group} could not lift where every point of the grid would have: \
                 the payload is heavier than the grid allows or its COM lies outside it"
            ),
            Self::Unexplained {
                group,
                reading: Measurement::Lifted { thrust },
            } => write!(
                f,
                "pair {group} lifted at {} N, which no point of the grid explains",
                Fixed(thrust, 2)
            ),
            Self::BeyondEdge { axis, above } => write!(
                f,
                "the readings point {} the grid's {} on {}",
                if above { "above" } else { "below" },
                if above { "maximum" } else { "minimum" },
                AXES.get(axis).copied().unwrap_or("an axis")
            ),
        }
    }
}

/// Where the estimation stands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Status {
    /// More lifts are needed.
    Measuring,
    /// The posterior mass near the MAP passed the threshold (after at least one lift that
    /// lifted: censored readings alone bound the payload, they never locate it).
    Converged,
    /// `max_measurements` lifts were taken without passing the threshold, but the posterior
    /// is tight enough to fly on: each axis's spread within one grid resolution or, if larger,
    /// [`SETTLED_COM_SPREAD`] (COM) and [`SETTLED_MASS_SPREAD`] of the estimate (mass), nothing
    /// piled up against the grid. The flight plans for the spread left ([`Estimate::spread`]).
    Settled,
    /// `max_measurements` lifts were taken without converging or settling.
    NotConverged,
    /// The readings say the payload lies outside the grid: no estimate can be trusted.
    OutsideGrid(OutsideGrid),
}

/// The chosen lifting group.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroupChoice {
    /// Group index (its first candidate).
    pub group: usize,
    /// Its mutual information with theta, nats.
    pub information: f32,
}

/// The current estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Posterior mean over the MAP's neighbourhood `Theta_N`: [COM x, COM y, mass].
    pub theta: [f32; 3],
    /// The MAP grid point.
    pub map: [f32; 3],
    /// Posterior mass of `Theta_N`.
    pub confidence: f32,
    /// Posterior standard deviation of each axis, [COM x, COM y, mass]
    /// ([`Concentration::spread`]).
    pub spread: [f32; 3],
    /// The lift-off thrust per robot the model predicts at `theta` for the group of the last
    /// update, N (the truth's counterpart of the reading before any thrust scale); `None`
    /// before any update or with `theta`'s COM outside the hull.
    pub model_lift: Option<f32>,
    /// Posterior mean of the thrust-scale factor (1 when the bias term is off).
    pub thrust_scale: f32,
    /// Mass the payload exceeds with at most 5 % posterior probability (upper edge of the cell
    /// where the mass marginal's cumulative reaches 95 %, counting the layer just above the
    /// grid's top mass), kg.
    pub mass_upper_95: f32,
    /// Lifts taken.
    pub measurements: u32,
    /// Where the estimation stands.
    pub status: Status,
}

/// `ln` of how much more posterior mass the layer just beyond a face of the grid must hold
/// than the whole grid before the estimator decides the payload lies outside the grid: a
/// hundred times. Over 600 simulated estimations of truths inside the paper's grids (noise
/// 1 N) the ratio never passed 20 (`ln` 2.98); a payload too heavy to lift, or a reading no
/// grid point explains, passes it at once.
pub const BEYOND_EDGE_LN_RATIO: f32 = 4.6;

/// `ln` of how much more posterior mass the layer just beyond the face the MAP sits on must
/// hold than the whole grid for the posterior to count as piled up against that face (no
/// convergence then): twenty times. Axes the lifts barely observe (the narrow plate's COM y)
/// put a few times the grid's mass just beyond it by noise alone, with the truth inside.
pub const PILED_UP_LN_RATIO: f32 = 3.0;

/// The standard deviation of either COM axis, m, that an estimate which ran out of lifts may
/// have and still be flown on a grid finer than it ([`Status::Settled`]): a fine grid's
/// 3 x 3 x 3 block can be narrower than lifts resolve within their noise. Twice the spread
/// left, times the payload's weight, is then the roll or pitch torque the formation must hold
/// besides the disturbance ([`crate::mission::jobs::design_torque`]).
pub const SETTLED_COM_SPREAD: f32 = 0.025;

/// The standard deviation of the mass, as a share of the estimated mass, that an estimate
/// which ran out of lifts may have and still be flown on a grid finer than it
/// ([`Status::Settled`]): the take-off's feed-forward 15 % off at worst, which its
/// integrators absorb.
pub const SETTLED_MASS_SPREAD: f32 = 0.15;

#[derive(Clone, Copy, Debug, PartialEq)]
struct GroupGeometry {
    centroid: Vec2,
    size: usize,
    reachable: bool,
}

/// The estimation state machine.
#[derive(Clone, Debug)]
pub struct Estimator {
    grid: Grid,
    hull: ConvexHull,
    groups: Vec<GroupGeometry, MAX_CANDIDATES>,
    likelihood: LiftLikelihood,
    robot_mass: f32,
    threshold: f32,
    max_measurements: u32,
    posterior: Posterior,
    guard: GuardBand,
    measurements: u32,
    /// Readings that lifted (censored ones alone bound the payload, they never locate it).
    lifted: u32,
    outside: GridVerdict,
    summary: Concentration,
    /// The posterior is piled up against an edge of the grid (see [`Self::status`]).
    piled_up: bool,
    mass_upper_95: f32,
    /// The model's lift-off thrust at the estimate for the last update's group, N.
    model_lift: Option<f32>,
    probabilities: Vec<f32, MAX_GRID_POINTS>,
    fractions: Vec<f32, MAX_GRID_POINTS>,
    scratch: InformationScratch,
}

impl Estimator {
    /// An estimator with a uniform prior for `scenario`.
    pub fn new(scenario: &Scenario, options: EstimatorOptions) -> Result<Self, EstimationError> {
        let mut estimator = Self::UNLOADED;
        estimator.load(scenario, options)?;
        Ok(estimator)
    }

    /// An estimator with no scenario: every buffer empty, nothing to estimate until
    /// [`Self::load`]. A constant, so the flight controller can place the estimator (with its
    /// grid-sized buffers) in a static instead of building it on a stack.
    pub const UNLOADED: Self = Self {
        grid: Grid::EMPTY,
        hull: ConvexHull::EMPTY,
        groups: Vec::new(),
        likelihood: LiftLikelihood {
            sigma: 0.0,
            max_thrust: 0.0,
        },
        robot_mass: 0.0,
        threshold: 0.0,
        max_measurements: 0,
        posterior: Posterior::EMPTY,
        guard: GuardBand::EMPTY,
        measurements: 0,
        lifted: 0,
        outside: GridVerdict::Inside,
        summary: Concentration {
            map_indices: [0; 3],
            map: [0.0; 3],
            mass_near_map: 0.0,
            local_mean: [0.0; 3],
            spread: [0.0; 3],
        },
        piled_up: false,
        mass_upper_95: 0.0,
        model_lift: None,
        probabilities: Vec::new(),
        fractions: Vec::new(),
        scratch: InformationScratch::EMPTY,
    };

    /// In place: the estimator of `scenario` with a uniform prior, as [`Self::new`] builds
    /// it, without a second copy of the buffers. On an error the estimator is left unloaded.
    pub fn load(
        &mut self,
        scenario: &Scenario,
        options: EstimatorOptions,
    ) -> Result<(), EstimationError> {
        let loaded = self.fill(scenario, options);
        if loaded.is_err() {
            self.grid = Grid::EMPTY;
            self.posterior.reset_on_hull(&Grid::EMPTY, &self.hull);
            self.groups.clear();
        }
        loaded
    }

    fn fill(
        &mut self,
        scenario: &Scenario,
        options: EstimatorOptions,
    ) -> Result<(), EstimationError> {
        self.grid =
            Grid::new(&scenario.estimation, options.thrust_scale).map_err(EstimationError::Grid)?;
        self.hull.clone_from(&scenario.payload.hull);
        if !self.posterior.reset_on_hull(&self.grid, &self.hull) {
            return Err(EstimationError::NoSupport);
        }
        self.guard
            .reset(&self.grid, &self.hull)
            .map_err(EstimationError::Grid)?;
        self.groups.clear();
        for g in (0..group_count(scenario)).filter_map(|i| lift_group(scenario, i)) {
            // group_count <= MAX_CANDIDATES.
            let _ = self.groups.push(GroupGeometry {
                centroid: g.centroid,
                size: g.rotor_points.len(),
                reachable: g.reachable,
            });
        }
        if !self.groups.iter().any(|g| g.reachable) {
            return Err(EstimationError::NoReachableGroup);
        }
        self.probabilities.clear();
        let _ = self.probabilities.resize(self.grid.len(), 0.0);
        self.fractions.clear();
        let _ = self.fractions.resize(self.grid.com_len(), 0.0);
        self.likelihood = LiftLikelihood {
            sigma: scenario.estimation.noise_sigma,
            max_thrust: scenario.robots.max_thrust,
        };
        self.robot_mass = scenario.robots.mass;
        self.threshold = scenario.estimation.threshold;
        self.max_measurements = scenario.estimation.max_measurements;
        self.measurements = 0;
        self.lifted = 0;
        self.outside = GridVerdict::Inside;
        self.model_lift = None;
        self.summarise();
        Ok(())
    }

    /// The grid.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// The posterior.
    pub fn posterior(&self) -> &Posterior {
        &self.posterior
    }

    /// For each face of the grid (x below, x above, y below, y above, mass below, mass
    /// above): `ln` of the posterior mass the readings put on the layer just beyond it,
    /// relative to the whole grid's (see [`crate::estimation::guard`]).
    pub fn beyond_grid(&self) -> [f32; 6] {
        let ln_grid = self.posterior.ln_total();
        let ns = self.grid.scale_len();
        self.guard
            .faces()
            .map(|face| self.guard.ln_mass(&face, ns) - ln_grid)
    }

    /// Number of lifting groups (reachable or not).
    pub fn group_count(&self) -> usize {
        self.groups.len()
    }

    /// Whether the robots can stand at group `group`.
    pub fn is_reachable(&self, group: usize) -> bool {
        self.groups.get(group).is_some_and(|g| g.reachable)
    }

    fn fill_fractions(&mut self, group: usize) -> Result<(), EstimationError> {
        let g = *self
            .groups
            .get(group)
            .ok_or(EstimationError::UnknownGroup(group))?;
        for c in 0..self.grid.com_len() {
            self.fractions[c] =
                lift_fraction(&self.hull, self.grid.com(c), g.centroid, g.size).unwrap_or(0.0);
        }
        Ok(())
    }

    /// Mutual information of each group's next reading (nats) into `out`, `None` for groups
    /// the robots cannot reach. `out` shorter than [`Self::group_count`] gets the first ones.
    pub fn information_per_group(&mut self, out: &mut [Option<f32>]) {
        self.posterior.probabilities(&mut self.probabilities);
        for (group, slot) in out.iter_mut().enumerate().take(self.groups.len()) {
            *slot = None;
            if !self.groups[group].reachable || self.fill_fractions(group).is_err() {
                continue;
            }
            *slot = Some(mutual_information(
                &self.grid,
                &self.probabilities,
                &self.fractions,
                self.robot_mass,
                &self.likelihood,
                &mut self.scratch,
            ));
        }
    }

    /// The reachable group whose reading carries the most information (lowest index on ties).
    pub fn select_group(&mut self) -> Result<GroupChoice, EstimationError> {
        let mut scores = [None; MAX_CANDIDATES];
        self.information_per_group(&mut scores);
        scores
            .iter()
            .enumerate()
            .filter_map(|(group, s)| s.map(|information| GroupChoice { group, information }))
            .fold(None, |best: Option<GroupChoice>, c| match best {
                Some(b) if b.information >= c.information => Some(b),
                _ => Some(c),
            })
            .ok_or(EstimationError::NoReachableGroup)
    }

    /// Bayes update with the reading of group `group`; returns the new status. Once the
    /// status is [`Status::OutsideGrid`], [`Status::NotConverged`], [`Status::Settled`] or
    /// [`Status::Converged`] further readings are refused ([`EstimationError::Finished`]).
    pub fn update(
        &mut self,
        group: usize,
        measurement: Measurement,
    ) -> Result<Status, EstimationError> {
        if let Measurement::Lifted { thrust } = measurement {
            if !thrust.is_finite() || thrust < 0.0 {
                return Err(EstimationError::BadReading);
            }
        }
        let g = *self
            .groups
            .get(group)
            .ok_or(EstimationError::UnknownGroup(group))?;
        if matches!(
            self.status(),
            Status::OutsideGrid(_) | Status::NotConverged | Status::Settled
        ) {
            return Err(EstimationError::Finished);
        }
        let cell = CellModel {
            hull: &self.hull,
            centroid: g.centroid,
            size: g.size,
            robot_mass: self.robot_mass,
        };
        let update = self.guard.update_with_grid(
            &mut self.posterior,
            &self.grid,
            &cell,
            &self.likelihood,
            measurement,
        );
        self.measurements += 1;
        if matches!(measurement, Measurement::Lifted { .. }) {
            self.lifted += 1;
        }
        if !self.likelihood.explains(measurement, update.ln_best) {
            self.outside = GridVerdict::Outside(OutsideGrid::Unexplained {
                group,
                reading: measurement,
            });
        }
        self.summarise();
        let theta = self.summary.local_mean;
        self.model_lift = lift_fraction(
            &self.hull,
            Vec2::new(theta[0], theta[1]),
            g.centroid,
            g.size,
        )
        .map(|f| thrust_from_fraction(f, theta[2], self.robot_mass));
        Ok(self.status())
    }

    fn summarise(&mut self) {
        // The guard band against the grid: both unnormalised on the same scale.
        let ln_ratios = self.beyond_grid();
        let marginal = &mut self.probabilities[..self.grid.theta_len()];
        self.posterior.theta_marginal(&self.grid, marginal);
        self.summary = concentration(&self.grid, marginal);
        let shape = self.grid.shape();
        self.piled_up = false;
        for (face, &ln_ratio) in self.guard.faces().iter().zip(&ln_ratios) {
            let edge = if face.above { shape[face.axis] - 1 } else { 0 };
            self.piled_up |=
                ln_ratio > PILED_UP_LN_RATIO && self.summary.map_indices[face.axis] == edge;
            if ln_ratio > BEYOND_EDGE_LN_RATIO
                && self.measurements > 0
                && self.outside == GridVerdict::Inside
            {
                self.outside = GridVerdict::Outside(OutsideGrid::BeyondEdge {
                    axis: face.axis,
                    above: face.above,
                });
            }
        }
        // The mass marginal's 95 % quantile (cell upper edge), the layer above the grid's top
        // mass counted: a posterior piled up against the top does not hide a heavier payload.
        let nm = shape[2];
        let above = math::exp(math::min(ln_ratios[5], 30.0));
        let mut cumulative = 0.0;
        let mut upper = self.grid.mass(nm - 1) + self.grid.resolution()[2];
        for im in 0..nm {
            cumulative += marginal
                .iter()
                .enumerate()
                .filter(|(t, _)| t % nm == im)
                .map(|(_, p)| *p)
                .sum::<f32>()
                / (1.0 + above);
            if cumulative >= 0.95 {
                upper = self.grid.mass(im);
                break;
            }
        }
        self.mass_upper_95 = upper + 0.5 * self.grid.resolution()[2];
    }

    /// Where the estimation stands: outside the grid once the readings say so; converged once
    /// the mass near the MAP exceeds the threshold, after at least one lift that lifted and
    /// with the posterior not piled up against an edge of the grid
    /// ([`PILED_UP_LN_RATIO`]); once `max_measurements` lifts were taken without it, settled
    /// when the posterior is tight enough to fly on, not converged otherwise.
    pub fn status(&self) -> Status {
        if let GridVerdict::Outside(why) = self.outside {
            Status::OutsideGrid(why)
        } else if self.lifted > 0 && !self.piled_up && self.summary.mass_near_map > self.threshold {
            Status::Converged
        } else if self.measurements >= self.max_measurements {
            if self.lifted > 0 && !self.piled_up && self.is_tight() {
                Status::Settled
            } else {
                Status::NotConverged
            }
        } else {
            Status::Measuring
        }
    }

    /// Whether the posterior's spread is tight enough to fly on: each COM axis within one
    /// grid resolution or [`SETTLED_COM_SPREAD`], whichever is larger, and the mass within
    /// one resolution or [`SETTLED_MASS_SPREAD`] of the estimated mass.
    fn is_tight(&self) -> bool {
        let [x, y, m] = self.summary.spread;
        let res = self.grid.resolution();
        let mass = self.summary.local_mean[2];
        x <= math::max(res[0], SETTLED_COM_SPREAD)
            && y <= math::max(res[1], SETTLED_COM_SPREAD)
            && m <= math::max(res[2], SETTLED_MASS_SPREAD * mass)
    }

    /// The current estimate.
    pub fn estimate(&self) -> Estimate {
        Estimate {
            theta: self.summary.local_mean,
            map: self.summary.map,
            confidence: self.summary.mass_near_map,
            spread: self.summary.spread,
            model_lift: self.model_lift,
            thrust_scale: self.posterior.mean_scale(&self.grid),
            mass_upper_95: self.mass_upper_95,
            measurements: self.measurements,
            status: self.status(),
        }
    }
}

#[cfg(test)]
mod tests;
