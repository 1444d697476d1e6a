//! The grid posterior over theta (and the thrust scale, when on), kept as log-probabilities so
//! that long runs never underflow (docs/models.md#grid-posterior-and-stopping-rule; Bayes'
//! rule and the stopping rule of Oishi & Jimbo (2025)).
//!
//! The prior is uniform on the grid points whose COM lies in the footprint's convex hull and
//! zero elsewhere. After each update the log-values are shifted so the largest is 0.

use heapless::Vec;

use crate::estimation::grid::Grid;
use crate::estimation::likelihood::{LiftLikelihood, Measurement};
use crate::geometry::{ConvexHull, Vec2};
use crate::liftoff_thrust::{lift_fraction, thrust_from_fraction};
use crate::math;
use crate::scenario::MAX_GRID_POINTS;

/// Predicted lift-off reading at grid point (COM with share `fraction`, mass `im`, scale `is`):
/// the thrust the flight controller believes it applies, `s * (m_r g + M g f)`.
pub fn predicted_reading(grid: &Grid, fraction: f32, im: usize, is: usize, robot_mass: f32) -> f32 {
    grid.scale(is) * thrust_from_fraction(fraction, grid.mass(im), robot_mass)
}

/// Sub-point offsets within a cell, in resolutions.
const SUB_OFFSETS: [f32; 3] = [-1.0 / 3.0, 0.0, 1.0 / 3.0];

/// The lift shares of one COM cell's sub-points, and `ln` of the number of likelihood terms
/// they make with the mass sub-points.
#[derive(Clone, Debug, PartialEq)]
pub struct CellShares {
    shares: Vec<f32, 9>,
    ln_terms: f32,
}

/// Scratch for one cell's likelihood terms: 9 COM sub-points times 3 mass sub-points.
pub type CellTerms = [f32; 27];

/// What one update did to the posterior.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UpdateSummary {
    /// The largest sub-point log-likelihood over the points with prior support: how well the
    /// best-explaining point explains the reading (`-inf` when no point has support).
    pub ln_best: f32,
    /// What was subtracted from every log-value to bring the largest back to 0.
    pub shift: f32,
}

/// The running largest values of one update's pass over the grid's COM blocks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UpdatePass {
    /// The largest updated log-value so far.
    top: f32,
    /// The largest sub-point log-likelihood so far.
    best: f32,
}

impl UpdatePass {
    /// A pass that has weighed nothing yet.
    pub const START: Self = Self {
        top: f32::NEG_INFINITY,
        best: f32::NEG_INFINITY,
    };
}

/// The lifting group and robots a reading came from, as the cell likelihood needs them.
#[derive(Clone, Copy, Debug)]
pub struct CellModel<'a> {
    /// The footprint's convex hull.
    pub hull: &'a ConvexHull,
    /// Centroid of the group's rotor points.
    pub centroid: Vec2,
    /// Robots in the group.
    pub size: usize,
    /// Mass of one robot, kg.
    pub robot_mass: f32,
}

/// One reading and what it is weighed with: the group's cell model and the noise model.
#[derive(Clone, Copy, Debug)]
pub struct Reading<'a, 'h> {
    /// The lifting group and robots.
    pub cell: &'a CellModel<'h>,
    /// The noise and the censoring limit.
    pub likelihood: &'a LiftLikelihood,
    /// What the lift produced.
    pub measurement: Measurement,
}

/// A reading's log-likelihood over one cell: the cell average and the best single sub-point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellLikelihood {
    /// `ln(mean(likelihood))` over the cell's sub-points.
    pub ln_mean: f32,
    /// The largest sub-point log-likelihood: how well the best point of the cell explains the
    /// reading.
    pub ln_best: f32,
}

impl CellModel<'_> {
    /// Lift shares of the COM sub-points of the cell centred on `centre` (COM resolutions
    /// `res_x`, `res_y`) that lie in the hull; empty when none does.
    pub fn shares(&self, centre: Vec2, res_x: f32, res_y: f32) -> CellShares {
        let mut shares = Vec::new();
        for dx in SUB_OFFSETS {
            for dy in SUB_OFFSETS {
                let com = Vec2::new(centre.x + dx * res_x, centre.y + dy * res_y);
                if let Some(f) = lift_fraction(self.hull, com, self.centroid, self.size) {
                    // At most 9 sub-points.
                    let _ = shares.push(f);
                }
            }
        }
        // Each share meets the three mass sub-points: `ln` of that many terms, once per cell
        // rather than at each of its masses and scales.
        let ln_terms = math::ln((shares.len() * SUB_OFFSETS.len()) as f32);
        CellShares { shares, ln_terms }
    }

    /// The reading's log-likelihood over the cell of COM shares `shares`, mass `mass` (mass
    /// resolution `res_mass`) and thrust scale `scale`; `None` when `shares` is empty.
    /// `terms` is scratch for the sub-points' terms (its contents on entry do not matter: a
    /// caller keeps one for a whole update instead of clearing a fresh one per cell).
    #[allow(clippy::too_many_arguments)]
    pub fn likelihood(
        &self,
        shares: &CellShares,
        mass: f32,
        res_mass: f32,
        scale: f32,
        likelihood: &LiftLikelihood,
        measurement: Measurement,
        terms: &mut CellTerms,
    ) -> Option<CellLikelihood> {
        // At most 9 shares times 3 masses; the largest term kept as they come (it is both
        // the best and the shift of the log-mean-exp).
        let mut len = 0;
        let mut top = f32::NEG_INFINITY;
        for &f in &shares.shares {
            for dm in SUB_OFFSETS {
                let predicted =
                    scale * thrust_from_fraction(f, mass + dm * res_mass, self.robot_mass);
                let term = likelihood.ln_likelihood(measurement, predicted);
                terms[len] = term;
                len += 1;
                top = math::max(top, term);
            }
        }
        if len == 0 {
            return None;
        }
        // ln(mean(exp(terms))) without overflow or underflow.
        Some(CellLikelihood {
            ln_mean: math::ln_sum_exp_from(&terms[..len], top) - shares.ln_terms,
            ln_best: top,
        })
    }
}

/// Unnormalised log posterior on every grid point.
#[derive(Clone, Debug, PartialEq)]
pub struct Posterior {
    ln_p: Vec<f32, MAX_GRID_POINTS>,
}

impl Posterior {
    /// No values: an unloaded estimator's.
    pub const EMPTY: Self = Self { ln_p: Vec::new() };

    /// Uniform prior on the points whose COM lies in `hull`; `None` when no grid COM does.
    pub fn uniform_on_hull(grid: &Grid, hull: &ConvexHull) -> Option<Self> {
        let mut posterior = Self::EMPTY;
        posterior.reset_on_hull(grid, hull).then_some(posterior)
    }

    /// In place: the uniform prior on the points whose COM lies in `hull`; false (and no
    /// support at all) when no grid COM does.
    pub fn reset_on_hull(&mut self, grid: &Grid, hull: &ConvexHull) -> bool {
        let block = grid.len() / grid.com_len().max(1);
        self.ln_p.clear();
        let mut any = false;
        for c in 0..grid.com_len() {
            let inside = hull.contains(grid.com(c), 1e-6);
            any |= inside;
            let v = if inside { 0.0 } else { f32::NEG_INFINITY };
            for _ in 0..block {
                // grid.len() <= MAX_GRID_POINTS by Grid::new.
                let _ = self.ln_p.push(v);
            }
        }
        any
    }

    /// The log-values, flat in the grid's layout.
    pub fn ln_values(&self) -> &[f32] {
        &self.ln_p
    }

    /// Bayes update with one reading of the group `cell`.
    ///
    /// Each grid point stands for its cell (`+-res/2` on every theta axis): its likelihood is
    /// the reading's likelihood averaged over the cell, by `3 x 3 x 3` sub-points at
    /// `-res/3, 0, +res/3` combined in the log domain. A truth between grid points then
    /// weighs its neighbouring cells as it should, where a point likelihood would lock onto
    /// whichever point predicts nearest (neighbouring points' predictions differ by about
    /// `sigma` on the paper's grids, so the point posterior is overconfident).
    ///
    /// [`crate::estimation::guard::GuardBand::update_with_grid`] makes the same update and
    /// the guard band's in one pass.
    pub fn update(
        &mut self,
        grid: &Grid,
        cell: &CellModel<'_>,
        likelihood: &LiftLikelihood,
        measurement: Measurement,
    ) -> UpdateSummary {
        let res = grid.resolution();
        let mut terms = [0.0; 27];
        let mut pass = UpdatePass::START;
        for c in 0..grid.com_len() {
            if self.supports_com(grid, c) {
                let shares = cell.shares(grid.com(c), res[0], res[1]);
                let reading = Reading {
                    cell,
                    likelihood,
                    measurement,
                };
                self.weigh_com(grid, c, &shares, &reading, &mut terms, &mut pass);
            }
        }
        self.renormalise(pass)
    }

    /// Whether any point of COM point `c`'s block (its masses and scales) has support.
    pub fn supports_com(&self, grid: &Grid, c: usize) -> bool {
        let block = grid.len() / grid.com_len().max(1);
        self.ln_p[c * block..(c + 1) * block]
            .iter()
            .any(|v| *v != f32::NEG_INFINITY)
    }

    /// The first half of [`Self::update`] for COM point `c`, whose cell's lift shares are
    /// `shares`: adds the reading's cell log-likelihood to each supported point of its block
    /// and keeps the largest values in `pass`.
    pub fn weigh_com(
        &mut self,
        grid: &Grid,
        c: usize,
        shares: &CellShares,
        reading: &Reading<'_, '_>,
        terms: &mut CellTerms,
        pass: &mut UpdatePass,
    ) {
        let (nm, ns) = (grid.shape()[2], grid.scale_len());
        let res_mass = grid.resolution()[2];
        for im in 0..nm {
            for is in 0..ns {
                let i = (c * nm + im) * ns + is;
                if self.ln_p[i] == f32::NEG_INFINITY {
                    continue;
                }
                let Some(l) = reading.cell.likelihood(
                    shares,
                    grid.mass(im),
                    res_mass,
                    grid.scale(is),
                    reading.likelihood,
                    reading.measurement,
                    terms,
                ) else {
                    continue;
                };
                self.ln_p[i] += l.ln_mean;
                pass.top = math::max(pass.top, self.ln_p[i]);
                pass.best = math::max(pass.best, l.ln_best);
            }
        }
    }

    /// The second half of [`Self::update`], once every COM block is weighed: shifts the
    /// log-values so that the largest is 0.
    pub fn renormalise(&mut self, pass: UpdatePass) -> UpdateSummary {
        let shift = if pass.top.is_finite() { pass.top } else { 0.0 };
        self.ln_p
            .iter_mut()
            .filter(|v| v.is_finite())
            .for_each(|v| *v -= shift);
        UpdateSummary {
            ln_best: pass.best,
            shift,
        }
    }

    /// `ln` of the unnormalised posterior mass of the whole grid.
    pub fn ln_total(&self) -> f32 {
        math::ln_sum_exp(&self.ln_p)
    }

    /// Normalised probabilities of every grid point into `out` (length `grid.len()`).
    pub fn probabilities(&self, out: &mut [f32]) {
        let mut total = 0.0;
        for (o, &l) in out.iter_mut().zip(self.ln_p.iter()) {
            *o = if l.is_finite() { math::exp(l) } else { 0.0 };
            total += *o;
        }
        if total > 0.0 {
            out.iter_mut().for_each(|o| *o /= total);
        }
    }

    /// Normalised marginal over theta (the thrust scale summed out) into `out` (length
    /// `grid.theta_len()`).
    pub fn theta_marginal(&self, grid: &Grid, out: &mut [f32]) {
        let ns = grid.scale_len();
        let mut total = 0.0;
        for (t, o) in out.iter_mut().enumerate().take(grid.theta_len()) {
            *o = self.ln_p[t * ns..(t + 1) * ns]
                .iter()
                .filter(|l| l.is_finite())
                .map(|&l| math::exp(l))
                .sum();
            total += *o;
        }
        if total > 0.0 {
            out.iter_mut().for_each(|o| *o /= total);
        }
    }

    /// Posterior mean of the thrust scale (1 without the axis).
    pub fn mean_scale(&self, grid: &Grid) -> f32 {
        let ns = grid.scale_len();
        let (mut total, mut weighted) = (0.0, 0.0);
        for (i, &l) in self.ln_p.iter().enumerate() {
            if l.is_finite() {
                let w = math::exp(l);
                total += w;
                weighted += w * grid.scale(i % ns);
            }
        }
        if total > 0.0 { weighted / total } else { 1.0 }
    }
}

/// The stopping rule's view of a theta marginal: the MAP point and the posterior mass of
/// `Theta_N`, the points within one resolution of it on every axis
/// (docs/models.md#grid-posterior-and-stopping-rule).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Concentration {
    /// Grid indices of the MAP point.
    pub map_indices: [usize; 3],
    /// Theta value of the MAP point.
    pub map: [f32; 3],
    /// Posterior mass of `Theta_N`.
    pub mass_near_map: f32,
    /// Posterior mean of theta over `Theta_N`: the estimate, finer than the grid.
    pub local_mean: [f32; 3],
    /// Posterior standard deviation of each theta axis over the whole marginal, each point
    /// standing for its cell (the cell's own `res / sqrt(12)` counted): [COM x, COM y, mass].
    pub spread: [f32; 3],
}

/// Finds the MAP of the normalised theta marginal `marginal`, the mass around it and the
/// marginal's spread.
pub fn concentration(grid: &Grid, marginal: &[f32]) -> Concentration {
    let best = marginal.iter().enumerate().take(grid.theta_len()).fold(
        (0, f32::NEG_INFINITY),
        |acc, (i, &p)| if p > acc.1 { (i, p) } else { acc },
    );
    let map_indices = grid.axis_indices(best.0);
    let shape = grid.shape();
    let range =
        |a: usize| map_indices[a].saturating_sub(1)..=(map_indices[a] + 1).min(shape[a] - 1);
    let (mut mass, mut sum) = (0.0, [0.0f32; 3]);
    for ix in range(0) {
        for iy in range(1) {
            for im in range(2) {
                let t = grid.theta_index([ix, iy, im]);
                let p = marginal[t];
                let theta = grid.theta(t);
                mass += p;
                for a in 0..3 {
                    sum[a] += p * theta[a];
                }
            }
        }
    }
    let map = grid.theta(best.0);
    let local_mean = if mass > 0.0 {
        sum.map(|s| s / mass)
    } else {
        map
    };
    Concentration {
        map_indices,
        map,
        mass_near_map: mass,
        local_mean,
        spread: spread(grid, marginal, map_indices),
    }
}

/// The standard deviation of each theta axis of the normalised marginal `marginal`, each point
/// standing for its cell: the points' variance about the mean plus a cell's `res^2 / 12`. The
/// moments are taken in index steps from the MAP `centre` (no cancellation in `f32`), in one
/// pass of the grid's layout (no index division).
pub fn spread(grid: &Grid, marginal: &[f32], centre: [usize; 3]) -> [f32; 3] {
    let shape = grid.shape();
    let res = grid.resolution();
    // Sums of p d and p d^2 per axis, d the index step from the centre.
    let (mut first, mut second) = ([0.0f32; 3], [0.0f32; 3]);
    let mut total = 0.0f32;
    let mut points = marginal.iter().take(grid.theta_len());
    for ix in 0..shape[0] {
        let dx = ix as f32 - centre[0] as f32;
        for iy in 0..shape[1] {
            let dy = iy as f32 - centre[1] as f32;
            // The mass axis summed first: its row's mass and moments.
            let (mut row, mut m1, mut m2) = (0.0f32, 0.0f32, 0.0f32);
            for im in 0..shape[2] {
                let Some(&p) = points.next() else {
                    break;
                };
                let dm = im as f32 - centre[2] as f32;
                row += p;
                m1 += p * dm;
                m2 += p * dm * dm;
            }
            total += row;
            first[0] += row * dx;
            second[0] += row * dx * dx;
            first[1] += row * dy;
            second[1] += row * dy * dy;
            first[2] += m1;
            second[2] += m2;
        }
    }
    if total <= 0.0 {
        return [f32::NAN; 3];
    }
    [0, 1, 2].map(|a| {
        let mean = first[a] / total;
        let variance = math::max(second[a] / total - mean * mean, 0.0) + 1.0 / 12.0;
        res[a] * math::sqrt(variance)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper::{checked, rect_sim1};

    #[test]
    fn spread_is_a_cells_width_on_one_point_and_grows_with_the_points_it_covers() {
        let scenario = checked(rect_sim1());
        let grid = Grid::new(&scenario.estimation, None).unwrap();
        let res = grid.resolution();
        let mut marginal = std::vec![0.0f32; grid.theta_len()];
        let centre = [1, 1, 1];
        marginal[grid.theta_index(centre)] = 1.0;
        let one = concentration(&grid, &marginal);
        for (a, (spread, res)) in one.spread.iter().zip(res).enumerate() {
            let cell = res / 12f32.sqrt();
            assert!((spread - cell).abs() < 1e-5, "axis {a}: {one:?}");
        }
        // Half on the next mass: the mass's variance grows by a quarter of a step squared.
        marginal[grid.theta_index(centre)] = 0.5;
        marginal[grid.theta_index([1, 1, 2])] = 0.5;
        let two = concentration(&grid, &marginal);
        let mass = res[2] * (0.25f32 + 1.0 / 12.0).sqrt();
        assert!((two.spread[2] - mass).abs() < 1e-5, "{two:?}");
        assert!((two.spread[0] - one.spread[0]).abs() < 1e-6, "{two:?}");
        // Uniform over the grid: an axis's standard deviation is its length's over sqrt(12).
        marginal
            .iter_mut()
            .for_each(|p| *p = 1.0 / grid.theta_len() as f32);
        let flat = concentration(&grid, &marginal);
        for (a, (spread, (res, n))) in flat
            .spread
            .iter()
            .zip(res.iter().zip(grid.shape()))
            .enumerate()
        {
            let expect = res * n as f32 / 12f32.sqrt();
            assert!(
                (spread - expect).abs() < 1e-3 * expect,
                "axis {a}: {flat:?}"
            );
        }
    }
}
