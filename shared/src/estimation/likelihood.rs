//! The measurement model of one lift (docs/models.md#likelihood-and-censoring; Oishi & Jimbo
//! (2025), eq. (2)): a thrust reading `z` with
//! likelihood `N(z; lambda(theta), sigma^2)`, or, when the group cannot lift even at the
//! robots' maximum thrust, a censored reading with likelihood `P(lambda(theta) + e >= max)`,
//! `e ~ N(0, sigma^2)`.

use crate::math;

/// A reading that every grid point misses by more than this many standard deviations (a
/// lifted reading) or that every grid point would have avoided by as many (a censored one:
/// every point would have lifted) is not explained by the grid: the truth lies outside it.
pub const UNEXPLAINED_SIGMAS: f32 = 4.0;

/// What one lift produced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Measurement {
    /// The payload started to tilt at this thrust per robot, N.
    Lifted {
        /// Thrust per robot at lift-off, N.
        thrust: f32,
    },
    /// The group reached its maximum thrust and the payload did not move.
    CouldNotLift,
}

/// The noise and the censoring limit of lift measurements.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiftLikelihood {
    /// Standard deviation of a thrust reading, N.
    pub sigma: f32,
    /// Thrust per robot at which a reading is censored, N.
    pub max_thrust: f32,
}

impl LiftLikelihood {
    /// `ln p(measurement | predicted lift-off thrust)` up to a constant that does not depend on
    /// the prediction.
    pub fn ln_likelihood(&self, measurement: Measurement, predicted: f32) -> f32 {
        match measurement {
            Measurement::Lifted { thrust } => {
                let r = (thrust - predicted) / self.sigma;
                -0.5 * r * r
            }
            Measurement::CouldNotLift => {
                math::ln_normal_sf((self.max_thrust - predicted) / self.sigma)
            }
        }
    }

    /// Whether a point whose log-likelihood for `measurement` is `ln_best` (see
    /// [`Self::ln_likelihood`]) explains it within [`UNEXPLAINED_SIGMAS`].
    pub fn explains(&self, measurement: Measurement, ln_best: f32) -> bool {
        let limit = match measurement {
            Measurement::Lifted { .. } => -0.5 * UNEXPLAINED_SIGMAS * UNEXPLAINED_SIGMAS,
            Measurement::CouldNotLift => math::ln_normal_sf(UNEXPLAINED_SIGMAS),
        };
        ln_best >= limit
    }

    /// Probability that a group whose true lift-off thrust is `predicted` cannot lift.
    pub fn censored_probability(&self, predicted: f32) -> f32 {
        1.0 - math::normal_cdf((self.max_thrust - predicted) / self.sigma)
    }

    /// Entropy (nats) of the reading given its prediction: the differential entropy of the
    /// Gaussian part below the limit plus the discrete entropy of the censored outcome.
    /// With `a = (max - predicted) / sigma`:
    /// `Phi(a) (ln(sigma sqrt(2 pi)) + 1/2) - a phi(a) / 2 - Pc ln Pc`, `Pc = 1 - Phi(a)`.
    pub fn conditional_entropy(&self, predicted: f32) -> f32 {
        let a = (self.max_thrust - predicted) / self.sigma;
        let gaussian = math::ln(self.sigma) + math::LN_SQRT_2PI + 0.5;
        if a > 8.0 {
            return gaussian;
        }
        let below = math::normal_cdf(a);
        let censored = 1.0 - below;
        let discrete = if censored > 0.0 {
            -censored * math::ln(censored)
        } else {
            0.0
        };
        below * gaussian - 0.5 * a * math::normal_pdf(a) + discrete
    }
}
