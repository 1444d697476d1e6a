//! The scenario's `[plant]` departures applied to the physics plant
//! (docs/formats.md#the-plant-section): each rotor's efficiency drawn from the run's seed, the
//! motor lag, the payload's inertia, the robots' true mass, the wind, ground effect and the
//! pack's sag. (Motion capture's latency and
//! dropout are the sensors': [`super::sensors::Sensors::with_mocap_departures`].)

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scenario_toml::PlantDepartures;

use super::PlantConfig;

/// Applies the departures to a plant's configuration; what the seed draws (the rotors'
/// efficiencies) is the same for the same seed and rotor count.
pub trait ApplyDepartures {
    /// Applies them to `config` with the run's `seed`.
    fn apply(&self, config: &mut PlantConfig, seed: u64);
}

impl ApplyDepartures for PlantDepartures {
    fn apply(&self, config: &mut PlantConfig, seed: u64) {
        let n = config.rotor_points.len();
        let spread = self.rotor_efficiency_spread;
        config.efficiency = if spread > 0.0 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xEFF1_C1E4);
            (0..n)
                .map(|_| 1.0 + rng.random_range(-spread..=spread))
                .collect()
        } else {
            Vec::new()
        };
        config.motor_time_constant = self.motor_time_constant;
        config.inertia_scale = self.inertia_scale;
        config.robot_mass *= self.robot_mass_scale;
        config.wind = super::wind::WindConfig {
            mean: self.wind,
            gust: self.gust,
            seed,
        };
        config.ground_effect = self.ground_effect;
        config.pack_resistance = self.battery_sag;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shared::geometry::Vec2;

    #[test]
    fn the_model_changes_nothing_and_a_spread_is_drawn_from_the_seed_within_its_bounds() {
        let config = || PlantConfig {
            rotor_points: vec![Vec2::new(0.0, 0.0); 8],
            robot_mass: 0.1,
            ..PlantConfig::MODEL
        };
        let mut model = config();
        PlantDepartures::MODEL.apply(&mut model, 1);
        assert!(model.efficiency.is_empty());
        assert_eq!(model.robot_mass, 0.1);
        assert_eq!(model.inertia_scale, 1.0);
        assert!(!model.ground_effect);
        assert_eq!(model.pack_resistance, 0.0);
        let d = PlantDepartures {
            rotor_efficiency_spread: 0.08,
            robot_mass_scale: 1.3,
            ground_effect: true,
            battery_sag: 0.03,
            ..PlantDepartures::MODEL
        };
        let (mut a, mut b, mut c) = (config(), config(), config());
        d.apply(&mut a, 1);
        d.apply(&mut b, 1);
        d.apply(&mut c, 2);
        assert_eq!(a.efficiency, b.efficiency, "the same seed, the same rotors");
        assert_ne!(a.efficiency, c.efficiency);
        assert_eq!(a.efficiency.len(), 8);
        assert!(a.efficiency.iter().all(|e| (0.92..=1.08).contains(e)));
        assert!((a.robot_mass - 0.13).abs() < 1e-6);
        assert!(a.ground_effect);
        assert_eq!(a.pack_resistance, 0.03);
    }
}
