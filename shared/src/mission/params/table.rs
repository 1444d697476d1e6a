//! The parameter table: every tunable's name, unit, range, default and where it lives in the
//! [`MissionConfig`], in the order the protocol numbers them. Written in groups, a file for
//! each side of the vehicle; [`TABLE`] joins them in the protocol's order.

use super::*;

mod cascade;
mod flight;
mod ground_link;
mod hardware;
mod manual;
mod mission;

/// Every parameter, in the order the protocol numbers them (`param_index`).
pub static TABLE: [ParamSpec; COUNT] = join(&[
    mission::ESTIMATION,
    mission::RAIL,
    mission::TIMING,
    flight::FLIGHT_FAILSAFES,
    flight::FLIGHT_PLAN,
    cascade::CASCADE,
    flight::ADAPTATION,
    hardware::DRIVERS,
    ground_link::LINK_FAILSAFES,
    ground_link::MAP_ORIGIN,
    hardware::BRING_UP,
    manual::MANUAL_CONTROL,
]);

/// The groups one after another, at compile time; the build fails unless they hold [`COUNT`]
/// parameters.
const fn join(groups: &[&[ParamSpec]]) -> [ParamSpec; COUNT] {
    let mut table = [groups[0][0]; COUNT];
    let mut at = 0;
    let mut g = 0;
    while g < groups.len() {
        let mut i = 0;
        while i < groups[g].len() {
            assert!(at < COUNT, "more parameters than COUNT");
            table[at] = groups[g][i];
            at += 1;
            i += 1;
        }
        g += 1;
    }
    assert!(at == COUNT, "fewer parameters than COUNT");
    table
}
