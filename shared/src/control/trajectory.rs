//! The reference trajectory: take-off, transit to the target, hover, landing
//! (docs/models.md#reference-trajectory; the target: docs/formats.md#scenario-keys), or the
//! items of a ground station's route ([`crate::flight::route`], docs/ground-link.md#missions)
//! flown one after the other, then a landing.
//!
//! Each segment is a minimum-jerk polynomial `p(t) = a + (b - a) s(t/T)`,
//! `s(u) = 10 u^3 - 15 u^4 + 6 u^5`, smooth in position, velocity and acceleration, with zero
//! velocity and acceleration at both ends. Its duration gives a peak speed
//! `1.875 |b - a| / T` of at most the segment's speed limit. Positions are world NED from the
//! take-off point.

use crate::control::vector::Vec3;
use crate::flight::route::{MAX_ROUTE_ITEMS, Route, RouteItem, RoutePoint};
use crate::math;

/// Where the flight is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlightPhase {
    /// Climbing vertically to the target height.
    Takeoff,
    /// Moving at the target height to above the target.
    Transit,
    /// Holding over the target.
    Hover,
    /// Descending to the ground at the target.
    Land,
    /// The plan is over: the setpoint sits [`SETTLE_DEPTH`] below the ground at the target, so
    /// the controller lets the weight rest on the ground until the landing is detected.
    Done,
}

/// Speed limits and timing of a plan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanLimits {
    /// Peak climb speed, m/s.
    pub climb_speed: f32,
    /// Peak horizontal speed, m/s.
    pub cruise_speed: f32,
    /// Peak descent speed, m/s.
    pub descent_speed: f32,
    /// Time over the target before landing, s.
    pub hover_time: f32,
}

impl PlanLimits {
    /// The defaults.
    pub const DEFAULT: Self = Self {
        climb_speed: 0.3,
        cruise_speed: 0.5,
        descent_speed: 0.25,
        hover_time: 3.0,
    };
}

impl Default for PlanLimits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What the controller should follow at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Setpoint {
    /// Position, m.
    pub position: Vec3,
    /// Velocity, m/s.
    pub velocity: Vec3,
    /// Acceleration (feedforward), m/s^2.
    pub acceleration: Vec3,
    /// Heading, rad.
    pub yaw: f32,
}

/// How far below the ground the setpoint goes once the landing segment is over, m: the
/// position loop then asks for less thrust than the weight and the payload settles, where a
/// setpoint on the ground would keep it hovering at zero height, skating on its contact.
pub const SETTLE_DEPTH: f32 = 0.3;

/// Peak-speed factor of the minimum-jerk profile.
const MIN_JERK_PEAK: f32 = 1.875;
/// Shortest segment, s.
const MIN_DURATION: f32 = 0.5;

/// One minimum-jerk segment of a plan, from rest to rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanSegment {
    /// What the segment does.
    pub phase: FlightPhase,
    /// Start point, NED, m.
    pub from: Vec3,
    /// End point, NED, m.
    pub to: Vec3,
    /// Duration, s.
    pub duration: f32,
    /// Heading, rad.
    pub yaw: f32,
    /// The route item this segment flies (0 for a plan to the payload description's target).
    pub item: u8,
    /// The segment's end is its item's end: the item is reached there.
    pub ends_item: bool,
}

impl PlanSegment {
    fn new(phase: FlightPhase, from: Vec3, to: Vec3, speed: f32, yaw: f32) -> Self {
        let distance = (to - from).norm();
        let duration = (MIN_JERK_PEAK * distance / speed.max(1e-3)).max(MIN_DURATION);
        Self {
            phase,
            from,
            to,
            duration,
            yaw,
            item: 0,
            ends_item: false,
        }
    }

    /// A move from `from` to `to` within both the horizontal and the vertical limits.
    fn moving(phase: FlightPhase, from: Vec3, to: Vec3, limits: &PlanLimits, yaw: f32) -> Self {
        let d = to - from;
        let horizontal = libm::hypotf(d.x, d.y) / limits.cruise_speed.max(1e-3);
        let vertical_speed = if d.z < 0.0 {
            limits.climb_speed
        } else {
            limits.descent_speed
        };
        let vertical = math::abs(d.z) / vertical_speed.max(1e-3);
        let duration = (MIN_JERK_PEAK * math::max(horizontal, vertical)).max(MIN_DURATION);
        Self {
            duration,
            ..Self::new(phase, from, to, 1.0, yaw)
        }
    }

    fn of_item(self, item: usize, ends_item: bool) -> Self {
        Self {
            item: item as u8,
            ends_item,
            ..self
        }
    }

    /// The setpoint `t` seconds into the segment (held at its end after `duration`; a segment
    /// of no duration, such as a hover of no time, is its end at rest).
    pub fn sample(&self, t: f32) -> Setpoint {
        if self.duration.is_nan() || self.duration <= 0.0 {
            return Setpoint {
                position: self.to,
                velocity: Vec3::ZERO,
                acceleration: Vec3::ZERO,
                yaw: self.yaw,
            };
        }
        let u = math::clamp(t / self.duration, 0.0, 1.0);
        let (u2, u3) = (u * u, u * u * u);
        let s = 10.0 * u3 - 15.0 * u3 * u + 6.0 * u3 * u2;
        let ds = (30.0 * u2 - 60.0 * u3 + 30.0 * u2 * u2) / self.duration;
        let dds = (60.0 * u - 180.0 * u2 + 120.0 * u3) / (self.duration * self.duration);
        let d = self.to - self.from;
        Setpoint {
            position: self.from + d * s,
            velocity: d * ds,
            acceleration: d * dds,
            yaw: self.yaw,
        }
    }
}

/// Most segments a plan has: two for each route item (a move to its point, then what it does
/// there), a take-off before the first and a landing after the last.
pub const MAX_PLAN_SEGMENTS: usize = 2 * MAX_ROUTE_ITEMS + 2;

/// The segments of a flight: take-off, transit, hover and landing at the target, a route's
/// items, or a landing where the vehicle is.
#[derive(Clone, Debug, PartialEq)]
pub struct FlightPlan {
    segments: heapless::Vec<PlanSegment, MAX_PLAN_SEGMENTS>,
}

impl FlightPlan {
    /// A plan from `start` (on the ground, NED) to `target` = [x, y, height above ground],
    /// holding heading `yaw`.
    pub fn new(start: Vec3, target: [f32; 3], yaw: f32, limits: PlanLimits) -> Self {
        let height = target[2].max(0.0);
        let top = Vec3::new(start.x, start.y, start.z - height);
        let above = Vec3::new(target[0], target[1], start.z - height);
        let ground = Vec3::new(target[0], target[1], start.z);
        let segments = [
            PlanSegment::new(FlightPhase::Takeoff, start, top, limits.climb_speed, yaw),
            PlanSegment::new(FlightPhase::Transit, top, above, limits.cruise_speed, yaw),
            PlanSegment {
                duration: limits.hover_time.max(0.0),
                ..PlanSegment::new(FlightPhase::Hover, above, above, 1.0, yaw)
            },
            PlanSegment::new(FlightPhase::Land, above, ground, limits.descent_speed, yaw),
        ];
        Self {
            segments: heapless::Vec::from_slice(&segments).unwrap_or_default(),
        }
    }

    /// A plan from `start` (NED; on the ground at NED height `ground`, or in the air) flying
    /// `route`'s items from item `first` on, holding heading `yaw`: on the ground, a take-off
    /// to the first item's height unless it is one; each item's move and what it does; a
    /// landing where the last item ends unless it is one. Each item's last segment is marked
    /// reached ([`PlanSegment::ends_item`]), its items numbered as in the whole route. An
    /// empty route is a plan that lands where it is.
    pub fn from_route(
        start: Vec3,
        ground: f32,
        route: &Route,
        first: usize,
        yaw: f32,
        limits: PlanLimits,
    ) -> Self {
        let mut plan = Self {
            segments: heapless::Vec::new(),
        };
        plan.fill_from_route(start, ground, route, first, yaw, limits);
        plan
    }

    /// This plan becomes [`Self::from_route`]'s, in place (a plan is 1.2 KB: the control
    /// step fills it where it is rather than building and moving one).
    pub fn fill_from_route(
        &mut self,
        start: Vec3,
        ground: f32,
        route: &Route,
        first: usize,
        yaw: f32,
        limits: PlanLimits,
    ) {
        let segments = &mut self.segments;
        segments.clear();
        let at = |p: &RoutePoint| Vec3::new(p.north, p.east, ground - p.height);
        let mut here = start;
        let mut last_item = first;
        let mut landed = false;
        let items = route.items().iter().enumerate().skip(first);
        for (i, item) in items {
            last_item = i;
            // Clear of the ground by more than the land detector's few centimetres.
            let airborne = here.z < ground - 0.05;
            let mut push = |segment: PlanSegment| {
                let _ = segments.push(segment.of_item(i, false));
            };
            // The first item's height: a climb straight up to it first.
            let target = match item {
                RouteItem::Takeoff { height } => Some(Vec3::new(here.x, here.y, ground - height)),
                RouteItem::Waypoint(p) => Some(at(p)),
                RouteItem::Loiter { at: point, .. } => point.as_ref().map(at),
                RouteItem::Land { at: point } => {
                    point.as_ref().map(|p| Vec3::new(p.north, p.east, here.z))
                }
            };
            if !airborne
                && let Some(t) = target
                && !matches!(item, RouteItem::Takeoff { .. } | RouteItem::Land { .. })
            {
                let top = Vec3::new(here.x, here.y, t.z);
                push(PlanSegment::moving(
                    FlightPhase::Takeoff,
                    here,
                    top,
                    &limits,
                    yaw,
                ));
                here = top;
            }
            // After the climb (if any): a move in the air is a transit.
            let phase = if here.z < ground - 0.05 {
                FlightPhase::Transit
            } else {
                FlightPhase::Takeoff
            };
            // A landing where the vehicle already is needs no move to it first.
            let close = |t: Vec3| {
                matches!(item, RouteItem::Land { .. })
                    && libm::hypotf(t.x - here.x, t.y - here.y) < 0.01
            };
            if let Some(t) = target.filter(|&t| !close(t)) {
                push(PlanSegment::moving(phase, here, t, &limits, yaw));
                here = t;
            }
            match item {
                RouteItem::Loiter { seconds, .. } => push(PlanSegment {
                    duration: seconds.max(0.0),
                    ..PlanSegment::new(FlightPhase::Hover, here, here, 1.0, yaw)
                }),
                RouteItem::Land { .. } => {
                    let down = Vec3::new(here.x, here.y, ground);
                    push(PlanSegment::moving(
                        FlightPhase::Land,
                        here,
                        down,
                        &limits,
                        yaw,
                    ));
                    here = down;
                    landed = true;
                }
                RouteItem::Takeoff { .. } | RouteItem::Waypoint(_) => {}
            }
            if let Some(last) = segments.last_mut() {
                last.ends_item = true;
            }
        }
        if !landed {
            let down = Vec3::new(here.x, here.y, ground);
            let land = PlanSegment::moving(FlightPhase::Land, here, down, &limits, yaw);
            let _ = segments.push(land.of_item(last_item, false));
        }
    }

    /// A landing straight down from `from` to the ground at height `ground_z` (NED z).
    pub fn landing(from: Vec3, ground_z: f32, yaw: f32, limits: PlanLimits) -> Self {
        let mut plan = Self {
            segments: heapless::Vec::new(),
        };
        plan.fill_landing(from, ground_z, yaw, limits);
        plan
    }

    /// This plan becomes [`Self::landing`]'s, in place.
    pub fn fill_landing(&mut self, from: Vec3, ground_z: f32, yaw: f32, limits: PlanLimits) {
        let ground = Vec3::new(from.x, from.y, ground_z);
        let land = PlanSegment::new(FlightPhase::Land, from, ground, limits.descent_speed, yaw);
        self.segments.clear();
        let _ = self.segments.push(land);
    }

    /// The plan goes on from `here` (NED, in the air) at segment `index`: that segment becomes a
    /// move from `here` to its end (a hover's a move to its point, then the hover), the
    /// segments after it as they were, in place. After Position mode the flight goes on with
    /// its plan from where the pilot left the vehicle. Nothing changes past the plan's end.
    pub fn resume_from(&mut self, index: usize, here: Vec3, limits: PlanLimits) {
        let Some(current) = self.segments.get(index).copied() else {
            return;
        };
        let hover = current.phase == FlightPhase::Hover;
        let phase = if hover {
            FlightPhase::Transit
        } else {
            current.phase
        };
        let back = PlanSegment::moving(phase, here, current.to, &limits, current.yaw)
            .of_item(usize::from(current.item), current.ends_item && !hover);
        let mut segments = heapless::Vec::<PlanSegment, MAX_PLAN_SEGMENTS>::new();
        let _ = segments.push(back);
        if hover {
            let _ = segments.push(current);
        }
        for s in self.segments.iter().skip(index + 1) {
            let _ = segments.push(*s);
        }
        self.segments = segments;
    }

    /// Segment `index`, in order; `None` past the last.
    pub fn segment(&self, index: usize) -> Option<&PlanSegment> {
        self.segments.get(index)
    }

    /// Total duration when every segment ends on time, s.
    pub fn duration(&self) -> f32 {
        self.segments.iter().map(|s| s.duration).sum()
    }

    /// Where the hover over the target happens (NED); the last point for a landing.
    pub fn hover_point(&self) -> Vec3 {
        self.segments
            .iter()
            .find(|s| s.phase == FlightPhase::Hover)
            .or(self.segments.last())
            .map_or(Vec3::ZERO, |s| s.from)
    }

    /// The setpoint after the last segment: [`SETTLE_DEPTH`] below its end, at rest.
    pub fn settled(&self) -> Setpoint {
        let last = self.segments.last();
        Setpoint {
            position: last.map_or(Vec3::ZERO, |s| s.to) + Vec3::DOWN * SETTLE_DEPTH,
            yaw: last.map_or(0.0, |s| s.yaw),
            ..Setpoint::default()
        }
    }

    /// The setpoint and phase `t` seconds after take-off began, when every segment ends on
    /// time (the flight stack waits at a segment's end until the vehicle is there).
    pub fn sample(&self, t: f32) -> (Setpoint, FlightPhase) {
        let mut start = 0.0;
        for segment in &self.segments {
            if t < start + segment.duration {
                return (segment.sample(t - start), segment.phase);
            }
            start += segment.duration;
        }
        (self.settled(), FlightPhase::Done)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plan_is_continuous_and_respects_its_speed_limits() {
        let limits = PlanLimits::default();
        let plan = FlightPlan::new(Vec3::ZERO, [0.3, 1.98, 0.5], 0.0, limits);
        let dt = 0.0025;
        let mut last = plan.sample(0.0).0;
        let mut t = dt;
        let mut phases = heapless::Vec::<FlightPhase, 8>::new();
        while t < plan.duration() + 1.0 {
            let (sp, phase) = plan.sample(t);
            if phases.last() != Some(&phase) {
                let _ = phases.push(phase);
            }
            // Smooth everywhere but at the end, where the setpoint drops below the ground.
            let jump = (sp.position - last.position).norm();
            let settling = phase == FlightPhase::Done;
            assert!(jump < 0.6 * dt * 2.0 || settling, "jump at {t}");
            assert!(
                (sp.velocity - last.velocity).norm() < 0.05,
                "velocity jump at {t}"
            );
            let v = sp.velocity;
            assert!(libm::hypotf(v.x, v.y) <= limits.cruise_speed + 1e-3);
            assert!(v.z.abs() <= limits.climb_speed.max(limits.descent_speed) + 1e-3);
            last = sp;
            t += dt;
        }
        assert_eq!(
            phases.as_slice(),
            &[
                FlightPhase::Takeoff,
                FlightPhase::Transit,
                FlightPhase::Hover,
                FlightPhase::Land,
                FlightPhase::Done
            ]
        );
        let top = plan.sample(plan.duration() * 0.0 + 1.875 * 0.5 / 0.3).0;
        assert!(
            (top.position.z + 0.5).abs() < 1e-3,
            "reaches the target height"
        );
        assert!((plan.hover_point() - Vec3::new(0.3, 1.98, -0.5)).norm() < 1e-6);
        let settled = Vec3::new(0.3, 1.98, SETTLE_DEPTH);
        assert!(
            (last.position - settled).norm() < 1e-6,
            "settles at the target"
        );
        let touchdown = plan.sample(plan.duration() - 1e-3).0.position;
        assert!(
            (touchdown - Vec3::new(0.3, 1.98, 0.0)).norm() < 5e-3,
            "lands at the target: {touchdown:?}"
        );
    }

    /// A route's plan: a climb to the first item's height, each item's move and hover, and
    /// a landing below the last; each item's last segment marks it reached, in order; every
    /// move within its speed limits.
    #[test]
    fn a_route_plan_flies_each_item_and_marks_it_reached() {
        use crate::flight::route::{Route, RouteItem, RoutePoint};
        let p = |north, east, height| RoutePoint {
            north,
            east,
            height,
        };
        let route = Route::new(&[
            RouteItem::Waypoint(p(1.0, 0.0, 0.7)),
            RouteItem::Loiter {
                at: None,
                seconds: 2.0,
            },
            RouteItem::Waypoint(p(1.0, 1.0, 0.5)),
        ])
        .expect("a route");
        let limits = PlanLimits::default();
        let plan = FlightPlan::from_route(Vec3::ZERO, 0.0, &route, 0, 0.0, limits);
        let phases: heapless::Vec<(FlightPhase, u8, bool), 8> = (0..8)
            .filter_map(|i| plan.segment(i))
            .map(|s| (s.phase, s.item, s.ends_item))
            .collect();
        use FlightPhase::*;
        assert_eq!(
            phases.as_slice(),
            &[
                (Takeoff, 0, false),
                (Transit, 0, true),
                (Hover, 1, true),
                (Transit, 2, true),
                (Land, 2, false)
            ]
        );
        let end = plan.segment(4).expect("the landing").to;
        assert!((end - Vec3::new(1.0, 1.0, 0.0)).norm() < 1e-6);
        let mut t = 0.0;
        while t < plan.duration() {
            let v = plan.sample(t).0.velocity;
            assert!(
                libm::hypotf(v.x, v.y) <= limits.cruise_speed + 1e-3,
                "at {t}"
            );
            assert!(v.z <= limits.descent_speed + 1e-3 && -v.z <= limits.climb_speed + 1e-3);
            t += 0.01;
        }
        // From item 2 in the air: straight there, then down.
        let here = Vec3::new(0.5, 0.0, -0.6);
        let jump = FlightPlan::from_route(here, 0.0, &route, 2, 0.0, limits);
        assert_eq!(
            jump.segment(0).map(|s| (s.phase, s.item)),
            Some((Transit, 2))
        );
        assert_eq!(jump.segment(0).map(|s| s.from), Some(here));
    }

    /// `PLN_HOVER_T` may be 0 (no hover): the hover segment then lasts no time, and its
    /// setpoint, sampled by the flight stack at its first tick, was 0/0 (NaN thrusts in
    /// flight). Every segment's setpoint is finite at any time, whatever its length.
    #[test]
    fn a_segment_of_no_duration_holds_its_end_at_rest() {
        let limits = PlanLimits {
            hover_time: 0.0,
            ..PlanLimits::DEFAULT
        };
        let plan = FlightPlan::new(Vec3::ZERO, [0.3, 1.98, 0.5], 0.0, limits);
        let hover = plan.segment(2).expect("a hover segment");
        assert_eq!(hover.phase, FlightPhase::Hover);
        assert_eq!(hover.duration, 0.0);
        for t in [0.0, 0.0025, 1.0, -1.0] {
            let sp = hover.sample(t);
            assert_eq!(sp.position, hover.to, "at {t}");
            assert_eq!(sp.velocity, Vec3::ZERO, "at {t}");
            assert_eq!(sp.acceleration, Vec3::ZERO, "at {t}");
        }
        let mut t = 0.0;
        while t < plan.duration() + 1.0 {
            let (sp, _) = plan.sample(t);
            let finite = [sp.position, sp.velocity, sp.acceleration]
                .iter()
                .all(|v| v.x.is_finite() && v.y.is_finite() && v.z.is_finite());
            assert!(finite, "at {t}: {sp:?}");
            t += 0.0025;
        }
    }

    #[test]
    fn a_plan_resumed_in_the_hover_flies_back_to_its_point_then_hovers_and_lands() {
        let limits = PlanLimits::DEFAULT;
        let mut plan = FlightPlan::new(Vec3::ZERO, [2.0, 0.0, 1.0], 0.0, limits);
        let hover = *plan.segment(2).expect("a hover");
        let here = Vec3::new(3.0, 1.0, -1.5);
        plan.resume_from(2, here, limits);
        let back = plan.segment(0).expect("the move back");
        assert_eq!(
            (back.phase, back.from, back.to),
            (FlightPhase::Transit, here, hover.to)
        );
        assert_eq!(plan.segment(1), Some(&hover));
        assert_eq!(plan.segment(2).map(|s| s.phase), Some(FlightPhase::Land));
        assert_eq!(plan.segment(3), None);
        // In a transit: from here to the transit's end, then the rest.
        let mut plan = FlightPlan::new(Vec3::ZERO, [2.0, 0.0, 1.0], 0.0, limits);
        let transit = *plan.segment(1).expect("a transit");
        plan.resume_from(1, here, limits);
        let back = plan.segment(0).expect("the move back");
        assert_eq!((back.phase, back.to), (FlightPhase::Transit, transit.to));
        assert_eq!(plan.segment(1).map(|s| s.phase), Some(FlightPhase::Hover));
    }
}
