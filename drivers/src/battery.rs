//! The power module's pack voltage on the Pixhawk 6C's ADC: ADC counts to volts
//! through the board's divider.
//!
//! The power module's voltage output reaches `BAT1 VOLTAGE` on the POWER1 connector, wired (as
//! PX4's `boards/px4/fmu-v6c` has it: `ADC_BATTERY1_VOLTAGE_CHANNEL`, PC5, ADC12_INP8) to
//! channel 8 of ADC1; the pack voltage is the pin's voltage times the module's divider, 18.1
//! for the Holybro PM02 (PX4's `BAT1_V_DIV` default for this board), against the 3.3 V
//! reference.

/// ADC1's channel of the battery voltage (PC5, `ADC12_INP8`).
pub const BATTERY_VOLTAGE_CHANNEL: u8 = 8;
/// The power module's divider (PX4's `BAT1_V_DIV` default on fmu-v6c).
pub const DEFAULT_DIVIDER: f32 = 18.1;
/// The ADC's reference, V (the board's 3.3 V analog supply).
pub const REFERENCE_VOLTS: f32 = 3.3;

/// Converts ADC readings to the pack's voltage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BatteryScale {
    /// Pack volts per pin volt.
    pub divider: f32,
    /// The ADC's reference, V.
    pub reference: f32,
    /// Resolution, bits (16 on the STM32H7's ADC at full resolution).
    pub bits: u8,
}

impl BatteryScale {
    /// The Pixhawk 6C with a PM02-class module at the ADC's 16 bits.
    pub const PIXHAWK6C: Self = Self {
        divider: DEFAULT_DIVIDER,
        reference: REFERENCE_VOLTS,
        bits: 16,
    };

    /// The pack's voltage of a reading of `counts`, V (counts beyond full scale read as full
    /// scale; a resolution beyond 16 bits as 16).
    pub fn volts(&self, counts: u16) -> f32 {
        let bits = u32::from(self.bits.clamp(1, 16));
        let full = ((1u32 << bits) - 1) as f32;
        let counts = (u32::from(counts)).min((1u32 << bits) - 1) as f32;
        counts / full * self.reference * self.divider
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_become_pack_volts_through_the_divider() {
        let s = BatteryScale::PIXHAWK6C;
        // Full scale: 3.3 V at the pin, 59.73 V at the pack.
        assert!((s.volts(u16::MAX) - 59.73).abs() < 1e-3);
        assert_eq!(s.volts(0), 0.0);
        // A 4S pack at 16.0 V puts 16.0 / 18.1 = 0.884 V on the pin: 17,555 of 65,535.
        let counts = (16.0 / 18.1 / 3.3 * 65_535.0f32).round() as u16;
        assert_eq!(counts, 17_555);
        assert!((s.volts(counts) - 16.0).abs() < 1e-3);
        // At 12 bits the same pin voltage reads 1/16 as many counts.
        let twelve = BatteryScale { bits: 12, ..s };
        assert!((twelve.volts(1097) - 16.0).abs() < 0.02);
        // Counts past a 12-bit full scale read as full scale.
        assert_eq!(twelve.volts(60_000), twelve.volts(4095));
    }
}
