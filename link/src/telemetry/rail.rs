//! Each robot's rail position, as `DEBUG_FLOAT_ARRAY` named `rail`: the formation once the
//! robots have moved to it; not a number until the positions are confirmed.

use super::VehicleSnapshot;
use crate::hil::MAX_ROBOTS;
use crate::msg::DEBUG_FLOAT_ARRAY_DATA;

/// `array_id` of the rail positions' `DEBUG_FLOAT_ARRAY`.
pub const RAIL_ARRAY_ID: u16 = 1;
/// `name` of the rail positions' `DEBUG_FLOAT_ARRAY`.
pub const RAIL_ARRAY_NAME: &str = "rail";

impl VehicleSnapshot {
    /// `DEBUG_FLOAT_ARRAY` `rail` and its `data` (an extension field: its bytes, to send
    /// with `Encoder::encode_extended`), one arc length per robot in use (not a number while
    /// the positions are not known).
    pub fn rail_positions(&self) -> (DEBUG_FLOAT_ARRAY_DATA, [u8; 4 * MAX_ROBOTS], usize) {
        let robots = usize::from(self.robots).min(MAX_ROBOTS);
        let mut data = [0u8; 4 * MAX_ROBOTS];
        for (j, &s) in self.rail[..robots].iter().enumerate() {
            let s = if self.rail_known { s } else { f32::NAN };
            data[4 * j..4 * j + 4].copy_from_slice(&s.to_le_bytes());
        }
        let array = DEBUG_FLOAT_ARRAY_DATA {
            time_usec: self.time_us,
            array_id: RAIL_ARRAY_ID,
            name: RAIL_ARRAY_NAME.into(),
        };
        (array, data, 4 * robots)
    }
}
