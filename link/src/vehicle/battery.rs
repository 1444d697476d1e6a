//! `BATTERY_STATUS` both ways (docs/failures.md#failures): the pack's voltage read from one
//! (the vehicle takes the plant's in hardware-in-the-loop), and the one the HIL plant sends
//! for its simulated pack.

use crate::msg::{BATTERY_STATUS_DATA, MavBatteryFunction};

/// Offset of `BATTERY_STATUS`'s `voltages` in its payload (after two `int32` and an `int16`).
const BATTERY_VOLTAGES_OFFSET: usize = 10;

/// The pack voltage of a `BATTERY_STATUS` payload, V, as MAVLink puts it: the whole pack in
/// `voltages[0]` (mV) when the cells are not measured, continued in `voltages[1]` when it
/// reaches 65,534 mV; with cells measured, their sum. `None` when no voltage is given.
pub fn battery_volts(payload: &[u8]) -> Option<f32> {
    let cell = |i: usize| {
        let at = BATTERY_VOLTAGES_OFFSET + 2 * i;
        // Trailing zero bytes dropped by MAVLink 2 read as zero.
        let lo = payload.get(at).copied().unwrap_or(0);
        let hi = payload.get(at + 1).copied().unwrap_or(0);
        u16::from_le_bytes([lo, hi])
    };
    let first = cell(0);
    if first == u16::MAX {
        return None;
    }
    let mut millivolts = u32::from(first);
    // The pack beyond 65,534 mV, or the other cells: summed until the first unused one.
    for i in 1..10 {
        let c = cell(i);
        if c == u16::MAX || (c == 0 && first != u16::MAX - 1) {
            break;
        }
        millivolts += u32::from(c);
    }
    Some(volts_of(millivolts))
}

/// The whole millivolts `BATTERY_STATUS` carries for a pack at `volts` (not a number or below
/// zero: 0; above 65,534 mV: 65,534, the largest single entry).
pub fn pack_millivolts(volts: f32) -> u16 {
    let mv = volts * 1000.0;
    if mv.is_nan() {
        0
    } else {
        mv.min(65_534.0) as u16
    }
}

/// A voltage as the vehicle hands it between its tasks: whole millivolts, cut (below zero or
/// not a number: 0).
pub fn millivolts_of(volts: f32) -> u32 {
    (volts * 1000.0) as u32
}

/// Volts of `millivolts`.
pub fn volts_of(millivolts: u32) -> f32 {
    millivolts as f32 * 1e-3
}

/// `BATTERY_STATUS` of a pack at `volts` whose cells are not measured (the whole pack in
/// `voltages[0]`, the others unused), as the HIL plant reports its simulated pack.
pub fn battery_status(volts: f32) -> BATTERY_STATUS_DATA {
    let mut voltages = [u16::MAX; 10];
    voltages[0] = pack_millivolts(volts);
    BATTERY_STATUS_DATA {
        voltages,
        current_consumed: -1,
        energy_consumed: -1,
        temperature: i16::MAX,
        current_battery: -1,
        battery_remaining: -1,
        battery_function: MavBatteryFunction::MAV_BATTERY_FUNCTION_ALL,
        ..Default::default()
    }
}
