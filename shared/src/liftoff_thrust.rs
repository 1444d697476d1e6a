//! Lift-off thrust: the thrust per robot at which a group of robots lifting together makes the
//! payload pivot off the ground (docs/models.md#lift-off-thrust; Oishi & Jimbo (2025), eq. (1);
//! the equilibrium of Corah et al. (2017) in closed form).
//!
//! With `k` robots at rotor points `p_j` each applying thrust `T`, robot mass `m_r`, payload mass
//! `M` at COM `c`, and every other robot holding its own weight, the ground reaction's centre of
//! pressure is `q(t) = c + t (c - m)` with `m = mean(p_j)`, `t = k u / (M g - k u)`,
//! `u = T - m_r g`. The payload pivots when `q` leaves the convex hull `H` of the footprint:
//!
//! ```text
//! t*        = sup { t >= 0 : c + t (c - m) in H }
//! lambda    = m_r g + M g t* / (k (1 + t*))
//! ```
//!
//! [`lift_fraction`] is the part that depends on geometry only, `f = t* / (k (1 + t*))`, so that
//! `lambda = m_r g + M g f`: the estimator evaluates `f` once per COM and reuses it for every
//! mass on the grid.

use crate::geometry::{ConvexHull, Vec2};
use crate::scenario::GRAVITY;

/// Mean of the rotor points of a lifting group (`m` above). `None` for an empty group.
pub fn group_centroid(rotor_points: &[Vec2]) -> Option<Vec2> {
    if rotor_points.is_empty() {
        return None;
    }
    let sum = rotor_points.iter().fold(Vec2::default(), |acc, &p| acc + p);
    Some(sum * (1.0 / rotor_points.len() as f32))
}

/// `f = t* / (k (1 + t*))` for a COM `com` and a group of `k` robots whose rotor points have
/// centroid `centroid`: the share of the payload's weight each robot of the group carries at
/// lift-off. In `[0, 1/k]`; `1/k` when the group sits right above the COM (the whole payload
/// comes up at once). `None` when the COM lies outside the hull (no such payload can rest).
pub fn lift_fraction(hull: &ConvexHull, com: Vec2, centroid: Vec2, k: usize) -> Option<f32> {
    if k == 0 {
        return None;
    }
    let t_star = hull.exit_distance(com, com - centroid)?;
    let per_robot = 1.0 / k as f32;
    if t_star.is_infinite() {
        return Some(per_robot);
    }
    Some(per_robot * t_star / (1.0 + t_star))
}

/// Thrust per robot at lift-off (N) from the geometric share `fraction` ([`lift_fraction`]):
/// `m_r g + M g f`.
pub fn thrust_from_fraction(fraction: f32, mass: f32, robot_mass: f32) -> f32 {
    robot_mass * GRAVITY + mass * GRAVITY * fraction
}

/// Thrust per robot at lift-off (N) for a payload of `mass` (kg) at `com`, lifted by robots of
/// `robot_mass` (kg) at `rotor_points`. `None` when the COM lies outside the hull or the group
/// is empty.
pub fn lift_off_thrust(
    hull: &ConvexHull,
    com: Vec2,
    mass: f32,
    rotor_points: &[Vec2],
    robot_mass: f32,
) -> Option<f32> {
    let centroid = group_centroid(rotor_points)?;
    let f = lift_fraction(hull, com, centroid, rotor_points.len())?;
    Some(thrust_from_fraction(f, mass, robot_mass))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::MAX_VERTICES;
    use proptest::prelude::*;

    fn hull(raw: &[[f32; 2]]) -> ConvexHull {
        let pts: heapless::Vec<Vec2, MAX_VERTICES> =
            raw.iter().map(|p| Vec2::new(p[0], p[1])).collect();
        ConvexHull::of(&pts).expect("hull")
    }

    const RECT: [[f32; 2]; 4] = [[-0.88, -0.1], [0.88, -0.1], [0.88, 0.1], [-0.88, 0.1]];
    const L_SHAPE: [[f32; 2]; 6] = [
        [0.0, 0.0],
        [0.62, 0.0],
        [0.62, 0.2],
        [0.2, 0.2],
        [0.2, 0.62],
        [0.0, 0.62],
    ];

    #[test]
    fn end_pair_on_the_rectangle_by_hand() {
        // Pair at x = -1.0 on both long sides: centroid (-1, 0). COM at the centre.
        // The pivot line is the far short edge x = 0.88: t* = 0.88 / 1.0.
        let h = hull(&RECT);
        let points = [Vec2::new(-1.0, -0.22), Vec2::new(-1.0, 0.22)];
        let lambda = lift_off_thrust(&h, Vec2::new(0.0, 0.0), 3.0, &points, 0.1).unwrap();
        let t = 0.88_f32;
        let expected = 0.1 * GRAVITY + 3.0 * GRAVITY * t / (2.0 * (1.0 + t));
        assert!((lambda - expected).abs() < 1e-4, "{lambda} vs {expected}");
    }

    #[test]
    fn com_on_the_far_edge_pivots_immediately_and_above_the_group_lifts_all() {
        let h = hull(&RECT);
        let c = Vec2::new(0.88, 0.0);
        assert_eq!(lift_fraction(&h, c, Vec2::new(-1.0, 0.0), 2), Some(0.0));
        let c = Vec2::new(0.3, 0.0);
        assert_eq!(lift_fraction(&h, c, c, 2), Some(0.5));
        assert_eq!(lift_fraction(&h, Vec2::new(2.0, 0.0), c, 2), None);
    }

    /// Independent formulation: the paper's equilibrium as a small LP. At lift-off thrust the
    /// ground reaction `R = M g - k u >= 0` must sit at a point of the hull; `u` is the largest
    /// value for which some convex combination of hull vertices (weights `>= 0`) balances the
    /// moments. Solved by brute force: bisection on `u` with an exact feasibility test (is
    /// the centre of pressure inside the hull, checked against every vertex triangle fan).
    fn lift_off_by_lp(h: &ConvexHull, c: Vec2, mass: f32, points: &[Vec2], mr: f32) -> f32 {
        let k = points.len() as f32;
        let m = points.iter().fold(Vec2::default(), |a, &p| a + p) * (1.0 / k);
        let w = mass * GRAVITY;
        let feasible = |u: f32| {
            let reaction = w - k * u;
            if reaction <= 0.0 {
                return (c - m).norm() < 1e-6 && reaction.abs() < 1e-6;
            }
            // Moment balance about the origin: reaction * q + k u m = w c.
            let q = (c * w - m * (k * u)) * (1.0 / reaction);
            in_fan(h.vertices(), q)
        };
        let (mut lo, mut hi) = (0.0_f32, w / k);
        if feasible(hi) {
            return mr * GRAVITY + hi;
        }
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if feasible(mid) { lo = mid } else { hi = mid }
        }
        mr * GRAVITY + lo
    }

    /// Point in a convex polygon as a union of fan triangles with barycentric weights >= 0.
    fn in_fan(v: &[Vec2], q: Vec2) -> bool {
        (1..v.len() - 1).any(|i| {
            let (a, b, c) = (v[0], v[i], v[i + 1]);
            let d = (b - a).cross(c - a);
            let l1 = (b - q).cross(c - q) / d;
            let l2 = (c - q).cross(a - q) / d;
            let l3 = 1.0 - l1 - l2;
            l1 >= -1e-6 && l2 >= -1e-6 && l3 >= -1e-6
        })
    }

    proptest! {
        #[test]
        fn closed_form_matches_the_lp_on_the_l_shape(
            cx in 0.0f32..0.62, cy in 0.0f32..0.62, mass in 1.0f32..5.0,
            s in 0.0f32..1.0, spread in 0.1f32..0.5,
        ) {
            let h = hull(&L_SHAPE);
            let c = Vec2::new(cx, cy);
            prop_assume!(h.contains(c, -1e-3));
            // Two rotor points on a ring around the L, 0.12 m outside its hull.
            let angle = s * core::f32::consts::TAU;
            let at = |a: f32| Vec2::new(0.31 + 0.55 * libm::cosf(a), 0.31 + 0.55 * libm::sinf(a));
            let points = [at(angle), at(angle + spread)];
            let closed = lift_off_thrust(&h, c, mass, &points, 0.1).unwrap();
            let lp = lift_off_by_lp(&h, c, mass, &points, 0.1);
            prop_assert!((closed - lp).abs() < 2e-3 * (1.0 + lp), "closed {} lp {}", closed, lp);
        }

        #[test]
        fn lift_off_thrust_is_monotone_in_mass(
            cx in -0.8f32..0.8, cy in -0.09f32..0.09, m1 in 0.5f32..5.0, dm in 0.01f32..2.0,
        ) {
            let h = hull(&RECT);
            let points = [Vec2::new(1.0, -0.22), Vec2::new(1.0, 0.22)];
            let c = Vec2::new(cx, cy);
            let a = lift_off_thrust(&h, c, m1, &points, 0.1).unwrap();
            let b = lift_off_thrust(&h, c, m1 + dm, &points, 0.1).unwrap();
            prop_assert!(b >= a);
            prop_assert!(a >= 0.1 * GRAVITY - 1e-6);
            prop_assert!(a <= 0.1 * GRAVITY + m1 * GRAVITY / 2.0 + 1e-4);
        }
    }
}
