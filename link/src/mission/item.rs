//! A mission item to the route item it asks the vehicle to fly, in the local frame
//! (docs/ground-link.md#missions): the global position mapped by the map origin, the
//! altitude to a height above the take-off point, and the checks of `flight.target`.
//!
//! | command | flown as |
//! |---|---|
//! | `MAV_CMD_NAV_TAKEOFF` | a climb straight up to its altitude |
//! | `MAV_CMD_NAV_WAYPOINT` | a move to its position and altitude (the payload arrives at rest) |
//! | `MAV_CMD_NAV_LOITER_TIME` | a hover of param 1 seconds, at its position (latitude and longitude 0: where the vehicle is) |
//! | `MAV_CMD_NAV_LAND` | a landing below its position (latitude and longitude 0: where the vehicle is) |
//!
//! Frames: `MAV_FRAME_GLOBAL_RELATIVE_ALT` (the altitude is the height above the take-off
//! point, QGroundControl's default) and `MAV_FRAME_GLOBAL` (above mean sea level: the height
//! is over the origin's altitude, the floor of the motion-capture volume), each also in
//! their deprecated `_INT` twins; `MAV_FRAME_MISSION` for a hover or a landing where the
//! vehicle is. Anything else is refused.

use shared::flight::route::{RouteItem, RoutePoint, RouteProblem, check_item};

use crate::geo::{GeoOrigin, GlobalPoint, OriginError};
use crate::mission::wire::WireItem;
use crate::msg::MavMissionResult;

/// `MAV_CMD_NAV_WAYPOINT`.
pub const NAV_WAYPOINT: u16 = 16;
/// `MAV_CMD_NAV_LOITER_TIME`.
pub const NAV_LOITER_TIME: u16 = 19;
/// `MAV_CMD_NAV_LAND`.
pub const NAV_LAND: u16 = 21;
/// `MAV_CMD_NAV_TAKEOFF`.
pub const NAV_TAKEOFF: u16 = 22;

/// `MAV_FRAME_GLOBAL`, `MAV_FRAME_MISSION`, `MAV_FRAME_GLOBAL_RELATIVE_ALT` and the `_INT`
/// twins of the global ones.
const GLOBAL: u8 = 0;
const MISSION: u8 = 2;
const GLOBAL_RELATIVE: u8 = 3;
const GLOBAL_INT: u8 = 5;
const GLOBAL_RELATIVE_INT: u8 = 6;

/// Why an item is refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ItemProblem {
    /// A command the vehicle does not fly (its number).
    Command(u16),
    /// A frame the vehicle does not fly (its number).
    Frame(u8),
    /// The map origin cannot place a global position.
    Origin(OriginError),
    /// Out of `flight.target`'s bounds, or not a number.
    Route(RouteProblem),
}

impl ItemProblem {
    /// The `MISSION_ACK` result it is refused with.
    pub fn result(&self) -> MavMissionResult {
        match self {
            Self::Command(_) => MavMissionResult::MAV_MISSION_UNSUPPORTED,
            Self::Frame(_) => MavMissionResult::MAV_MISSION_UNSUPPORTED_FRAME,
            Self::Origin(_) => MavMissionResult::MAV_MISSION_DENIED,
            Self::Route(RouteProblem::LoiterTime { .. }) => {
                MavMissionResult::MAV_MISSION_INVALID_PARAM1
            }
            Self::Route(RouteProblem::TooFar { .. }) => {
                MavMissionResult::MAV_MISSION_INVALID_PARAM5_X
            }
            Self::Route(RouteProblem::NotAboveGround | RouteProblem::TooHigh { .. }) => {
                MavMissionResult::MAV_MISSION_INVALID_PARAM7
            }
            Self::Route(RouteProblem::TooMany) => MavMissionResult::MAV_MISSION_NO_SPACE,
            Self::Route(_) => MavMissionResult::MAV_MISSION_INVALID,
        }
    }
}

impl core::fmt::Display for ItemProblem {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Command(c) => write!(
                f,
                "command {c} is not flown (NAV_WAYPOINT, NAV_TAKEOFF, NAV_LOITER_TIME, NAV_LAND are)"
            ),
            Self::Frame(fr) => write!(
                f,
                "frame {fr} is not flown (use a global frame: relative altitude or above sea level)"
            ),
            Self::Origin(e) => write!(f, "no map origin to place it: {}", e.as_str()),
            Self::Route(p) => write!(f, "{p}"),
        }
    }
}

/// The name of a command for people.
pub fn command_name(command: u16) -> &'static str {
    match command {
        NAV_WAYPOINT => "NAV_WAYPOINT",
        NAV_LOITER_TIME => "NAV_LOITER_TIME",
        NAV_LAND => "NAV_LAND",
        NAV_TAKEOFF => "NAV_TAKEOFF",
        _ => "command",
    }
}

/// The route item `item` asks for, with the map origin `origin`; checked on its own (its
/// place in the route is [`shared::flight::Route::check`]'s).
pub fn to_route_item(item: &WireItem, origin: &GeoOrigin) -> Result<RouteItem, ItemProblem> {
    if !matches!(
        item.command,
        NAV_WAYPOINT | NAV_LOITER_TIME | NAV_LAND | NAV_TAKEOFF
    ) {
        return Err(ItemProblem::Command(item.command));
    }
    let relative = match item.frame {
        GLOBAL_RELATIVE | GLOBAL_RELATIVE_INT => true,
        GLOBAL | GLOBAL_INT => false,
        MISSION if matches!(item.command, NAV_LOITER_TIME | NAV_LAND) => true,
        other => return Err(ItemProblem::Frame(other)),
    };
    if !item.z.is_finite() && item.command != NAV_LAND {
        return Err(ItemProblem::Route(RouteProblem::NotFinite));
    }
    let height = if relative {
        item.z
    } else {
        item.z - origin.alt_m
    };
    // Latitude and longitude 0 (or a frame without a position): where the vehicle is.
    let here = item.frame == MISSION || (item.x == 0 && item.y == 0);
    let point = |height: f32| -> Result<RoutePoint, ItemProblem> {
        origin.check().map_err(ItemProblem::Origin)?;
        let p = GlobalPoint {
            lat_e7: item.x,
            lon_e7: item.y,
            alt_mm: (origin.alt_m * 1000.0) as i32,
        };
        let [north, east, _] = origin
            .to_local(&p)
            .ok_or(ItemProblem::Route(RouteProblem::NotFinite))?;
        Ok(RoutePoint {
            north,
            east,
            height,
        })
    };
    let route = match item.command {
        NAV_TAKEOFF => RouteItem::Takeoff { height },
        NAV_WAYPOINT => RouteItem::Waypoint(point(height)?),
        NAV_LOITER_TIME => RouteItem::Loiter {
            at: if here { None } else { Some(point(height)?) },
            seconds: item.params[0],
        },
        _ => RouteItem::Land {
            at: if here { None } else { Some(point(1.0)?) },
        },
    };
    check_item(&route).map_err(ItemProblem::Route)?;
    Ok(route)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ORIGIN: GeoOrigin = GeoOrigin {
        lat_e7: 356_812_000,
        lon_e7: 1_397_671_000,
        alt_m: 40.0,
    };

    fn at(north: f32, east: f32) -> (i32, i32) {
        let p = ORIGIN.to_global([north, east, 0.0]).expect("a point");
        (p.lat_e7, p.lon_e7)
    }

    fn waypoint(north: f32, east: f32, z: f32, frame: u8) -> WireItem {
        let (x, y) = at(north, east);
        WireItem {
            command: NAV_WAYPOINT,
            frame,
            autocontinue: 1,
            x,
            y,
            z,
            ..Default::default()
        }
    }

    #[test]
    fn a_waypoint_lands_in_the_local_frame_within_a_centimetre() {
        let Ok(RouteItem::Waypoint(p)) =
            to_route_item(&waypoint(0.3, 1.98, 0.5, GLOBAL_RELATIVE_INT), &ORIGIN)
        else {
            panic!("refused");
        };
        assert!(
            (p.north - 0.3).abs() < 0.01 && (p.east - 1.98).abs() < 0.01,
            "{p:?}"
        );
        assert_eq!(p.height, 0.5);
        // Above sea level: the height is over the origin's altitude.
        let Ok(RouteItem::Waypoint(p)) =
            to_route_item(&waypoint(0.3, 1.98, 41.5, GLOBAL_INT), &ORIGIN)
        else {
            panic!("refused");
        };
        assert!((p.height - 1.5).abs() < 1e-4);
    }

    #[test]
    fn bad_items_are_refused_with_a_result_and_a_reason() {
        let far = waypoint(5000.0, 0.0, 0.5, GLOBAL_RELATIVE_INT);
        let nan = WireItem {
            z: f32::NAN,
            ..waypoint(0.0, 0.0, 0.5, GLOBAL_RELATIVE_INT)
        };
        let local = waypoint(0.0, 0.0, 0.5, 1);
        let rtl = WireItem {
            command: 20,
            ..waypoint(0.0, 0.0, 0.5, GLOBAL_RELATIVE_INT)
        };
        let high = waypoint(0.0, 0.0, 50.0, GLOBAL_RELATIVE_INT);
        let cases = [
            (
                far,
                MavMissionResult::MAV_MISSION_INVALID_PARAM5_X,
                "from the origin",
            ),
            (nan, MavMissionResult::MAV_MISSION_INVALID, "not a number"),
            (
                local,
                MavMissionResult::MAV_MISSION_UNSUPPORTED_FRAME,
                "frame 1",
            ),
            (rtl, MavMissionResult::MAV_MISSION_UNSUPPORTED, "command 20"),
            (high, MavMissionResult::MAV_MISSION_INVALID_PARAM7, "m high"),
        ];
        for (item, result, says) in cases {
            let e = to_route_item(&item, &ORIGIN).expect_err("refused");
            assert_eq!(e.result(), result, "{item:?}");
            let text = std::format!("{e}");
            assert!(text.contains(says), "{text}");
        }
    }

    #[test]
    fn a_landing_or_hover_without_a_position_is_where_the_vehicle_is() {
        let land = WireItem {
            command: NAV_LAND,
            frame: GLOBAL_RELATIVE_INT,
            ..Default::default()
        };
        assert_eq!(
            to_route_item(&land, &ORIGIN),
            Ok(RouteItem::Land { at: None })
        );
        let hover = WireItem {
            command: NAV_LOITER_TIME,
            frame: MISSION,
            params: [4.0, 0.0, 0.0, 0.0],
            ..Default::default()
        };
        assert_eq!(
            to_route_item(&hover, &ORIGIN),
            Ok(RouteItem::Loiter {
                at: None,
                seconds: 4.0
            })
        );
    }
}
