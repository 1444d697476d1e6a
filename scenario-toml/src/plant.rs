//! The `[plant]` section (docs/formats.md#the-plant-section): how the simulated world departs
//! from the model the controller assumes. Simulation only: never sent to the vehicle. Every key
//! defaults to the model's value, so a file without the section flies as the model.

use serde::Deserialize;

/// How the plant departs from the controller's model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlantDepartures {
    /// Each rotor's thrust for its command is scaled by 1 + u, u drawn uniformly in
    /// +-spread per rotor from the run's seed.
    pub rotor_efficiency_spread: f32,
    /// The rotors' first-order lag, s.
    pub motor_time_constant: f32,
    /// The payload's inertia about its COM relative to the uniform plate's.
    pub inertia_scale: f32,
    /// Each robot's true mass relative to the description's.
    pub robot_mass_scale: f32,
    /// Motion capture's latency, s.
    pub mocap_latency: f32,
    /// The fraction of motion-capture fixes lost, in bursts.
    pub mocap_dropout: f32,
    /// The mean wind, north and east, m/s.
    pub wind: [f32; 2],
    /// The gusts about it, m/s RMS per horizontal axis (Dryden's first-order form).
    pub gust: f32,
    /// The frame's vibration on the raw accelerometer at hover thrust, m/s^2 RMS per axis, at
    /// the rotors' rotation and blade-pass frequencies.
    pub imu_vibration: f32,
    /// The same on the raw gyro, rad/s RMS per axis.
    pub gyro_vibration: f32,
    /// Whether each rotor's thrust rises near the ground (Cheeseman and Bennett's model).
    pub ground_effect: bool,
    /// The pack's internal resistance, Ohm: its voltage falls with the rotors' current and
    /// each rotor's thrust for its command with the voltage squared.
    pub battery_sag: f32,
}

impl PlantDepartures {
    /// The model itself: the plant the controller assumes.
    pub const MODEL: Self = Self {
        rotor_efficiency_spread: 0.0,
        motor_time_constant: 0.02,
        inertia_scale: 1.0,
        robot_mass_scale: 1.0,
        mocap_latency: 0.01,
        mocap_dropout: 0.0,
        wind: [0.0; 2],
        gust: 0.0,
        imu_vibration: 0.0,
        gyro_vibration: 0.0,
        ground_effect: false,
        battery_sag: 0.0,
    };
}

impl Default for PlantDepartures {
    fn default() -> Self {
        Self::MODEL
    }
}

/// The section as written.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields, expecting = "a [plant] table")]
pub(crate) struct PlantToml {
    rotor_efficiency_spread: Option<f64>,
    motor_time_constant: Option<f64>,
    inertia_scale: Option<f64>,
    robot_mass_scale: Option<f64>,
    mocap_latency: Option<f64>,
    mocap_dropout: Option<f64>,
    imu_vibration: Option<f64>,
    gyro_vibration: Option<f64>,
    wind: Option<Vec<f64>>,
    gust: Option<f64>,
    ground_effect: Option<bool>,
    battery_sag: Option<f64>,
}

/// Largest mean wind per axis, m/s (a strong breeze: no payload of this kind flies in more).
const MAX_WIND: f64 = 15.0;
/// Largest gusts, m/s RMS.
const MAX_GUST: f64 = 5.0;

/// Each key's name, range and what it is (units in the range's words).
const RANGES: [(&str, f64, f64, &str); 9] = [
    ("rotor_efficiency_spread", 0.0, 0.5, ""),
    ("motor_time_constant", 0.005, 0.5, " s"),
    ("inertia_scale", 0.1, 10.0, ""),
    ("robot_mass_scale", 0.5, 3.0, ""),
    ("mocap_latency", 0.0, 0.5, " s"),
    ("mocap_dropout", 0.0, 0.9, ""),
    ("imu_vibration", 0.0, 60.0, " m/s^2"),
    ("gyro_vibration", 0.0, 3.0, " rad/s"),
    // A fresh 4S pack of this size has some 0.01 to 0.02 Ohm; worn or cold, several times that.
    ("battery_sag", 0.0, 0.2, " Ohm"),
];

impl PlantToml {
    /// The departures, each value checked against its range; the error names the key.
    pub(crate) fn departures(&self) -> Result<PlantDepartures, String> {
        let m = PlantDepartures::MODEL;
        let given = [
            self.rotor_efficiency_spread,
            self.motor_time_constant,
            self.inertia_scale,
            self.robot_mass_scale,
            self.mocap_latency,
            self.mocap_dropout,
            self.imu_vibration,
            self.gyro_vibration,
            self.battery_sag,
        ];
        let defaults = [
            m.rotor_efficiency_spread,
            m.motor_time_constant,
            m.inertia_scale,
            m.robot_mass_scale,
            m.mocap_latency,
            m.mocap_dropout,
            m.imu_vibration,
            m.gyro_vibration,
            m.battery_sag,
        ];
        let mut v = [0.0f32; RANGES.len()];
        for (i, ((name, lo, hi, unit), value)) in RANGES.iter().zip(given).enumerate() {
            v[i] = match value {
                None => defaults[i],
                Some(x) if x.is_finite() && (*lo..=*hi).contains(&x) => x as f32,
                Some(x) => {
                    return Err(format!("plant.{name}: {x} is outside {lo} to {hi}{unit}"));
                }
            };
        }
        let wind = match self.wind.as_deref() {
            None => [0.0; 2],
            Some(&[n, e]) if [n, e].iter().all(|w| w.is_finite() && w.abs() <= MAX_WIND) => {
                [n as f32, e as f32]
            }
            Some(&[n, e]) => {
                return Err(format!(
                    "plant.wind: [{n}, {e}] has a component beyond {MAX_WIND} m/s"
                ));
            }
            Some(other) => {
                return Err(format!(
                    "plant.wind: [north, east] in m/s, two numbers (got {})",
                    other.len()
                ));
            }
        };
        let gust = match self.gust {
            None => 0.0,
            Some(g) if g.is_finite() && (0.0..=MAX_GUST).contains(&g) => g as f32,
            Some(g) => return Err(format!("plant.gust: {g} is outside 0 to {MAX_GUST} m/s")),
        };
        Ok(PlantDepartures {
            rotor_efficiency_spread: v[0],
            motor_time_constant: v[1],
            inertia_scale: v[2],
            robot_mass_scale: v[3],
            mocap_latency: v[4],
            mocap_dropout: v[5],
            wind,
            gust,
            imu_vibration: v[6],
            gyro_vibration: v[7],
            ground_effect: self.ground_effect.unwrap_or(m.ground_effect),
            battery_sag: v[8],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_section_is_the_model_and_a_value_out_of_range_is_named() {
        let none: PlantToml = toml::from_str("").expect("empty");
        assert_eq!(none.departures(), Ok(PlantDepartures::MODEL));
        let some: PlantToml =
            toml::from_str("inertia_scale = 1.5\nmotor_time_constant = 0.04").expect("parses");
        let d = some.departures().expect("in range");
        assert_eq!((d.inertia_scale, d.motor_time_constant), (1.5, 0.04));
        assert_eq!(d.robot_mass_scale, 1.0);
        let windy: PlantToml = toml::from_str("wind = [2.0, -1.0]\ngust = 1.0").expect("parses");
        let d = windy.departures().expect("in range");
        assert_eq!((d.wind, d.gust), ([2.0, -1.0], 1.0));
        let three: PlantToml = toml::from_str("wind = [2.0, 0.0, 1.0]").expect("parses");
        assert!(
            three
                .departures()
                .expect_err("refused")
                .contains("two numbers (got 3)")
        );
        let shaking: PlantToml =
            toml::from_str("imu_vibration = 10.0\ngyro_vibration = 0.3").expect("parses");
        let d = shaking.departures().expect("in range");
        assert_eq!((d.imu_vibration, d.gyro_vibration), (10.0, 0.3));
        let violent: PlantToml = toml::from_str("imu_vibration = 80.0").expect("parses");
        assert!(
            violent
                .departures()
                .expect_err("refused")
                .contains("plant.imu_vibration: 80 is outside 0 to 60 m/s^2")
        );
        let bad: PlantToml = toml::from_str("mocap_dropout = 1.0").expect("parses");
        let said = bad.departures().expect_err("refused");
        assert!(
            said.contains("plant.mocap_dropout: 1 is outside 0 to 0.9"),
            "{said}"
        );
    }

    #[test]
    fn ground_effect_and_the_packs_sag_are_read_and_a_sag_out_of_range_is_named() {
        let given: PlantToml =
            toml::from_str("ground_effect = true\nbattery_sag = 0.03").expect("parses");
        let d = given.departures().expect("in range");
        assert!(d.ground_effect);
        assert_eq!(d.battery_sag, 0.03);
        assert_eq!(d.gust, 0.0);
        let bad: PlantToml = toml::from_str("battery_sag = 0.5").expect("parses");
        let said = bad.departures().expect_err("refused");
        assert!(
            said.contains("plant.battery_sag: 0.5 is outside 0 to 0.2 Ohm"),
            "{said}"
        );
        let negative: PlantToml = toml::from_str("battery_sag = -0.01").expect("parses");
        assert!(
            negative
                .departures()
                .expect_err("refused")
                .contains("plant.battery_sag")
        );
        let Err(not_a_bool) = toml::from_str::<PlantToml>("ground_effect = 1") else {
            panic!("a number for ground_effect is refused");
        };
        assert!(
            not_a_bool.to_string().contains("ground_effect"),
            "{not_a_bool}"
        );
    }
}
