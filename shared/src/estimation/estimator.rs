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
    /// `max_measurements` lifts were taken without converging.
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
    /// status is [`Status::OutsideGrid`], [`Status::NotConverged`] or [`Status::Converged`]
    /// further readings are refused ([`EstimationError::Finished`]).
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
        if matches!(self.status(), Status::OutsideGrid(_) | Status::NotConverged) {
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
    /// ([`PILED_UP_LN_RATIO`]); not converged once
    /// `max_measurements` lifts were taken without it.
    pub fn status(&self) -> Status {
        if let GridVerdict::Outside(why) = self.outside {
            Status::OutsideGrid(why)
        } else if self.lifted > 0 && !self.piled_up && self.summary.mass_near_map > self.threshold {
            Status::Converged
        } else if self.measurements >= self.max_measurements {
            Status::NotConverged
        } else {
            Status::Measuring
        }
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
mod tests {
    use super::*;
    use crate::liftoff_thrust::lift_off_thrust;
    use crate::paper::{checked, l_sim1, rect_sim1};

    /// The model's reading for the scenario's truth (no noise).
    fn true_reading(scenario: &Scenario, group: usize, scale: f32) -> Measurement {
        let truth = scenario.truth.expect("fixture truth");
        let g = lift_group(scenario, group).expect("group");
        let lambda = lift_off_thrust(
            &scenario.payload.hull,
            truth.com,
            truth.mass,
            &g.rotor_points,
            scenario.robots.mass,
        )
        .expect("truth inside hull")
            * scale;
        if lambda >= scenario.robots.max_thrust {
            Measurement::CouldNotLift
        } else {
            Measurement::Lifted { thrust: lambda }
        }
    }

    fn run_noiseless(scenario: &Scenario, options: EstimatorOptions, scale: f32) -> Estimate {
        let mut e = Estimator::new(scenario, options).expect("estimator");
        while e.status() == Status::Measuring {
            let choice = e.select_group().expect("a group");
            e.update(choice.group, true_reading(scenario, choice.group, scale))
                .expect("update");
        }
        e.estimate()
    }

    #[test]
    fn noiseless_lifts_converge_on_the_truth_within_a_resolution() {
        for input in [rect_sim1(), l_sim1()] {
            let scenario = checked(input);
            let est = run_noiseless(&scenario, EstimatorOptions::default(), 1.0);
            let truth = scenario.truth.unwrap();
            let truth = [truth.com.x, truth.com.y, truth.mass];
            assert_eq!(est.status, Status::Converged, "{est:?}");
            for a in 0..3 {
                let err = (est.theta[a] - truth[a]).abs() / scenario.estimation.resolution[a];
                assert!(err <= 1.0, "axis {a}: {est:?} vs {truth:?}");
            }
            assert!(est.measurements <= 8, "{est:?}");
        }
    }

    #[test]
    fn the_estimate_carries_its_spread_and_the_models_lift_for_the_last_pair() {
        let scenario = checked(rect_sim1());
        let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
        let prior = e.estimate();
        assert_eq!(prior.model_lift, None, "no update yet");
        let mut last = None;
        let mut spread = prior.spread;
        while e.status() == Status::Measuring {
            let g = e.select_group().unwrap().group;
            let reading = true_reading(&scenario, g, 1.0);
            e.update(g, reading).unwrap();
            let est = e.estimate();
            // The spread narrows as lifts come in (never below a cell's own width).
            for a in 0..3 {
                let cell = scenario.estimation.resolution[a] / 12f32.sqrt();
                assert!(est.spread[a] >= cell * 0.999, "axis {a}: {est:?}");
            }
            spread = est.spread;
            last = Some((g, reading, est));
        }
        let (g, reading, est) = last.expect("at least one lift");
        let res = scenario.estimation.resolution;
        for (a, ((now, before), res)) in spread.iter().zip(prior.spread).zip(res).enumerate() {
            assert!(*now < before, "axis {a}: {prior:?} -> {est:?}");
            assert!(*now <= 1.5 * res, "{est:?}");
        }
        // The model at the estimate explains the noiseless reading of its pair within about
        // a resolution's change of prediction.
        let group = lift_group(&scenario, g).unwrap();
        let model = lift_off_thrust(
            &scenario.payload.hull,
            Vec2::new(est.theta[0], est.theta[1]),
            est.theta[2],
            &group.rotor_points,
            scenario.robots.mass,
        );
        assert_eq!(est.model_lift, model);
        if let (Measurement::Lifted { thrust }, Some(m)) = (reading, est.model_lift) {
            assert!((thrust - m).abs() < 0.5, "reading {thrust} N, model {m} N");
        }
    }

    #[test]
    fn l_shape_groups_closer_than_min_spacing_are_unreachable() {
        // Candidates 1.5, 1.72, 1.94 are 0.22 m apart, and 3.3 -> 0.1 across the rail's start
        // is 0.24 m: closer than min_spacing 0.25.
        let e = Estimator::new(&checked(l_sim1()), EstimatorOptions::default()).unwrap();
        let reachable: heapless::Vec<bool, 16> =
            (0..e.group_count()).map(|g| e.is_reachable(g)).collect();
        let unreachable: heapless::Vec<usize, 16> =
            (0..reachable.len()).filter(|&g| !reachable[g]).collect();
        assert_eq!(unreachable.as_slice(), &[4, 5, 10]);
    }

    #[test]
    fn information_falls_as_the_posterior_concentrates() {
        let scenario = checked(rect_sim1());
        let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
        let first = e.select_group().unwrap();
        assert!(first.information > 0.5, "{first:?}");
        for _ in 0..12 {
            let g = e.select_group().unwrap().group;
            e.update(g, true_reading(&scenario, g, 1.0)).unwrap();
        }
        let later = e.select_group().unwrap();
        assert!(
            later.information < 0.5 * first.information,
            "{first:?} {later:?}"
        );
    }

    #[test]
    fn a_thousand_updates_never_underflow() {
        let scenario = checked(rect_sim1());
        let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
        for k in 0..1000 {
            // Deliberately inconsistent readings: the likelihood of every point keeps falling.
            // (The estimator itself stops taking them once no point explains them; the
            // posterior underneath must survive them all.)
            let thrust = if k % 2 == 0 { 2.0 } else { 13.0 };
            let g = e.groups[k % 12];
            let cell = CellModel {
                hull: &e.hull,
                centroid: g.centroid,
                size: g.size,
                robot_mass: e.robot_mass,
            };
            e.posterior.update(
                &e.grid,
                &cell,
                &e.likelihood,
                Measurement::Lifted { thrust },
            );
        }
        e.summarise();
        let ln = e.posterior().ln_values();
        assert!(ln.iter().all(|v| !v.is_nan()));
        assert!(ln.contains(&0.0), "renormalised to a max of 0");
        assert!(e.estimate().confidence.is_finite());
    }

    #[test]
    fn a_reading_no_grid_point_explains_ends_the_estimation_outside_the_grid() {
        let mut scenario = checked(rect_sim1());
        scenario.estimation.noise_sigma = 0.2;
        let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
        // 14 N per robot on a long side: many sigma above what any payload of the grid (at
        // most 4 kg) needs there (about 10 N at most).
        let status = e.update(6, Measurement::Lifted { thrust: 14.0 }).unwrap();
        assert!(
            matches!(
                status,
                Status::OutsideGrid(OutsideGrid::Unexplained { group: 6, .. })
            ),
            "{status:?}"
        );
        assert_eq!(
            e.update(4, Measurement::Lifted { thrust: 5.0 }),
            Err(EstimationError::Finished),
            "no more readings once outside"
        );
    }

    #[test]
    fn a_payload_too_heavy_for_the_grid_is_outside_not_converged() {
        // rect-sim1's truth at 20 kg: beyond what the grid (2.5 to 4 kg) allows. Every lift the
        // MI picks reads "could not lift" where every grid point would have lifted.
        let mut scenario = checked(rect_sim1());
        if let Some(t) = scenario.truth.as_mut() {
            t.mass = 20.0;
        }
        // The mission's noise model (the lift detector's 0.5 N).
        scenario.estimation.noise_sigma = 0.5;
        let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
        let mut status = Status::Measuring;
        while status == Status::Measuring {
            let g = e.select_group().unwrap().group;
            let reading = true_reading(&scenario, g, 1.0);
            assert_eq!(reading, Measurement::CouldNotLift);
            status = e.update(g, reading).unwrap();
        }
        // Either no grid point explains a reading, or the layer beyond the grid's top mass
        // holds far more than the whole grid: outside, either way, within a few lifts.
        assert!(
            matches!(
                status,
                Status::OutsideGrid(
                    OutsideGrid::Unexplained { .. }
                        | OutsideGrid::BeyondEdge {
                            axis: 2,
                            above: true
                        }
                )
            ),
            "{status:?} at 20 kg"
        );
        assert!(e.estimate().measurements <= 4, "{:?}", e.estimate());
    }

    #[test]
    fn censored_readings_alone_never_converge() {
        // A censored reading that the grid can explain (a heavy payload far from the pair)
        // bounds the payload but never locates it: no convergence on it alone, however
        // lenient the threshold.
        let mut scenario = checked(rect_sim1());
        scenario.estimation.threshold = 0.05;
        let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
        // Pair 4 (candidates 1.88, 2.22) at a short end: heavy payloads whose COM lies
        // towards the other end cannot be tipped from there (up to 15 N on the grid).
        let status = e.update(4, Measurement::CouldNotLift).unwrap();
        assert_eq!(status, Status::Measuring, "{:?}", e.estimate());
        assert!(e.estimate().confidence > 0.05, "{:?}", e.estimate());
    }

    #[test]
    fn a_posterior_against_the_top_mass_bounds_the_mass_beyond_the_grid() {
        // Truth 5 kg on a grid that ends at 4 kg: every pair lifts, and two lifts cannot tell
        // a 5 kg payload from a 4 kg one with its COM elsewhere, so the estimate sits on the
        // top edge. The 95 % mass bound (for the thrust-margin check) must then count the
        // layer just above the grid instead of stopping at the grid's top cell.
        let mut scenario = checked(rect_sim1());
        if let Some(t) = scenario.truth.as_mut() {
            t.mass = 5.0;
            t.com = Vec2::new(0.1, 0.0);
        }
        let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
        let mut status = Status::Measuring;
        while status == Status::Measuring {
            let g = e.select_group().unwrap().group;
            status = e.update(g, true_reading(&scenario, g, 1.0)).unwrap();
        }
        let est = e.estimate();
        let top = scenario.estimation.grid_max[2];
        let res = scenario.estimation.resolution[2];
        assert!(
            est.mass_upper_95 > top + 0.5 * res + 1e-3,
            "{est:?}: the bound stops at the grid's top cell"
        );
    }

    #[test]
    fn truths_on_the_grids_edge_still_converge() {
        // The paper's grids with the truth on an edge cell: noiseless lifts converge inside.
        for input in [rect_sim1(), l_sim1()] {
            let base = checked(input);
            let setup = base.estimation;
            for theta in [
                [setup.grid_max[0], 0.0, setup.grid_max[2]],
                [
                    setup.grid_min[0] + 0.3,
                    setup.grid_min[1],
                    setup.grid_min[2],
                ],
            ] {
                let mut scenario = base.clone();
                let com = Vec2::new(theta[0], theta[1]);
                if !scenario.payload.hull.contains(com, 0.0) {
                    continue;
                }
                scenario.truth = Some(crate::scenario::Truth {
                    com,
                    mass: theta[2],
                });
                let est = run_noiseless(&scenario, EstimatorOptions::default(), 1.0);
                assert_eq!(est.status, Status::Converged, "{theta:?}: {est:?}");
            }
        }
    }

    #[test]
    fn could_not_lift_rules_out_the_light_payloads() {
        let scenario = checked(rect_sim1());
        let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
        // Group 8 (candidates 3.44, 3.88) sits on the far long side near the middle.
        e.update(8, Measurement::CouldNotLift).unwrap();
        let grid = *e.grid();
        let mut marginal = [0.0f32; MAX_GRID_POINTS];
        e.posterior().theta_marginal(&grid, &mut marginal);
        let light: f32 = (0..grid.theta_len())
            .filter(|&t| grid.theta(t)[2] < 2.6)
            .map(|t| marginal[t])
            .sum();
        let heavy: f32 = (0..grid.theta_len())
            .filter(|&t| grid.theta(t)[2] > 3.9)
            .map(|t| marginal[t])
            .sum();
        assert!(heavy > light, "heavy {heavy} light {light}");
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let scenario = checked(rect_sim1());
        let mut e = Estimator::new(&scenario, EstimatorOptions::default()).unwrap();
        assert_eq!(
            e.update(99, Measurement::Lifted { thrust: 5.0 }),
            Err(EstimationError::UnknownGroup(99))
        );
        assert_eq!(
            e.update(0, Measurement::Lifted { thrust: f32::NAN }),
            Err(EstimationError::BadReading)
        );
        let too_fine = EstimatorOptions {
            thrust_scale: Some(ThrustScaleAxis {
                min: 0.5,
                max: 2.0,
                step: 0.01,
            }),
        };
        assert!(matches!(
            Estimator::new(&scenario, too_fine),
            Err(EstimationError::Grid(_))
        ));
    }
}
