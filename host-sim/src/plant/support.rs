//! The payload's plate as the ground touches it (docs/models.md: on flat ground the payload
//! rests on its footprint's convex hull): the colliders rapier's contact is given.
//!
//! parry3d (rapier's geometry) keeps at most four corners of a polyhedron's face for contact
//! (its polygonal feature holds four vertices), so a plate whose hull has five or more corners
//! rested on four of them: a payload whose centre of mass lay outside those four sank into
//! the ground on its other side, tipping and knocking at 55 to 80 m/s^2, which the IMU monitor
//! read as noise. Such a plate therefore also gets a small ball under each hull corner, its
//! lowest point on the plate's underside: each is one smooth contact, and together they
//! carry the whole hull. A hull of at most four corners is the plate alone, as before.

use rapier3d::prelude::Vector;
use shared::geometry::{ConvexHull, Vec2};

/// Radius of a corner's ball, m: small beside any footprint, so a tilt of even 30 degrees
/// moves its lowest point by under a millimetre from the corner's.
pub const FOOT_RADIUS: f32 = 0.005;

/// What the ground touches: the plate (a convex polyhedron's corners) and the centres of the
/// corner balls of radius [`FOOT_RADIUS`] (body frame, NED).
#[derive(Clone, Debug, PartialEq)]
pub struct Support {
    /// The plate's corners, `thickness` m thick above the ground plane (NED: from z = 0 up to
    /// z = -thickness).
    pub plate: Vec<Vector>,
    /// The balls' centres: none for a hull of at most four corners.
    pub feet: Vec<Vector>,
}

/// The support of a plate of `footprint` and `thickness` m.
pub fn support(footprint: &[Vec2], thickness: f32) -> Support {
    let plate = footprint
        .iter()
        .flat_map(|p| {
            [
                Vector::new(p.x, p.y, 0.0),
                Vector::new(p.x, p.y, -thickness),
            ]
        })
        .collect();
    let feet = match ConvexHull::of(footprint) {
        Some(hull) if hull.vertices().len() > 4 => hull
            .vertices()
            .iter()
            .map(|p| Vector::new(p.x, p.y, -FOOT_RADIUS))
            .collect(),
        _ => Vec::new(),
    };
    Support { plate, feet }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn polygon(n: usize) -> Vec<Vec2> {
        (0..n)
            .map(|i| {
                let a = i as f32 * std::f32::consts::TAU / n as f32;
                Vec2::new(a.cos(), a.sin())
            })
            .collect()
    }

    #[test]
    fn a_hull_of_more_than_four_corners_stands_on_a_foot_at_each() {
        for n in 3..=9 {
            let s = support(&polygon(n), 0.03);
            assert_eq!(s.plate.len(), 2 * n, "{n} corners");
            assert_eq!(s.feet.len(), if n <= 4 { 0 } else { n }, "{n} corners");
            for foot in &s.feet {
                // Its lowest point on the plate's underside, under a corner.
                assert!((foot.z + FOOT_RADIUS).abs() < 1e-7);
                assert!((foot.x.hypot(foot.y) - 1.0).abs() < 1e-5, "{foot:?}");
            }
        }
    }

    #[test]
    fn a_concave_footprint_stands_on_its_hull_alone() {
        // An L: six corners, five on its hull (the inner corner is not).
        let l = [
            Vec2::new(0.0, 0.0),
            Vec2::new(2.0, 0.0),
            Vec2::new(2.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 2.0),
            Vec2::new(0.0, 2.0),
        ];
        let s = support(&l, 0.03);
        assert_eq!(s.feet.len(), 5);
        assert!(
            !s.feet
                .iter()
                .any(|f| (f.x - 1.0).abs() < 1e-6 && (f.y - 1.0).abs() < 1e-6)
        );
    }
}
