//! A route: the items a ground station's mission asks the vehicle to fly, in the local frame
//! (docs/ground-link.md#missions). It replaces the payload description's single target: the
//! estimation, formation and take-off run as before, then the flight flies the items in
//! order, then lands.
//!
//! Positions are metres north and east of the local frame's origin (the motion-capture
//! frame's, as `flight.target`'s), heights are metres above the take-off point. Every item
//! is checked against the same bounds as `flight.target` ([`MAX_TARGET_DISTANCE`],
//! [`MAX_TARGET_HEIGHT`]); [`Route::check`] names the item and what is wrong.

use crate::math;
use crate::scenario::{MAX_TARGET_DISTANCE, MAX_TARGET_HEIGHT};

/// Most items a route holds (a mission over this is refused as a whole).
pub const MAX_ROUTE_ITEMS: usize = 16;
/// Longest hover one item may ask for, s.
pub const MAX_LOITER_TIME: f32 = 600.0;

/// A point of a route: north and east of the origin and height above the take-off point, m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoutePoint {
    /// North of the origin, m.
    pub north: f32,
    /// East of the origin, m.
    pub east: f32,
    /// Height above the take-off point, m.
    pub height: f32,
}

/// One item of a route.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RouteItem {
    /// Climb straight up to `height` above the take-off point, m.
    Takeoff {
        /// Height, m.
        height: f32,
    },
    /// Fly to the point (the payload arrives there at rest before the next item).
    Waypoint(RoutePoint),
    /// Hover for `seconds`: at the point, or where the vehicle is.
    Loiter {
        /// Where, or `None`: where the vehicle is.
        at: Option<RoutePoint>,
        /// How long, s.
        seconds: f32,
    },
    /// Land: straight below the point (its height is not used), or where the vehicle is.
    /// Nothing may follow it.
    Land {
        /// Where, or `None`: where the vehicle is.
        at: Option<RoutePoint>,
    },
}

impl RouteItem {
    /// The item's name for people (MAVLink's command name).
    pub fn name(&self) -> &'static str {
        match self {
            Self::Takeoff { .. } => "NAV_TAKEOFF",
            Self::Waypoint(_) => "NAV_WAYPOINT",
            Self::Loiter { .. } => "NAV_LOITER_TIME",
            Self::Land { .. } => "NAV_LAND",
        }
    }
}

/// What is wrong with an item of a route.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RouteProblem {
    /// A coordinate or a time is not a number.
    NotFinite,
    /// The point is farther from the origin than `flight.target` may be, m.
    TooFar {
        /// Its distance, m.
        distance: f32,
    },
    /// The height is zero or below.
    NotAboveGround,
    /// The height is over `flight.target`'s bound, m.
    TooHigh {
        /// Its height, m.
        height: f32,
    },
    /// A hover of a negative time or over [`MAX_LOITER_TIME`].
    LoiterTime {
        /// Its time, s.
        seconds: f32,
    },
    /// An item after a landing.
    AfterLand,
    /// The first item the vehicle flies has no height to climb to (it must be a take-off,
    /// a waypoint or a hover at a point).
    NoTakeoffHeight,
    /// More items than [`MAX_ROUTE_ITEMS`].
    TooMany,
}

impl core::fmt::Display for RouteProblem {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        use crate::numbers::Fixed;
        match *self {
            Self::NotFinite => write!(f, "a coordinate is not a number"),
            Self::TooFar { distance } => write!(
                f,
                "{} m from the origin (at most {} m)",
                Fixed(distance, 1),
                Fixed(MAX_TARGET_DISTANCE, 0)
            ),
            Self::NotAboveGround => write!(f, "its height must be above the take-off point"),
            Self::TooHigh { height } => write!(
                f,
                "{} m high (at most {} m)",
                Fixed(height, 1),
                Fixed(MAX_TARGET_HEIGHT, 0)
            ),
            Self::LoiterTime { seconds } => write!(
                f,
                "a hover of {} s (0 to {} s)",
                Fixed(seconds, 0),
                Fixed(MAX_LOITER_TIME, 0)
            ),
            Self::AfterLand => write!(f, "nothing may follow NAV_LAND"),
            Self::NoTakeoffHeight => write!(
                f,
                "the first item needs a height: begin with NAV_TAKEOFF or NAV_WAYPOINT"
            ),
            Self::TooMany => write!(f, "more than {MAX_ROUTE_ITEMS} items"),
        }
    }
}

/// A refused route: which item (from 0) and why.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RouteError {
    /// The item, from 0.
    pub item: usize,
    /// What is wrong with it.
    pub problem: RouteProblem,
}

/// Checks a point against `flight.target`'s bounds.
pub fn check_point(p: &RoutePoint) -> Result<(), RouteProblem> {
    if !(p.north.is_finite() && p.east.is_finite() && p.height.is_finite()) {
        return Err(RouteProblem::NotFinite);
    }
    let distance = math::sqrt(p.north * p.north + p.east * p.east);
    if distance > MAX_TARGET_DISTANCE {
        return Err(RouteProblem::TooFar { distance });
    }
    check_height(p.height)
}

fn check_height(height: f32) -> Result<(), RouteProblem> {
    if !height.is_finite() {
        Err(RouteProblem::NotFinite)
    } else if height <= 0.0 {
        Err(RouteProblem::NotAboveGround)
    } else if height > MAX_TARGET_HEIGHT {
        Err(RouteProblem::TooHigh { height })
    } else {
        Ok(())
    }
}

/// Checks one item on its own (its bounds; not its place in the route).
pub fn check_item(item: &RouteItem) -> Result<(), RouteProblem> {
    match item {
        RouteItem::Takeoff { height } => check_height(*height),
        RouteItem::Waypoint(p) => check_point(p),
        RouteItem::Loiter { at, seconds } => {
            if !seconds.is_finite() {
                return Err(RouteProblem::NotFinite);
            }
            if *seconds < 0.0 || *seconds > MAX_LOITER_TIME {
                return Err(RouteProblem::LoiterTime { seconds: *seconds });
            }
            at.as_ref().map_or(Ok(()), check_point)
        }
        // The landing point's height is not flown: only its place is checked.
        RouteItem::Land { at } => at
            .as_ref()
            .map_or(Ok(()), |p| check_point(&RoutePoint { height: 1.0, ..*p })),
    }
}

/// The items a flight flies, checked.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Route {
    items: heapless::Vec<RouteItem, MAX_ROUTE_ITEMS>,
}

impl Route {
    /// An empty route (the payload description's target is flown).
    pub const EMPTY: Self = Self {
        items: heapless::Vec::new(),
    };

    /// A route of `items`, checked: each item within bounds, nothing after a landing, a
    /// height to take off to.
    pub fn new(items: &[RouteItem]) -> Result<Self, RouteError> {
        let items = heapless::Vec::from_slice(items).map_err(|_| RouteError {
            item: MAX_ROUTE_ITEMS,
            problem: RouteProblem::TooMany,
        })?;
        let route = Self { items };
        route.check()?;
        Ok(route)
    }

    /// Checks the route (see [`Self::new`]).
    pub fn check(&self) -> Result<(), RouteError> {
        let fail = |item, problem| Err(RouteError { item, problem });
        for (i, item) in self.items.iter().enumerate() {
            if let Err(problem) = check_item(item) {
                return fail(i, problem);
            }
            if i > 0 && matches!(self.items[i - 1], RouteItem::Land { .. }) {
                return fail(i, RouteProblem::AfterLand);
            }
        }
        if let Some(first) = self.items.first() {
            let height = match first {
                RouteItem::Takeoff { .. } | RouteItem::Waypoint(_) => true,
                RouteItem::Loiter { at, .. } => at.is_some(),
                RouteItem::Land { .. } => false,
            };
            if !height {
                return fail(0, RouteProblem::NoTakeoffHeight);
            }
        }
        Ok(())
    }

    /// The items, in order.
    pub fn items(&self) -> &[RouteItem] {
        &self.items
    }

    /// Whether there are no items.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// How many items.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Where the route lands (north, east of the origin, m): below its last item with a place
    /// ([`crate::control::trajectory::FlightPlan::from_route`] flies it so); `None` when no
    /// item has one (it lands where it took off).
    pub fn landing_point(&self) -> Option<(f32, f32)> {
        self.items.iter().rev().find_map(|item| match item {
            RouteItem::Waypoint(p)
            | RouteItem::Loiter { at: Some(p), .. }
            | RouteItem::Land { at: Some(p) } => Some((p.north, p.east)),
            _ => None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wp(north: f32, east: f32, height: f32) -> RouteItem {
        RouteItem::Waypoint(RoutePoint {
            north,
            east,
            height,
        })
    }

    #[test]
    fn a_route_within_bounds_is_taken() {
        let route = Route::new(&[
            RouteItem::Takeoff { height: 0.5 },
            wp(0.3, 1.98, 0.5),
            RouteItem::Loiter {
                at: None,
                seconds: 2.0,
            },
            RouteItem::Land { at: None },
        ])
        .expect("within bounds");
        assert_eq!(route.len(), 4);
    }

    #[test]
    fn each_bad_item_is_named_with_its_problem() {
        let cases: [(&[RouteItem], usize, RouteProblem); 7] = [
            (&[wp(f32::NAN, 0.0, 0.5)], 0, RouteProblem::NotFinite),
            (
                &[wp(0.0, 0.0, 0.5), wp(5000.0, 0.0, 0.5)],
                1,
                RouteProblem::TooFar { distance: 5000.0 },
            ),
            (&[wp(0.0, 0.0, 0.0)], 0, RouteProblem::NotAboveGround),
            (
                &[RouteItem::Takeoff { height: 12.0 }],
                0,
                RouteProblem::TooHigh { height: 12.0 },
            ),
            (
                &[
                    wp(0.0, 0.0, 0.5),
                    RouteItem::Loiter {
                        at: None,
                        seconds: -1.0,
                    },
                ],
                1,
                RouteProblem::LoiterTime { seconds: -1.0 },
            ),
            (
                &[
                    wp(0.0, 0.0, 0.5),
                    RouteItem::Land { at: None },
                    wp(0.0, 0.0, 0.5),
                ],
                2,
                RouteProblem::AfterLand,
            ),
            (
                &[RouteItem::Land { at: None }],
                0,
                RouteProblem::NoTakeoffHeight,
            ),
        ];
        for (items, item, problem) in cases {
            assert_eq!(
                Route::new(items),
                Err(RouteError { item, problem }),
                "{items:?}"
            );
        }
        let many = [wp(0.0, 0.0, 0.5); MAX_ROUTE_ITEMS + 1];
        assert_eq!(
            Route::new(&many).map_err(|e| e.problem),
            Err(RouteProblem::TooMany)
        );
    }
}
