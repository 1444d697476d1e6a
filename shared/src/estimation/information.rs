//! Mutual information between theta and the next lift reading of one group, under the current
//! posterior (docs/models.md#information-measure; the choice of lift by information follows
//! Corah et al. (2017)).
//!
//! Shannon information `I = H(z) - H(z | theta)`, by quadrature. Why Shannon and not the
//! Cauchy-Schwarz quadratic MI of Corah et al.: the quadratic form needs a double sum over grid
//! pairs, `O(G^2)` per group, while Shannon MI here costs `O(G + Q K)`:
//!
//! - The reading's marginal `p(z) = sum_theta w_theta N(z; lambda_theta, sigma^2)` is a Gaussian
//!   kernel smoothing of the distribution of predicted readings. The predictions are binned
//!   linearly (each weight split between its two nearest nodes, which keeps the mean exact) on a
//!   lattice of spacing `sigma / 4`; `p(z)` on the same lattice is then a short convolution with
//!   a fixed kernel of `+-6 sigma`, and `H(z)` a Riemann sum, which for a smooth density at
//!   that spacing is accurate to far better than the differences between groups.
//! - Readings are censored at the robots' maximum thrust (the group cannot lift): the reading is
//!   a mixed variable, a density below the limit plus a point mass "could not lift". Both
//!   entropies carry the discrete term, and `H(z | theta)` has a closed form per prediction
//!   ([`LiftLikelihood::conditional_entropy`]), so a group that surely cannot lift scores ~0.

use crate::estimation::grid::Grid;
use crate::estimation::likelihood::LiftLikelihood;
use crate::estimation::posterior::predicted_reading;
use crate::math;

/// Most lattice nodes of the reading's quadrature.
pub const MAX_BINS: usize = 512;
/// Lattice nodes per noise standard deviation (at most; wider when the span needs it).
const NODES_PER_SIGMA: f32 = 4.0;
/// Half-width of the Gaussian kernel, in standard deviations.
const KERNEL_SIGMAS: f32 = 6.0;
/// Most kernel taps on one side.
const MAX_KERNEL_HALF: usize = 24; // KERNEL_SIGMAS * NODES_PER_SIGMA
/// Standard deviations below the censoring limit past which a reading is surely lifted (as
/// [`LiftLikelihood::conditional_entropy`] takes it).
const CERTAIN_LIFT_SIGMAS: f32 = 8.0;
/// Grid points lighter than this are left out of the mixture.
const NEGLIGIBLE_WEIGHT: f32 = 1e-9;

/// Working memory of one information evaluation (kept by the caller, reused).
#[derive(Clone, Debug)]
pub struct InformationScratch {
    mixture: [f32; MAX_BINS],
    kernel: [f32; MAX_KERNEL_HALF + 1],
}

impl InformationScratch {
    /// Zeroed working memory.
    pub const EMPTY: Self = Self {
        mixture: [0.0; MAX_BINS],
        kernel: [0.0; MAX_KERNEL_HALF + 1],
    };
}

impl Default for InformationScratch {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// Mutual information (nats) between theta and a lift reading of a group whose geometric share
/// at COM point `c` is `fractions[c]`, when the grid's normalised probabilities are
/// `probabilities`.
pub fn mutual_information(
    grid: &Grid,
    probabilities: &[f32],
    fractions: &[f32],
    robot_mass: f32,
    likelihood: &LiftLikelihood,
    scratch: &mut InformationScratch,
) -> f32 {
    let sigma = likelihood.sigma;
    let limit = likelihood.max_thrust;
    let (nm, ns) = (grid.shape()[2], grid.scale_len());
    let each_point = |visit: &mut dyn FnMut(f32, f32)| {
        for (c, &fraction) in fractions.iter().enumerate().take(grid.com_len()) {
            for im in 0..nm {
                for is in 0..ns {
                    let w = probabilities[(c * nm + im) * ns + is];
                    if w > NEGLIGIBLE_WEIGHT {
                        visit(w, predicted_reading(grid, fraction, im, is, robot_mass));
                    }
                }
            }
        }
    };

    // The span of predictions.
    let (mut lowest, mut highest) = (f32::INFINITY, f32::NEG_INFINITY);
    each_point(&mut |_, reading| {
        lowest = lowest.min(reading);
        highest = highest.max(reading);
    });
    if !lowest.is_finite() {
        return 0.0;
    }
    // The lattice: fine enough for the kernel, coarse enough to fit, and placed so that the
    // censoring limit is a node (the density is integrated exactly up to it).
    let start = lowest - KERNEL_SIGMAS * sigma;
    let density_end = limit.min(highest + KERNEL_SIGMAS * sigma);
    let top = highest.max(density_end);
    let step = (sigma / NODES_PER_SIGMA).max((top - start) / (MAX_BINS - 3) as f32);
    let origin = if limit > start {
        limit - math::ceil((limit - start) / step) * step
    } else {
        start
    };
    let nodes = (((top - origin) / step) as usize + 2).min(MAX_BINS);

    // Linear binning of the predictions' distribution.
    let mixture = &mut scratch.mixture[..nodes];
    mixture.fill(0.0);
    // The nodes the predictions fall on: outside them the mixture is zero.
    let (mut first_weighted, mut last_weighted) = (nodes, 0);
    each_point(&mut |w, reading| {
        let at = (reading - origin) / step;
        let i = (at as usize).min(nodes - 2);
        let frac = math::clamp(at - i as f32, 0.0, 1.0);
        mixture[i] += w * (1.0 - frac);
        mixture[i + 1] += w * frac;
        first_weighted = first_weighted.min(i);
        last_weighted = last_weighted.max(i + 1);
    });

    // Conditional entropy and the censored mass, node by node. More than
    // `CERTAIN_LIFT_SIGMAS` below the limit a reading is never censored (in f32 its censored
    // probability is exactly 0) and its entropy is the Gaussian's: the same values as the
    // likelihood's own functions, without their `erfc` and `ln` at every node.
    let gaussian = likelihood.conditional_entropy(f32::NEG_INFINITY);
    let (mut conditional, mut censored) = (0.0, 0.0);
    for (i, &w) in mixture.iter().enumerate() {
        if w > 0.0 {
            let reading = origin + i as f32 * step;
            if (limit - reading) / sigma > CERTAIN_LIFT_SIGMAS {
                conditional += w * gaussian;
            } else {
                conditional += w * likelihood.conditional_entropy(reading);
                censored += w * likelihood.censored_probability(reading);
            }
        }
    }

    // Marginal entropy: Gaussian smoothing on the lattice, below the limit.
    let half = ((KERNEL_SIGMAS * sigma / step) as usize).min(MAX_KERNEL_HALF);
    for (d, k) in scratch.kernel.iter_mut().enumerate().take(half + 1) {
        *k = math::normal_pdf(d as f32 * step / sigma) / sigma;
    }
    let mut marginal = 0.0;
    if density_end > origin {
        let last_node = (math::round((density_end - origin) / step) as usize).min(nodes - 1);
        for j in 0..=last_node {
            // Only the nodes that carry weight add to the sum (the others add exact zeros).
            let from = j.saturating_sub(half).max(first_weighted);
            let to = (j + half).min(nodes - 1).min(last_weighted);
            let mut density = 0.0;
            for (b, &w) in mixture.iter().enumerate().take(to + 1).skip(from) {
                density += w * scratch.kernel[b.abs_diff(j)];
            }
            // Trapezoid rule: half weight at both ends.
            let weight = if j == 0 || j == last_node { 0.5 } else { 1.0 };
            if density > 0.0 {
                marginal -= weight * density * math::ln(density) * step;
            }
        }
    }
    if censored > 0.0 {
        marginal -= censored * math::ln(censored);
    }
    (marginal - conditional).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimation::grid::Grid;
    use crate::estimation::groups::lift_group;
    use crate::liftoff_thrust::lift_fraction;
    use crate::paper::{checked, rect_sim1};
    use crate::scenario::MAX_GRID_POINTS;
    use proptest::prelude::*;

    /// Independent formulation: `I = H(z) - H(z|theta)` with both entropies by dense
    /// trapezoid quadrature over z straight from the Gaussian mixture (`O(G Q)`), the censored
    /// point mass from the normal tail of every component.
    fn brute_force(readings: &[(f32, f32)], likelihood: &LiftLikelihood) -> f32 {
        let s = likelihood.sigma;
        let lo = readings.iter().map(|r| r.1).fold(f32::INFINITY, f32::min) - 8.0 * s;
        let hi = likelihood.max_thrust;
        let n = 4000;
        let dz = (hi - lo) / n as f32;
        let density = |z: f32| -> f64 {
            readings
                .iter()
                .map(|&(w, m)| w as f64 * (math::normal_pdf((z - m) / s) / s) as f64)
                .sum()
        };
        let mut h = 0.0f64;
        for i in 0..=n {
            let p = density(lo + i as f32 * dz);
            let trapezoid = if i == 0 || i == n { 0.5 } else { 1.0 };
            if p > 0.0 {
                h -= trapezoid * p * p.ln() * dz as f64;
            }
        }
        let censored: f64 = readings
            .iter()
            .map(|&(w, m)| w as f64 * likelihood.censored_probability(m) as f64)
            .sum();
        if censored > 0.0 {
            h -= censored * censored.ln();
        }
        let conditional: f64 = readings
            .iter()
            .map(|&(w, m)| w as f64 * likelihood.conditional_entropy(m) as f64)
            .sum();
        (h - conditional) as f32
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        #[test]
        fn binned_information_matches_dense_quadrature(
            group in 0usize..12, seed in 0u64..u64::MAX, max_thrust in 6.0f32..20.0,
            sigma in 0.3f32..2.0,
        ) {
            let scenario = checked(rect_sim1());
            let grid = Grid::new(&scenario.estimation, None).unwrap();
            let g = lift_group(&scenario, group).unwrap();
            let hull = &scenario.payload.hull;
            let fractions: heapless::Vec<f32, MAX_GRID_POINTS> = (0..grid.com_len())
                .map(|c| lift_fraction(hull, grid.com(c), g.centroid, 2).unwrap_or(0.0))
                .collect();
            // A random posterior (xorshift weights, zero outside the hull).
            let mut state = seed | 1;
            let mut probs: heapless::Vec<f32, MAX_GRID_POINTS> = heapless::Vec::new();
            for t in 0..grid.len() {
                state ^= state << 13; state ^= state >> 7; state ^= state << 17;
                let inside = hull.contains(grid.com(t / grid.shape()[2]), 1e-6);
                let w = if inside { (state % 1000) as f32 / 1000.0 } else { 0.0 };
                let _ = probs.push(w * w * w);
            }
            let total: f32 = probs.iter().sum();
            probs.iter_mut().for_each(|p| *p /= total);
            let likelihood = LiftLikelihood { sigma, max_thrust };
            let mut scratch = InformationScratch::default();
            let fast = mutual_information(&grid, &probs, &fractions, 0.1, &likelihood, &mut scratch);
            let readings: heapless::Vec<(f32, f32), MAX_GRID_POINTS> = (0..grid.len())
                .map(|t| {
                    let (c, im) = (t / grid.shape()[2], t % grid.shape()[2]);
                    (probs[t], predicted_reading(&grid, fractions[c], im, 0, 0.1))
                })
                .collect();
            let slow = brute_force(&readings, &likelihood);
            prop_assert!((fast - slow).abs() < 0.02 + 0.02 * slow, "fast {} slow {}", fast, slow);
        }
    }

    /// The shortcut for readings far below the limit gives exactly what the likelihood's own
    /// functions give there.
    #[test]
    fn far_below_the_limit_a_reading_is_surely_lifted_exactly() {
        let likelihood = LiftLikelihood {
            sigma: 0.5,
            max_thrust: 14.2,
        };
        let gaussian = likelihood.conditional_entropy(f32::NEG_INFINITY);
        let mut reading = 14.2 - CERTAIN_LIFT_SIGMAS * 0.5 - 1e-3;
        while reading > -5.0 {
            assert_eq!(
                likelihood.censored_probability(reading),
                0.0,
                "at {reading}"
            );
            assert_eq!(
                likelihood.conditional_entropy(reading),
                gaussian,
                "at {reading}"
            );
            reading -= 0.013;
        }
    }

    #[test]
    fn a_group_that_surely_cannot_lift_carries_no_information() {
        // The likelihood's robots reach 1.5 N, just above their own weight (a payload
        // description with such robots is refused: no group could tip its payloads).
        let scenario = checked(rect_sim1());
        let grid = Grid::new(&scenario.estimation, None).unwrap();
        let g = lift_group(&scenario, 2).unwrap();
        let fractions: heapless::Vec<f32, MAX_GRID_POINTS> = (0..grid.com_len())
            .map(|c| {
                lift_fraction(&scenario.payload.hull, grid.com(c), g.centroid, 2).unwrap_or(0.0)
            })
            .collect();
        let probs: heapless::Vec<f32, MAX_GRID_POINTS> =
            (0..grid.len()).map(|_| 1.0 / grid.len() as f32).collect();
        let likelihood = LiftLikelihood {
            sigma: 0.2,
            max_thrust: 1.5,
        };
        let mi = mutual_information(
            &grid,
            &probs,
            &fractions,
            0.1,
            &likelihood,
            &mut InformationScratch::default(),
        );
        assert!(mi < 1e-3, "{mi}");
    }
}
