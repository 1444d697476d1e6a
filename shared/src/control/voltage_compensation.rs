//! Thrust compensation for the pack's voltage (docs/models.md#battery-compensation), as PX4's
//! `MC_BAT_SCALE_EN` does it: at a given ESC command a motor's speed goes with the voltage and
//! its thrust with the speed squared, so a pack that sags more than the one the thrust map
//! was measured with makes every rotor weaker than commanded, by `(V / V_map)^2`. A lift then
//! reads heavy, and a hover needs more than the model says.
//!
//! The pack's open-circuit voltage is estimated from the filtered reading plus the sag the
//! map's own pack shows at this load (`V_oc = V + drop * load`, PX4's `BAT_V_LOAD_DROP`
//! rule): the load is filtered like the reading so a step of thrust does not show as a sag
//! before the reading has followed it. Each rotor's command is then raised by
//! `(V_map / V_oc)^2`, never lowered, and by at most [`MAX_SCALE`] (PX4 caps its scale at
//! 1.3 of the command; a pack that low is the battery failsafe's business).

use crate::math;
use crate::mission::supervision::BATTERY_FILTER_S;

/// Largest factor on a rotor's thrust command.
pub const MAX_SCALE: f32 = 1.3;

/// The factor needed beyond which the pack counts as short ([`VoltageCompensation::short`]):
/// every rotor then makes a tenth or more less than asked. Just past [`MAX_SCALE`] (a pack
/// near `BAT_LOW_V`) the rotors fall a few percent short, less than any rotor's own share.
pub const SHORT_SCALE: f32 = MAX_SCALE / 0.9;
/// A shortfall of the open-circuit estimate below the map's voltage smaller than this is
/// the reading's noise, not a sag, V.
pub const DEAD_BAND_VOLTS: f32 = 0.02;

/// What the compensation needs to know of the pack.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PackModel {
    /// Compensation on (`MC_BAT_SCALE_EN`).
    pub enabled: bool,
    /// The open-circuit voltage at which the thrust map was measured, V.
    pub map_volts: f32,
    /// How far that pack's reading fell with every rotor at full thrust, V (in proportion
    /// below it).
    pub full_load_drop: f32,
}

impl PackModel {
    /// On; the simulated vehicle's pack and its map (16 V open circuit, 0.8 V sag at full).
    pub const DEFAULT: Self = Self {
        enabled: true,
        map_volts: 16.0,
        full_load_drop: 0.8,
    };
}

impl Default for PackModel {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The compensation's state: the rotors' load filtered as the voltage reading is.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VoltageCompensation {
    load: Option<f32>,
    /// The last scale needed more than [`SHORT_SCALE`]: the pack cannot make up the rotors'
    /// thrust.
    short: bool,
}

impl VoltageCompensation {
    /// No load seen yet.
    pub const fn new() -> Self {
        Self {
            load: None,
            short: false,
        }
    }

    /// Whether the pack was, at the last [`Self::scale`], far too low for the compensation to
    /// make up (the factor needed beyond [`SHORT_SCALE`]): every rotor then makes a tenth or
    /// more less than asked.
    pub fn short(&self) -> bool {
        self.short
    }

    /// The factor on every rotor's command this tick, `dt` s after the last: `volts` the
    /// filtered pack reading (none yet: 1), `load` the rotors' commanded thrust over their
    /// whole (0 to 1).
    pub fn scale(&mut self, pack: &PackModel, volts: Option<f32>, load: f32, dt: f32) -> f32 {
        let load = math::clamp(load, 0.0, 1.0);
        let filtered = match self.load {
            None => load,
            Some(f) => f + math::clamp(dt / (BATTERY_FILTER_S + dt), 0.0, 1.0) * (load - f),
        };
        self.load = Some(filtered);
        self.short = false;
        let Some(volts) = volts.filter(|v| v.is_finite() && *v > 0.0) else {
            return 1.0;
        };
        if !pack.enabled || pack.map_volts.is_nan() || pack.map_volts <= 0.0 {
            return 1.0;
        }
        let open_circuit = volts + pack.full_load_drop * filtered;
        if open_circuit >= pack.map_volts - DEAD_BAND_VOLTS {
            return 1.0;
        }
        let ratio = pack.map_volts / math::max(open_circuit, f32::MIN_POSITIVE);
        self.short = ratio * ratio > SHORT_SCALE;
        math::min(ratio * ratio, MAX_SCALE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plant's rule: the rotors feel only the sag beyond the map's pack.
    fn reading(extra_sag: f32, load: f32) -> f32 {
        16.0 - 0.8 * load - extra_sag
    }

    #[test]
    fn a_pack_far_below_what_the_cap_makes_up_is_short() {
        let pack = PackModel::DEFAULT;
        // Near BAT_LOW_V under a light load: at the cap (a few percent short), not short.
        let mut c = VoltageCompensation::new();
        assert_eq!(c.scale(&pack, Some(13.8), 0.1, 0.0025), MAX_SCALE);
        assert!(!c.short());
        // 11 V: twice the thrust needed, far beyond the cap.
        assert_eq!(c.scale(&pack, Some(11.0), 0.4, 0.0025), MAX_SCALE);
        assert!(c.short());
        // No reading: nothing known, not short.
        assert_eq!(c.scale(&pack, None, 0.4, 0.0025), 1.0);
        assert!(!c.short());
    }

    #[test]
    fn the_maps_own_pack_is_not_compensated() {
        // The reading filtered as the mission filters it, through steps of load.
        let config = crate::mission::supervision::SupervisionConfig::DEFAULT;
        let mut battery = crate::mission::supervision::BatteryMonitor::new();
        let mut c = VoltageCompensation::new();
        let pack = PackModel::DEFAULT;
        for load in [0.0, 0.2, 1.0, 0.5, 0.0] {
            for _ in 0..2000 {
                let _ = battery.update(Some(reading(0.0, load)), 0.0025, &config);
                assert_eq!(c.scale(&pack, battery.volts(), load, 0.0025), 1.0);
            }
        }
    }

    #[test]
    fn a_sagging_pack_gets_back_the_thrust_it_takes() {
        let mut c = VoltageCompensation::new();
        let pack = PackModel::DEFAULT;
        let extra = 0.4;
        let mut scale = 1.0;
        for _ in 0..4000 {
            scale = c.scale(&pack, Some(reading(extra, 0.5)), 0.5, 0.0025);
        }
        // The rotors make (15.6 / 16)^2 of their command: the scale undoes it.
        let delivered = ((16.0 - extra) / 16.0f32).powi(2);
        assert!((scale * delivered - 1.0).abs() < 1e-3, "{scale}");
    }

    #[test]
    fn the_scale_is_capped_off_or_without_a_reading_one() {
        let mut c = VoltageCompensation::new();
        let pack = PackModel::DEFAULT;
        assert_eq!(c.scale(&pack, Some(10.0), 0.5, 0.0025), MAX_SCALE);
        assert_eq!(c.scale(&pack, None, 0.5, 0.0025), 1.0);
        assert_eq!(c.scale(&pack, Some(f32::NAN), 0.5, 0.0025), 1.0);
        let off = PackModel {
            enabled: false,
            ..pack
        };
        assert_eq!(c.scale(&off, Some(10.0), 0.5, 0.0025), 1.0);
        // A pack above the map's voltage is not turned down.
        assert_eq!(c.scale(&pack, Some(16.8), 0.0, 0.0025), 1.0);
    }
}
