//! The estimation loop as the flight controller runs it (SPEC.md section 2, step 1): choose the
//! lifting group with the most information, take its reading, update, check convergence.
//!
//! The estimator does not move robots or ramp thrust; the mission does that and hands back the
//! [`Measurement`]. Everything here is bounded: fixed-size buffers, one pass over the grid per
//! group per selection.

use heapless::Vec;

use crate::estimation::grid::{Grid, GridError, ThrustScaleAxis};
use crate::estimation::groups::{group_count, lift_group};
use crate::estimation::information::{InformationScratch, mutual_information};
use crate::estimation::likelihood::{LiftLikelihood, Measurement};
use crate::estimation::posterior::{CellModel, Concentration, Posterior, concentration};
use crate::geometry::{ConvexHull, Vec2};
use crate::scenario::{MAX_CANDIDATES, MAX_GRID_POINTS, Scenario};
use crate::statics::lift_fraction;

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
        }
    }
}

impl core::error::Error for EstimationError {}

/// Where the estimation stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// More lifts are needed.
    Measuring,
    /// The posterior mass near the MAP passed the threshold.
    Converged,
    /// `max_measurements` lifts were taken without converging.
    NotConverged,
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
    /// Posterior mean of the thrust-scale factor (1 when the bias term is off).
    pub thrust_scale: f32,
    /// Mass the payload exceeds with at most 5 % posterior probability (upper edge of the cell
    /// where the mass marginal's cumulative reaches 95 %), kg.
    pub mass_upper_95: f32,
    /// Lifts taken.
    pub measurements: u32,
    /// Where the estimation stands.
    pub status: Status,
}

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
    measurements: u32,
    summary: Concentration,
    mass_upper_95: f32,
    probabilities: Vec<f32, MAX_GRID_POINTS>,
    fractions: Vec<f32, MAX_GRID_POINTS>,
    scratch: InformationScratch,
}

impl Estimator {
    /// An estimator with a uniform prior for `scenario`.
    pub fn new(scenario: &Scenario, options: EstimatorOptions) -> Result<Self, EstimationError> {
        let grid =
            Grid::new(&scenario.estimation, options.thrust_scale).map_err(EstimationError::Grid)?;
        let hull = scenario.payload.hull.clone();
        let posterior =
            Posterior::uniform_on_hull(&grid, &hull).ok_or(EstimationError::NoSupport)?;
        let groups: Vec<GroupGeometry, MAX_CANDIDATES> = (0..group_count(scenario))
            .filter_map(|i| lift_group(scenario, i))
            .map(|g| GroupGeometry {
                centroid: g.centroid,
                size: g.rotor_points.len(),
                reachable: g.reachable,
            })
            .collect();
        if !groups.iter().any(|g| g.reachable) {
            return Err(EstimationError::NoReachableGroup);
        }
        let mut probabilities = Vec::new();
        let _ = probabilities.resize(grid.len(), 0.0);
        let mut fractions = Vec::new();
        let _ = fractions.resize(grid.com_len(), 0.0);
        let mut estimator = Self {
            grid,
            hull,
            groups,
            likelihood: LiftLikelihood {
                sigma: scenario.estimation.noise_sigma,
                max_thrust: scenario.robots.max_thrust,
            },
            robot_mass: scenario.robots.mass,
            threshold: scenario.estimation.threshold,
            max_measurements: scenario.estimation.max_measurements,
            posterior,
            measurements: 0,
            summary: Concentration {
                map_indices: [0; 3],
                map: [0.0; 3],
                mass_near_map: 0.0,
                local_mean: [0.0; 3],
            },
            mass_upper_95: 0.0,
            probabilities,
            fractions,
            scratch: InformationScratch::default(),
        };
        estimator.summarise();
        Ok(estimator)
    }

    /// The grid.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// The posterior.
    pub fn posterior(&self) -> &Posterior {
        &self.posterior
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

    /// Bayes update with the reading of group `group`; returns the new status.
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
        let cell = CellModel {
            hull: &self.hull,
            centroid: g.centroid,
            size: g.size,
            robot_mass: self.robot_mass,
        };
        self.posterior
            .update(&self.grid, &cell, &self.likelihood, measurement);
        self.measurements += 1;
        self.summarise();
        Ok(self.status())
    }

    fn summarise(&mut self) {
        let marginal = &mut self.probabilities[..self.grid.theta_len()];
        self.posterior.theta_marginal(&self.grid, marginal);
        self.summary = concentration(&self.grid, marginal);
        // The mass marginal's 95 % quantile (cell upper edge).
        let [_, _, nm] = self.grid.shape();
        let mut cumulative = 0.0;
        let mut upper = self.grid.mass(nm - 1);
        for im in 0..nm {
            cumulative += marginal
                .iter()
                .enumerate()
                .filter(|(t, _)| t % nm == im)
                .map(|(_, p)| *p)
                .sum::<f32>();
            if cumulative >= 0.95 {
                upper = self.grid.mass(im);
                break;
            }
        }
        self.mass_upper_95 = upper + 0.5 * self.grid.resolution()[2];
    }

    /// Where the estimation stands: converged once the mass near the MAP exceeds the threshold,
    /// not converged once `max_measurements` lifts were taken without it.
    pub fn status(&self) -> Status {
        if self.measurements > 0 && self.summary.mass_near_map > self.threshold {
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
    use crate::paper::{checked, l_sim1, rect_sim1};
    use crate::statics::lift_off_thrust;

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
            let thrust = if k % 2 == 0 { 2.0 } else { 13.0 };
            e.update(k % 12, Measurement::Lifted { thrust }).unwrap();
        }
        let ln = e.posterior().ln_values();
        assert!(ln.iter().all(|v| !v.is_nan()));
        assert!(ln.contains(&0.0), "renormalised to a max of 0");
        assert!(e.estimate().confidence.is_finite());
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
