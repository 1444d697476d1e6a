//! The grid's guard band: one layer of points just beyond each face of the estimation grid,
//! updated with every reading like the grid itself
//! (docs/models.md#grid-posterior-and-stopping-rule; the grid is the prior's support, but a
//! payload need not respect it).
//!
//! The guard band does not move the estimate: the posterior, its MAP and its mean stay on the
//! grid the scenario gives. It answers two questions the grid alone cannot:
//! - how much posterior mass the readings would put just beyond the grid if it were one
//!   point wider (that mass counts against the stopping rule's concentration, so a posterior
//!   that is only concentrated because the grid truncates it does not converge);
//! - whether a layer beyond a face outweighs the whole grid, in which case the truth lies
//!   outside it and no estimate on the grid can be trusted.
//!
//! A guard point gets the prior of a grid point where a payload could be (COM in the
//! footprint's hull, mass above zero) and none elsewhere.

use heapless::Vec;

use crate::estimation::grid::{Grid, GridError};
use crate::estimation::likelihood::{LiftLikelihood, Measurement};
use crate::estimation::posterior::{
    CellModel, CellShares, CellTerms, Posterior, Reading, UpdatePass, UpdateSummary,
};
use crate::geometry::{ConvexHull, Vec2};
use crate::math;
use crate::scenario::MAX_GRID_POINTS;

/// Most guard points (all six faces, thrust scale included): as many as the grid may have.
pub const MAX_GUARD_POINTS: usize = MAX_GRID_POINTS;

/// One face of the grid: the points beyond `axis`'s maximum (`above`) or minimum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Face {
    /// Axis (0: COM x, 1: COM y, 2: mass).
    pub axis: usize,
    /// Beyond the maximum (true) or below the minimum.
    pub above: bool,
    start: usize,
    len: usize,
}

/// The six faces' guard points and their log posterior, on the grid posterior's scale.
#[derive(Clone, Debug, PartialEq)]
pub struct GuardBand {
    faces: [Face; 6],
    /// Flat: face after face, point after point, thrust scale innermost.
    ln_p: Vec<f32, MAX_GUARD_POINTS>,
}

/// The two axes other than `axis`, in order.
fn other_axes(axis: usize) -> [usize; 2] {
    match axis {
        0 => [1, 2],
        1 => [0, 2],
        _ => [0, 1],
    }
}

impl GuardBand {
    /// No guard points: an unloaded estimator's.
    pub const EMPTY: Self = Self {
        faces: [Face {
            axis: 0,
            above: false,
            start: 0,
            len: 0,
        }; 6],
        ln_p: Vec::new(),
    };

    /// The guard band of `grid` on a payload with footprint hull `hull`, with a uniform prior
    /// where a payload could be.
    pub fn new(grid: &Grid, hull: &ConvexHull) -> Result<Self, GridError> {
        let mut band = Self::EMPTY;
        band.reset(grid, hull)?;
        Ok(band)
    }

    /// In place: the guard band of `grid`, as [`Self::new`] makes it.
    pub fn reset(&mut self, grid: &Grid, hull: &ConvexHull) -> Result<(), GridError> {
        let shape = grid.shape();
        let ns = grid.scale_len();
        let mut faces = [Face {
            axis: 0,
            above: false,
            start: 0,
            len: 0,
        }; 6];
        let mut start = 0;
        for (f, face) in faces.iter_mut().enumerate() {
            let axis = f / 2;
            let [b, c] = other_axes(axis);
            let len = shape[b] * shape[c];
            *face = Face {
                axis,
                above: f % 2 == 1,
                start,
                len,
            };
            start += len * ns;
        }
        if start > MAX_GUARD_POINTS {
            return Err(GridError::TooManyGuardPoints { points: start });
        }
        self.faces = faces;
        self.ln_p.clear();
        let res = grid.resolution();
        for face in faces {
            for k in 0..face.len {
                let theta = self.theta(grid, &face, k);
                let possible =
                    theta[2] > res[2] / 3.0 && hull.contains(Vec2::new(theta[0], theta[1]), 1e-6);
                let prior = if possible { 0.0 } else { f32::NEG_INFINITY };
                for _ in 0..ns {
                    // Counted above: fits in MAX_GUARD_POINTS.
                    let _ = self.ln_p.push(prior);
                }
            }
        }
        Ok(())
    }

    /// The faces.
    pub fn faces(&self) -> &[Face; 6] {
        &self.faces
    }

    /// Theta `[x, y, mass]` of guard point `k` of `face`.
    fn theta(&self, grid: &Grid, face: &Face, k: usize) -> [f32; 3] {
        let shape = grid.shape();
        let res = grid.resolution();
        let [b, c] = other_axes(face.axis);
        let (ib, ic) = (k / shape[c], k % shape[c]);
        let mut theta = [0.0; 3];
        theta[b] = grid.axis_value(b, ib);
        theta[c] = grid.axis_value(c, ic);
        theta[face.axis] = if face.above {
            grid.axis_value(face.axis, shape[face.axis] - 1) + res[face.axis]
        } else {
            grid.axis_value(face.axis, 0) - res[face.axis]
        };
        theta
    }

    /// Bayes update with one reading, as [`crate::estimation::posterior::Posterior::update`]
    /// made it on the grid; `shift` is what the grid's update subtracted to renormalise.
    pub fn update(
        &mut self,
        grid: &Grid,
        cell: &CellModel<'_>,
        likelihood: &LiftLikelihood,
        measurement: Measurement,
        shift: f32,
    ) {
        let reading = Reading {
            cell,
            likelihood,
            measurement,
        };
        let res = grid.resolution();
        let mut terms = [0.0; 27];
        for c in 0..grid.com_len() {
            if self.supports_mass_faces(grid, c) {
                let shares = cell.shares(grid.com(c), res[0], res[1]);
                self.weigh_mass_faces(grid, c, &shares, &reading, &mut terms);
            }
        }
        self.finish_update(grid, &reading, shift, &mut terms);
    }

    /// Bayes update of the grid's `posterior` and of the guard band with one reading, as
    /// [`Posterior::update`] and then [`Self::update`] make them, in one pass over the grid's
    /// COM points: the two mass faces lie over the grid's COM points, so each COM's lift
    /// shares (most of a point's cost) serve its grid block and its two mass-face points.
    pub fn update_with_grid(
        &mut self,
        posterior: &mut Posterior,
        grid: &Grid,
        cell: &CellModel<'_>,
        likelihood: &LiftLikelihood,
        measurement: Measurement,
    ) -> UpdateSummary {
        let reading = Reading {
            cell,
            likelihood,
            measurement,
        };
        let res = grid.resolution();
        let mut terms = [0.0; 27];
        let mut pass = UpdatePass::START;
        for c in 0..grid.com_len() {
            let on_grid = posterior.supports_com(grid, c);
            let on_faces = self.supports_mass_faces(grid, c);
            if !on_grid && !on_faces {
                continue;
            }
            let shares = cell.shares(grid.com(c), res[0], res[1]);
            if on_grid {
                posterior.weigh_com(grid, c, &shares, &reading, &mut terms, &mut pass);
            }
            if on_faces {
                self.weigh_mass_faces(grid, c, &shares, &reading, &mut terms);
            }
        }
        let summary = posterior.renormalise(pass);
        self.finish_update(grid, &reading, summary.shift, &mut terms);
        summary
    }

    /// The mass faces (below and above): the last two, each with one point per grid COM.
    fn mass_faces(&self) -> [Face; 2] {
        [self.faces[4], self.faces[5]]
    }

    /// Whether either mass face's points over grid COM point `c` have support.
    fn supports_mass_faces(&self, grid: &Grid, c: usize) -> bool {
        let ns = grid.scale_len();
        self.mass_faces().iter().any(|face| {
            let base = face.start + c * ns;
            self.ln_p[base..base + ns]
                .iter()
                .any(|v| *v != f32::NEG_INFINITY)
        })
    }

    /// Adds the reading's cell log-likelihood to the mass faces' points over grid COM point
    /// `c`, whose cell's lift shares are `shares` (the renormalising shift comes after, in
    /// [`Self::finish_update`]).
    fn weigh_mass_faces(
        &mut self,
        grid: &Grid,
        c: usize,
        shares: &CellShares,
        reading: &Reading<'_, '_>,
        terms: &mut CellTerms,
    ) {
        let ns = grid.scale_len();
        let res_mass = grid.resolution()[2];
        for face in self.mass_faces() {
            let base = face.start + c * ns;
            if self.ln_p[base..base + ns]
                .iter()
                .all(|v| *v == f32::NEG_INFINITY)
            {
                continue;
            }
            let mass = self.theta(grid, &face, c)[2];
            for is in 0..ns {
                let l = reading.cell.likelihood(
                    shares,
                    mass,
                    res_mass,
                    grid.scale(is),
                    reading.likelihood,
                    reading.measurement,
                    terms,
                );
                let slot = &mut self.ln_p[base + is];
                *slot = match l {
                    Some(l) if slot.is_finite() => *slot + l.ln_mean,
                    _ => f32::NEG_INFINITY,
                };
            }
        }
    }

    /// The rest of an update once the mass faces are weighed: the COM faces' points (their
    /// COMs lie beyond the grid's, so they work out their own lift shares), then `shift`
    /// off the mass faces' points.
    fn finish_update(
        &mut self,
        grid: &Grid,
        reading: &Reading<'_, '_>,
        shift: f32,
        terms: &mut CellTerms,
    ) {
        let ns = grid.scale_len();
        let res = grid.resolution();
        // The COM faces list the masses of one COM one after another: its sub-points' lift
        // shares (the geometry, most of a point's cost) are worked out once for them all.
        let mut shares_at: Option<(Vec2, CellShares)> = None;
        for face in &self.faces[..4] {
            for k in 0..face.len {
                let base = face.start + k * ns;
                if self.ln_p[base..base + ns]
                    .iter()
                    .all(|v| *v == f32::NEG_INFINITY)
                {
                    continue;
                }
                let theta = self.theta(grid, face, k);
                let com = Vec2::new(theta[0], theta[1]);
                let shares = match &shares_at {
                    Some((at, shares)) if *at == com => shares,
                    _ => {
                        let shares = reading.cell.shares(com, res[0], res[1]);
                        &shares_at.insert((com, shares)).1
                    }
                };
                for is in 0..ns {
                    let l = reading.cell.likelihood(
                        shares,
                        theta[2],
                        res[2],
                        grid.scale(is),
                        reading.likelihood,
                        reading.measurement,
                        terms,
                    );
                    let slot = &mut self.ln_p[base + is];
                    *slot = match l {
                        Some(l) if slot.is_finite() => *slot + l.ln_mean - shift,
                        _ => f32::NEG_INFINITY,
                    };
                }
            }
        }
        // Every finite mass-face value was weighed in this update (the rest are -inf, which
        // the shift leaves so): `(value + ln_mean) - shift` as the COM faces' points have it.
        for face in self.mass_faces() {
            let ns_len = face.len * ns;
            self.ln_p[face.start..face.start + ns_len]
                .iter_mut()
                .for_each(|v| *v -= shift);
        }
    }

    /// `ln` of the unnormalised posterior mass on `face` (`-inf` when it has none).
    pub fn ln_mass(&self, face: &Face, ns: usize) -> f32 {
        math::ln_sum_exp(&self.ln_p[face.start..face.start + face.len * ns])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimation::grid::Grid;
    use crate::estimation::likelihood::LiftLikelihood;
    use crate::estimation::posterior::Posterior;
    use crate::liftoff_thrust::group_centroid;
    use crate::paper::{checked, rect_sim1};

    /// The one-pass update of the grid and the guard band gives, bit for bit, what the grid's
    /// update and then the guard band's own give (lifted and censored readings, with and
    /// without the thrust-scale axis).
    #[test]
    fn the_update_with_the_grid_is_the_two_updates_bit_for_bit() {
        use crate::estimation::grid::ThrustScaleAxis;
        use crate::paper::l_sim1;
        let readings = [
            (0.12, 0.56, Measurement::Lifted { thrust: 6.2 }),
            (1.88, 2.22, Measurement::Lifted { thrust: 9.1 }),
            (3.0, 3.44, Measurement::CouldNotLift),
            (0.3, 0.9, Measurement::Lifted { thrust: 4.4 }),
        ];
        let scale = ThrustScaleAxis {
            min: 0.9,
            max: 1.1,
            step: 0.1,
        };
        for (input, scale) in [
            (rect_sim1(), None),
            (l_sim1(), None),
            (l_sim1(), Some(scale)),
        ] {
            let scenario = checked(input);
            let hull = &scenario.payload.hull;
            let grid = Grid::new(&scenario.estimation, scale).unwrap();
            let mut apart = (
                Posterior::uniform_on_hull(&grid, hull).unwrap(),
                GuardBand::new(&grid, hull).unwrap(),
            );
            let mut together = apart.clone();
            let likelihood = LiftLikelihood {
                sigma: 1.0,
                max_thrust: 14.2,
            };
            let rail = &scenario.payload.rail;
            for (a, b, reading) in readings {
                let points = [rail.point_at(a), rail.point_at(b)];
                let cell = CellModel {
                    hull,
                    centroid: group_centroid(&points).unwrap(),
                    size: 2,
                    robot_mass: 0.1,
                };
                let update = apart.0.update(&grid, &cell, &likelihood, reading);
                apart
                    .1
                    .update(&grid, &cell, &likelihood, reading, update.shift);
                let joint = together.1.update_with_grid(
                    &mut together.0,
                    &grid,
                    &cell,
                    &likelihood,
                    reading,
                );
                assert_eq!(joint, update);
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<std::vec::Vec<_>>();
                assert_eq!(bits(apart.0.ln_values()), bits(together.0.ln_values()));
                assert_eq!(bits(&apart.1.ln_p), bits(&together.1.ln_p));
            }
        }
    }

    /// The guard band is the grid one point wider, restricted to its outer layers: after the
    /// same readings, each face's mass relative to the inner grid must be what a posterior on
    /// the widened grid holds there.
    #[test]
    fn each_face_holds_what_a_wider_grid_would() {
        let scenario = checked(rect_sim1());
        let hull = &scenario.payload.hull;
        let mut inner_setup = scenario.estimation;
        inner_setup.grid_min = [-0.4, -0.02, 3.0];
        inner_setup.grid_max = [0.4, 0.04, 3.5];
        let mut wide_setup = inner_setup;
        for a in 0..3 {
            wide_setup.grid_min[a] -= inner_setup.resolution[a];
            wide_setup.grid_max[a] += inner_setup.resolution[a];
        }
        let inner = Grid::new(&inner_setup, None).unwrap();
        let wide = Grid::new(&wide_setup, None).unwrap();
        assert_eq!(
            wide.shape(),
            inner.shape().map(|n| n + 2),
            "one point wider on each side"
        );
        let mut posterior = Posterior::uniform_on_hull(&inner, hull).unwrap();
        let mut wide_posterior = Posterior::uniform_on_hull(&wide, hull).unwrap();
        let mut guard = GuardBand::new(&inner, hull).unwrap();
        let likelihood = LiftLikelihood {
            sigma: 1.0,
            max_thrust: 14.2,
        };
        let rail = &scenario.payload.rail;
        let readings = [
            (0.12, 0.56, Measurement::Lifted { thrust: 6.2 }),
            (1.88, 2.22, Measurement::Lifted { thrust: 9.1 }),
            (3.0, 3.44, Measurement::CouldNotLift),
        ];
        for (a, b, reading) in readings {
            let points = [rail.point_at(a), rail.point_at(b)];
            let cell = CellModel {
                hull,
                centroid: group_centroid(&points).unwrap(),
                size: 2,
                robot_mass: 0.1,
            };
            let update = posterior.update(&inner, &cell, &likelihood, reading);
            guard.update(&inner, &cell, &likelihood, reading, update.shift);
            wide_posterior.update(&wide, &cell, &likelihood, reading);
        }
        // The inner grid's mass inside the wide posterior, and each outer layer's.
        let shape = wide.shape();
        let ln = wide_posterior.ln_values();
        let in_range = |i: usize, n: usize| (1..n - 1).contains(&i);
        let mass_where = |keep: &dyn Fn([usize; 3]) -> bool| {
            let terms: std::vec::Vec<f32> = (0..wide.theta_len())
                .filter(|&t| keep(wide.axis_indices(t)))
                .map(|t| ln[t])
                .collect();
            math::ln_sum_exp(&terms)
        };
        let inside = mass_where(&|i| (0..3).all(|a| in_range(i[a], shape[a])));
        for face in guard.faces() {
            let layer = if face.above { shape[face.axis] - 1 } else { 0 };
            let expected = mass_where(&|i| {
                i[face.axis] == layer
                    && (0..3)
                        .filter(|&a| a != face.axis)
                        .all(|a| in_range(i[a], shape[a]))
            }) - inside;
            let got = guard.ln_mass(face, 1) - posterior.ln_total();
            assert!(
                (got - expected).abs() < 1e-3 || (got < -60.0 && expected < -60.0),
                "face {face:?}: guard {got}, wider grid {expected}"
            );
        }
    }
}
