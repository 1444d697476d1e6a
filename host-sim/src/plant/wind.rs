//! Wind over the payload (docs/formats.md#the-plant-section): a mean wind and gusts about it in
//! Dryden's first-order form (MIL-F-8785C's low-altitude model: each horizontal axis a
//! Gauss-Markov process of the given RMS with correlation time L / V, the length scale L taken
//! as [`GUST_LENGTH`] near the ground), pushing on the payload as drag on its footprint's area
//! ([`DRAG_COEFFICIENT`], air at [`AIR_DENSITY`]), applied at the footprint's centroid.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use shared::control::vector::Vec3;
use shared::geometry::{Vec2, area_moments};

/// Air density, kg/m^3 (sea level, 15 C).
pub const AIR_DENSITY: f32 = 1.225;
/// Drag coefficient on the footprint's area: a bluff body's (a flat plate edge-on has less;
/// its robots, rotors and their wakes add): conservative.
pub const DRAG_COEFFICIENT: f32 = 1.0;
/// The gusts' length scale near the ground, m (Dryden's L_u at a few metres up).
pub const GUST_LENGTH: f32 = 5.0;

/// The wind a plant has.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindConfig {
    /// Mean wind, north and east, m/s.
    pub mean: [f32; 2],
    /// Gusts, m/s RMS per horizontal axis.
    pub gust: f32,
    /// Seed of the gusts.
    pub seed: u64,
}

impl WindConfig {
    /// No wind.
    pub const CALM: Self = Self {
        mean: [0.0; 2],
        gust: 0.0,
        seed: 0,
    };
}

/// The drag the wind makes this step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drag {
    /// Force, world frame (NED), N.
    pub force: Vec3,
    /// Where it acts, body frame, m.
    pub at: Vec2,
}

/// The wind's state: its gusts now.
#[derive(Clone, Debug)]
pub struct Wind {
    config: WindConfig,
    gust: [f32; 2],
    rng: ChaCha8Rng,
}

impl Wind {
    /// The wind of `config`, its gusts starting from a draw of their own distribution.
    pub fn new(config: &WindConfig) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(config.seed ^ 0x6057_5EED);
        let mut draw = || {
            let n: f32 = StandardNormal.sample(&mut rng);
            n * config.gust
        };
        let gust = [draw(), draw()];
        Self {
            config: *config,
            gust,
            rng,
        }
    }

    /// The air's velocity over the ground now, NED (horizontal), m/s.
    pub fn air(&self) -> Vec3 {
        let [n, e] = self.config.mean;
        Vec3::new(n + self.gust[0], e + self.gust[1], 0.0)
    }

    /// The gusts moved on by `dt` s, and the drag on a payload of `footprint` moving at
    /// `velocity` (NED) in the air; `None` in calm air.
    pub fn drag(&mut self, velocity: Vec3, footprint: &[Vec2], dt: f32) -> Option<Drag> {
        let c = self.config;
        if c.mean == [0.0; 2] && c.gust == 0.0 {
            return None;
        }
        if c.gust > 0.0 {
            let speed = (c.mean[0].hypot(c.mean[1])).max(1.0);
            let tau = GUST_LENGTH / speed;
            let a = (-dt / tau).exp();
            let b = c.gust * (1.0 - a * a).sqrt();
            for g in &mut self.gust {
                let n: f32 = StandardNormal.sample(&mut self.rng);
                *g = a * *g + b * n;
            }
        }
        let mut relative = self.air() - velocity;
        relative.z = 0.0;
        let plate = area_moments(footprint);
        let q = 0.5 * AIR_DENSITY * DRAG_COEFFICIENT * plate.area * relative.norm();
        Some(Drag {
            force: relative * q,
            at: plate.centroid,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Vec<Vec2> {
        vec![
            Vec2::new(-0.5, -0.5),
            Vec2::new(0.5, -0.5),
            Vec2::new(0.5, 0.5),
            Vec2::new(-0.5, 0.5),
        ]
    }

    #[test]
    fn a_steady_wind_pushes_downwind_with_the_dynamic_pressure_on_the_area() {
        let mut w = Wind::new(&WindConfig {
            mean: [2.0, 0.0],
            gust: 0.0,
            seed: 1,
        });
        let d = w.drag(Vec3::ZERO, &square(), 0.0005).expect("wind");
        // 0.5 * 1.225 * 1.0 * 1 m^2 * (2 m/s)^2 = 2.45 N north.
        assert!((d.force.x - 2.45).abs() < 1e-4, "{d:?}");
        assert_eq!((d.force.y, d.force.z), (0.0, 0.0));
        // Moving with the air: no drag.
        let still = w
            .drag(Vec3::new(2.0, 0.0, 0.0), &square(), 0.0005)
            .expect("wind");
        assert!(still.force.norm() < 1e-6);
        assert!(
            Wind::new(&WindConfig::CALM)
                .drag(Vec3::ZERO, &square(), 0.0005)
                .is_none()
        );
    }

    #[test]
    fn gusts_have_their_rms_and_their_correlation_time() {
        let mut w = Wind::new(&WindConfig {
            mean: [5.0, 0.0],
            gust: 1.0,
            seed: 3,
        });
        let dt = 0.0005;
        let n = 400_000;
        let (mut sum, mut sq) = (0.0f64, 0.0f64);
        for _ in 0..n {
            w.drag(Vec3::ZERO, &square(), dt);
            let g = f64::from(w.air().x - 5.0);
            sum += g;
            sq += g * g;
        }
        let mean = sum / f64::from(n);
        let rms = (sq / f64::from(n) - mean * mean).sqrt();
        // 200 s over a 1 s correlation time: within about a tenth.
        assert!((0.8..1.2).contains(&rms), "rms {rms}");
        assert!(mean.abs() < 0.3, "mean {mean}");
    }
}
