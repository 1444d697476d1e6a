//! The ground link's parameters: its, the battery's and the geofence's failsafes, and the map origin
//! (docs/ground-link.md#the-map-origin).

use super::*;
use crate::mission::supervision::FenceAction;

/// The ground link's and the battery's failsafes (mission::supervision).
pub(super) const LINK_FAILSAFES: &[ParamSpec] = &[
    ParamSpec {
        name: "FS_GCS_ACT",
        unit: "-",
        min: 0.0,
        max: 2.0,
        integer: true,
        allowed: &[],
        #[cfg(feature = "docs")]
        doc: "ground link lost in flight: 0 not watched (no start refused), 1 fly on to the target and land, 2 hold FS_GCS_HOLD_T then land in place",
        get: |c| c.supervision.gcs_action as u8 as f32,
        set: |c, v| c.supervision.gcs_action = GcsLossAction::from_value(v),
    },
    ParamSpec {
        name: "GF_ACTION",
        unit: "-",
        min: 0.0,
        max: 5.0,
        integer: true,
        allowed: &[0.0, 1.0, 2.0, 5.0],
        #[cfg(feature = "docs")]
        doc: "outside the geofence in flight: 0 not watched, 1 a warning, 2 hold where it is (until the operator lands or resumes), 5 land where it is (PX4's numbers; no return, and no termination: it would drop the payload)",
        get: |c| c.supervision.fence_action as u8 as f32,
        set: |c, v| c.supervision.fence_action = FenceAction::from_value(v),
    },
    param!(
        "GF_MAX_HOR_DIST",
        "m",
        0.0,
        1000.0,
        "the geofence's radius about the take-off point, across the ground; 0 no limit",
        |c| c.supervision.fence_horizontal
    ),
    param!(
        "GF_MAX_VER_DIST",
        "m",
        0.0,
        1000.0,
        "the geofence's height above the take-off point; 0 no limit",
        |c| c.supervision.fence_vertical
    ),
    param!(
        "FS_GCS_LOSS_T",
        "s",
        1.0,
        60.0,
        "time without a ground station's heartbeat before the link counts as lost (PX4's COM_DL_LOSS_T)",
        |c| c.supervision.gcs_timeout
    ),
    param!(
        "FS_GCS_HOLD_T",
        "s",
        0.0,
        300.0,
        "with FS_GCS_ACT 2: time held where the vehicle is before it lands in place (a link back meanwhile resumes the plan)",
        |c| c.supervision.gcs_hold_time
    ),
    param!(
        "BAT_LOW_V",
        "V",
        0.0,
        100.0,
        "filtered pack voltage below which the battery is low: a warning, and no start; 0 off",
        |c| c.supervision.battery_low
    ),
    param!(
        "BAT_CRIT_V",
        "V",
        0.0,
        100.0,
        "filtered pack voltage below which the battery is critical: landing in place (stop on the ground); 0 off",
        |c| c.supervision.battery_critical
    ),
    param!(
        flag "MC_BAT_SCALE_EN",
        "raise the rotors' commands as the pack sags below the thrust map's pack (PX4's name)",
        |c| c.supervision.pack.enabled
    ),
    param!(
        "BAT_V_MAP",
        "V",
        1.0,
        100.0,
        "open-circuit pack voltage at which the thrust map was measured (the voltage compensation's reference)",
        |c| c.supervision.pack.map_volts
    ),
    param!(
        "BAT_V_FULL_DROP",
        "V",
        0.0,
        10.0,
        "how far the thrust map's pack read below its open-circuit voltage with every rotor at full thrust",
        |c| c.supervision.pack.full_load_drop
    ),
];

/// The map origin: the ground link's (a ground station's map), no field of the
/// configuration. Degrees split in a whole part and a part in 1e-7 degrees, each exact as a
/// REAL32 (one float of degrees rounds to 1.7 m); docs/ground-link.md#the-map-origin.
pub(super) const MAP_ORIGIN: &[ParamSpec] = &[
    param!(
        link "ORIG_LAT_DEG",
        "deg",
        -90.0,
        90.0,
        47.0,
        "map origin's latitude (the local frame's origin), whole degrees; plus ORIG_LAT_E7 (default: PX4's simulation home)"
    ),
    param!(
        link "ORIG_LAT_E7",
        "1e-7 deg",
        -9_999_999.0,
        9_999_999.0,
        3_977_420.0,
        "map origin's latitude past ORIG_LAT_DEG, 1e-7 degrees (the same sign)"
    ),
    param!(
        link "ORIG_LON_DEG",
        "deg",
        -180.0,
        180.0,
        8.0,
        "map origin's longitude, whole degrees (east positive); plus ORIG_LON_E7"
    ),
    param!(
        link "ORIG_LON_E7",
        "1e-7 deg",
        -9_999_999.0,
        9_999_999.0,
        5_455_940.0,
        "map origin's longitude past ORIG_LON_DEG, 1e-7 degrees (the same sign)"
    ),
    ParamSpec {
        name: "ORIG_ALT",
        unit: "m",
        min: -1_000.0,
        max: 10_000.0,
        integer: false,
        allowed: &[],
        #[cfg(feature = "docs")]
        doc: "map origin's altitude above mean sea level",
        get: |_| ORIGIN_DEFAULT_ALT,
        set: |_, _| {},
    },
];
