//! Plane geometry of the payload: the footprint polygon and its convex hull, and the closed
//! rail with its arc-length parametrisation.
//!
//! docs/formats.md#scenario-keys (`footprint`, `rail`, `candidates` as arc lengths) and
//! docs/models.md#lift-off-thrust (the ground support is the convex hull `H` of the footprint).
//! Coordinates are the payload's body frame in metres.

use core::ops::{Add, Mul, Neg, Sub};

use heapless::Vec;

use crate::math;

/// Most vertices a footprint, its hull or a rail may have.
pub const MAX_VERTICES: usize = 32;

/// A point or a vector in the payload's horizontal plane, metres.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vec2 {
    /// Body x (forward).
    pub x: f32,
    /// Body y (right).
    pub y: f32,
}

impl Vec2 {
    /// A vector from its components.
    pub const fn new(x: f32, y: f32) -> Self {
        Self { x, y }
    }

    /// Dot product.
    pub fn dot(self, other: Self) -> f32 {
        self.x * other.x + self.y * other.y
    }

    /// z component of the cross product `self x other` (positive: `other` is counter-clockwise).
    pub fn cross(self, other: Self) -> f32 {
        self.x * other.y - self.y * other.x
    }

    /// Euclidean length.
    pub fn norm(self) -> f32 {
        math::sqrt(self.dot(self))
    }

    /// True when both components are finite.
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite()
    }
}

impl Add for Vec2 {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y)
    }
}

impl Sub for Vec2 {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y)
    }
}

impl Mul<f32> for Vec2 {
    type Output = Self;
    fn mul(self, k: f32) -> Self {
        Self::new(self.x * k, self.y * k)
    }
}

impl Neg for Vec2 {
    type Output = Self;
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y)
    }
}

/// Why a vertex list is not a usable simple polygon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PolygonError {
    /// Fewer than three vertices.
    TooFewVertices,
    /// More than [`MAX_VERTICES`] vertices.
    TooManyVertices,
    /// A coordinate is NaN or infinite.
    NotFinite {
        /// Index of the offending vertex.
        vertex: usize,
    },
    /// Two consecutive vertices coincide.
    ZeroLengthEdge {
        /// Index of the edge's first vertex.
        edge: usize,
    },
    /// Two edges cross or touch, or an edge folds back onto its neighbour.
    SelfIntersecting {
        /// Index of the first edge.
        edge_a: usize,
        /// Index of the second edge.
        edge_b: usize,
    },
    /// The polygon encloses no area.
    ZeroArea,
}

impl core::fmt::Display for PolygonError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::TooFewVertices => write!(f, "needs at least 3 vertices"),
            Self::TooManyVertices => write!(f, "has more than {MAX_VERTICES} vertices"),
            Self::NotFinite { vertex } => write!(f, "vertex {vertex} is not a finite number"),
            Self::ZeroLengthEdge { edge } => {
                write!(f, "vertices {edge} and the next one coincide")
            }
            Self::SelfIntersecting { edge_a, edge_b } => {
                write!(f, "is self-intersecting (edges {edge_a} and {edge_b} meet)")
            }
            Self::ZeroArea => write!(f, "encloses no area"),
        }
    }
}

impl core::error::Error for PolygonError {}

/// The signed area of a closed polygon (shoelace; positive when counter-clockwise).
pub fn signed_area(vertices: &[Vec2]) -> f32 {
    let n = vertices.len();
    let mut twice = 0.0;
    for i in 0..n {
        twice += vertices[i].cross(vertices[(i + 1) % n]);
    }
    0.5 * twice
}

/// Area moments of a simple polygon about its centroid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaMoments {
    /// Enclosed area, m^2.
    pub area: f32,
    /// Centroid.
    pub centroid: Vec2,
    /// `integral of (x - cx)^2 dA`, m^4.
    pub xx: f32,
    /// `integral of (y - cy)^2 dA`, m^4.
    pub yy: f32,
}

/// Area, centroid and second moments of a simple polygon (either orientation).
pub fn area_moments(vertices: &[Vec2]) -> AreaMoments {
    let n = vertices.len();
    let (mut a2, mut cx, mut cy, mut xx, mut yy) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for i in 0..n {
        let (p, q) = (vertices[i], vertices[(i + 1) % n]);
        let c = p.cross(q);
        a2 += c;
        cx += (p.x + q.x) * c;
        cy += (p.y + q.y) * c;
        xx += c * (p.x * p.x + p.x * q.x + q.x * q.x);
        yy += c * (p.y * p.y + p.y * q.y + q.y * q.y);
    }
    if a2.abs() < 1e-12 {
        return AreaMoments {
            area: 0.0,
            centroid: vertices.first().copied().unwrap_or_default(),
            xx: 0.0,
            yy: 0.0,
        };
    }
    let area = 0.5 * a2;
    let centroid = Vec2::new(cx / (3.0 * a2), cy / (3.0 * a2));
    // Moments about the origin carry the orientation's sign, like the area.
    let (xx0, yy0) = (xx / 12.0 / area.signum(), yy / 12.0 / area.signum());
    let area = area.abs();
    AreaMoments {
        area,
        centroid,
        xx: xx0 - area * centroid.x * centroid.x,
        yy: yy0 - area * centroid.y * centroid.y,
    }
}

/// Checks that `vertices` form a simple closed polygon: at least three finite vertices, no
/// zero-length edge, no two edges meeting except neighbours at their shared vertex, and a
/// non-zero area.
pub fn check_simple_polygon(vertices: &[Vec2]) -> Result<(), PolygonError> {
    let n = vertices.len();
    if n < 3 {
        return Err(PolygonError::TooFewVertices);
    }
    if n > MAX_VERTICES {
        return Err(PolygonError::TooManyVertices);
    }
    if let Some(vertex) = vertices.iter().position(|v| !v.is_finite()) {
        return Err(PolygonError::NotFinite { vertex });
    }
    let edge = |i: usize| (vertices[i], vertices[(i + 1) % n]);
    for i in 0..n {
        let (a, b) = edge(i);
        if (b - a).norm() <= 1e-6 {
            return Err(PolygonError::ZeroLengthEdge { edge: i });
        }
    }
    for i in 0..n {
        let (a, b) = edge(i);
        // A neighbour that folds straight back over this edge.
        let (_, c) = edge((i + 1) % n);
        if (b - a).cross(c - b).abs() <= 1e-9 && (b - a).dot(c - b) < 0.0 {
            return Err(PolygonError::SelfIntersecting {
                edge_a: i,
                edge_b: (i + 1) % n,
            });
        }
        for j in (i + 2)..n {
            if i == 0 && j == n - 1 {
                continue; // neighbours through the closing vertex
            }
            let (p, q) = edge(j);
            if segments_touch(a, b, p, q) {
                return Err(PolygonError::SelfIntersecting {
                    edge_a: i,
                    edge_b: j,
                });
            }
        }
    }
    if math::abs(signed_area(vertices)) <= 1e-9 {
        return Err(PolygonError::ZeroArea);
    }
    Ok(())
}

/// True when closed segments `a-b` and `p-q` share at least one point.
fn segments_touch(a: Vec2, b: Vec2, p: Vec2, q: Vec2) -> bool {
    let side = |o: Vec2, d: Vec2, r: Vec2| {
        let c = d.cross(r - o);
        if c > 1e-9 {
            1
        } else if c < -1e-9 {
            -1
        } else {
            0
        }
    };
    let on_segment = |o: Vec2, e: Vec2, r: Vec2| {
        r.x >= o.x.min(e.x) - 1e-9
            && r.x <= o.x.max(e.x) + 1e-9
            && r.y >= o.y.min(e.y) - 1e-9
            && r.y <= o.y.max(e.y) + 1e-9
    };
    let (ab, pq) = (b - a, q - p);
    let (s1, s2) = (side(a, ab, p), side(a, ab, q));
    let (s3, s4) = (side(p, pq, a), side(p, pq, b));
    if s1 * s2 < 0 && s3 * s4 < 0 {
        return true;
    }
    (s1 == 0 && on_segment(a, b, p))
        || (s2 == 0 && on_segment(a, b, q))
        || (s3 == 0 && on_segment(p, q, a))
        || (s4 == 0 && on_segment(p, q, b))
}

/// True when `p` lies inside the closed polygon `vertices` (crossing number). A point on the
/// boundary may count either way; callers that need a clear answer check for touching first.
pub fn polygon_contains(vertices: &[Vec2], p: Vec2) -> bool {
    let n = vertices.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (vertices[i], vertices[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if p.x < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Distance from `p` to the segment `a-b`.
pub fn distance_to_segment(p: Vec2, a: Vec2, b: Vec2) -> f32 {
    let d = b - a;
    let length2 = d.dot(d);
    let t = if length2 > 0.0 {
        math::clamp((p - a).dot(d) / length2, 0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + d * t)).norm()
}

/// Distance from `p` to the outline of the closed polygon `vertices` (its edges).
pub fn distance_to_outline(vertices: &[Vec2], p: Vec2) -> f32 {
    let n = vertices.len();
    (0..n)
        .map(|i| distance_to_segment(p, vertices[i], vertices[(i + 1) % n]))
        .fold(f32::INFINITY, f32::min)
}

/// The first pair of edges (edge `i` of `a`, edge `j` of `b`; edge `i` runs from vertex `i` to
/// the next) that share a point, if the closed polygons `a` and `b` touch or cross at all.
pub fn first_touching_edges(a: &[Vec2], b: &[Vec2]) -> Option<(usize, usize)> {
    let (n, m) = (a.len(), b.len());
    for i in 0..n {
        for j in 0..m {
            if segments_touch(a[i], a[(i + 1) % n], b[j], b[(j + 1) % m]) {
                return Some((i, j));
            }
        }
    }
    None
}

/// A point of the closed path `path` that lies farther than `max` from the outline of the
/// closed polygon `outline`, with its distance; `None` when every point of the path (not only
/// its vertices) is within `max + tolerance`.
///
/// Branch and bound along each segment: the distance to the outline changes at most as fast as
/// one moves, so on a piece of length `L` whose ends are `d0` and `d1` from the outline, no
/// point is farther than `(d0 + d1 + L) / 2`. Pieces whose bound exceeds `max + tolerance`
/// are halved until a point beyond `max` is found or the bound clears. `tolerance` must be
/// positive; the work grows with `perimeter / tolerance` only where the path runs near `max`.
pub fn farthest_beyond(
    path: &[Vec2],
    outline: &[Vec2],
    max: f32,
    tolerance: f32,
) -> Option<(Vec2, f32)> {
    let tolerance = tolerance.max(1e-6);
    let n = path.len();
    for i in 0..n {
        let (a, b) = (path[i], path[(i + 1) % n]);
        let da = distance_to_outline(outline, a);
        if da > max {
            return Some((a, da));
        }
        let db = distance_to_outline(outline, b);
        // Pieces still to examine, as (start, end, distance at start, distance at end).
        let mut pending: Vec<(Vec2, Vec2, f32, f32), 64> = Vec::new();
        let _ = pending.push((a, b, da, db));
        while let Some((p, q, dp, dq)) = pending.pop() {
            let length = (q - p).norm();
            if 0.5 * (dp + dq + length) <= max + tolerance {
                continue;
            }
            let mid = (p + q) * 0.5;
            let dm = distance_to_outline(outline, mid);
            if dm > max {
                return Some((mid, dm));
            }
            // Halving 64 times takes any finite length below any positive tolerance; a full
            // stack means the piece is already that short.
            if pending.len() + 2 > pending.capacity() || length <= tolerance {
                continue;
            }
            let _ = pending.push((mid, q, dm, dq));
            let _ = pending.push((p, mid, dp, dm));
        }
    }
    None
}

/// The convex hull of a point set, counter-clockwise, without collinear vertices.
#[derive(Clone, Debug, PartialEq)]
pub struct ConvexHull {
    vertices: Vec<Vec2, MAX_VERTICES>,
}

impl ConvexHull {
    /// No hull: what an unloaded payload description holds until it is given one.
    pub const EMPTY: Self = Self {
        vertices: Vec::new(),
    };

    /// Hull of `points` (Andrew's monotone chain). `None` for fewer than three points, more
    /// than [`MAX_VERTICES`], or when all points are collinear.
    pub fn of(points: &[Vec2]) -> Option<Self> {
        let mut sorted: Vec<Vec2, MAX_VERTICES> = Vec::from_slice(points).ok()?;
        if sorted.len() < 3 {
            return None;
        }
        math::sort_small_by(&mut sorted, |a, b| {
            a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)).is_lt()
        });
        // Lower hull then upper hull; each point pops the ones that would make a right turn.
        let mut hull: Vec<Vec2, { 2 * MAX_VERTICES }> = Vec::new();
        for pass in 0..2 {
            let floor = hull.len();
            let push = |p: Vec2, hull: &mut Vec<Vec2, { 2 * MAX_VERTICES }>| {
                while hull.len() >= floor + 2 {
                    let k = hull.len();
                    if (hull[k - 1] - hull[k - 2]).cross(p - hull[k - 2]) <= 1e-9 {
                        hull.pop();
                    } else {
                        break;
                    }
                }
                // Capacity is twice the input, so this cannot overflow.
                let _ = hull.push(p);
            };
            if pass == 0 {
                sorted.iter().for_each(|&p| push(p, &mut hull));
            } else {
                sorted.iter().rev().for_each(|&p| push(p, &mut hull));
            }
            hull.pop(); // the last point of each chain starts the other one
        }
        if hull.len() < 3 {
            return None;
        }
        let vertices = Vec::from_slice(&hull).ok()?;
        Some(Self { vertices })
    }

    /// The hull's vertices, counter-clockwise.
    pub fn vertices(&self) -> &[Vec2] {
        &self.vertices
    }

    /// The hull's edges as (start, end), counter-clockwise, without a division per edge.
    fn edges(&self) -> impl Iterator<Item = (Vec2, Vec2)> + '_ {
        let ends = self.vertices.iter().skip(1).chain(self.vertices.first());
        self.vertices.iter().copied().zip(ends.copied())
    }

    /// True when `p` lies inside the hull or within `tolerance` metres outside its boundary.
    pub fn contains(&self, p: Vec2, tolerance: f32) -> bool {
        self.edges().all(|(a, b)| {
            let d = b - a;
            let side = d.cross(p - a);
            if tolerance >= 0.0 {
                // `side >= -tolerance |d|` without the square root (a long software routine
                // on the Cortex-M7, and the estimator asks this of every point it weighs):
                // inside, or outside by at most the tolerance.
                side >= 0.0 || side * side <= tolerance * tolerance * d.dot(d)
            } else {
                side >= -tolerance * d.norm()
            }
        })
    }

    /// `sup { t >= 0 : origin + t * direction in H }`: how far along `direction` (in units of its
    /// length) a point starting at `origin` can travel before it leaves the hull.
    /// `None` when `origin` is outside the hull; `f32::INFINITY` when `direction` is zero.
    ///
    /// One pass over the edges: each edge's side of `origin` is the containment test's
    /// ([`Self::contains`] with a tolerance of `1e-6`) and the slack the ray uses up.
    pub fn exit_distance(&self, origin: Vec2, direction: Vec2) -> Option<f32> {
        const TOLERANCE: f32 = 1e-6;
        let mut t_max = f32::INFINITY;
        for (a, b) in self.edges() {
            let d = b - a;
            let side = d.cross(origin - a);
            if !(side >= 0.0 || side * side <= TOLERANCE * TOLERANCE * d.dot(d)) {
                return None;
            }
            // Inside: d x (p - a) >= 0. Along the ray it falls at rate d x direction.
            let rate = d.cross(direction);
            if rate < 0.0 {
                t_max = t_max.min(side.max(0.0) / -rate);
            }
        }
        Some(t_max)
    }
}

/// A closed rail through the rotor centres, parametrised by arc length from its first vertex.
#[derive(Clone, Debug, PartialEq)]
pub struct Rail {
    vertices: Vec<Vec2, MAX_VERTICES>,
    /// `cumulative[i]` is the arc length at vertex `i`; the last entry is the perimeter.
    cumulative: Vec<f32, { MAX_VERTICES + 1 }>,
}

impl Rail {
    /// No rail: what an unloaded payload description holds until it is given one.
    pub const EMPTY: Self = Self {
        vertices: Vec::new(),
        cumulative: Vec::new(),
    };

    /// A rail through `vertices` in order, closed back to the first. The path must be a simple
    /// polygon.
    pub fn new(vertices: &[Vec2]) -> Result<Self, PolygonError> {
        check_simple_polygon(vertices)?;
        let vertices: Vec<Vec2, MAX_VERTICES> =
            Vec::from_slice(vertices).map_err(|_| PolygonError::TooManyVertices)?;
        let n = vertices.len();
        let mut cumulative = Vec::new();
        let mut s = 0.0;
        for i in 0..=n {
            // Capacity MAX_VERTICES + 1 holds n + 1 entries.
            let _ = cumulative.push(s);
            if i < n {
                s += (vertices[(i + 1) % n] - vertices[i]).norm();
            }
        }
        Ok(Self {
            vertices,
            cumulative,
        })
    }

    /// The rail's vertices, as given.
    pub fn vertices(&self) -> &[Vec2] {
        &self.vertices
    }

    /// Total length of the closed rail, metres.
    pub fn perimeter(&self) -> f32 {
        self.cumulative[self.cumulative.len() - 1]
    }

    /// `s` brought into `[0, perimeter)`.
    pub fn wrap(&self, s: f32) -> f32 {
        let p = self.perimeter();
        let w = s - p * math::floor(s / p);
        if w >= p { 0.0 } else { w }
    }

    /// Arc length from `from` forward (in the rail's direction) to `to`, in `[0, perimeter)`.
    pub fn forward_gap(&self, from: f32, to: f32) -> f32 {
        self.wrap(to - from)
    }

    /// Number of straight segments (as many as vertices: the rail is closed).
    pub fn segment_count(&self) -> usize {
        self.vertices.len()
    }

    /// Index of the segment holding arc length `s` (wrapped); a vertex belongs to the segment
    /// that starts there.
    pub fn segment_at(&self, s: f32) -> usize {
        let s = self.wrap(s);
        // n is small: a linear scan is fine.
        (0..self.vertices.len())
            .rev()
            .find(|&i| self.cumulative[i] <= s)
            .unwrap_or(0)
    }

    /// Arc lengths where segment `i` starts and ends (`end` may equal the perimeter).
    pub fn segment_span(&self, i: usize) -> (f32, f32) {
        (self.cumulative[i], self.cumulative[i + 1])
    }

    /// Unit direction of segment `i`, in the rail's direction.
    pub fn segment_direction(&self, i: usize) -> Vec2 {
        let n = self.vertices.len();
        let d = self.vertices[(i + 1) % n] - self.vertices[i];
        d * (1.0 / d.norm())
    }

    /// The point at arc length `s` (wrapped onto the rail).
    pub fn point_at(&self, s: f32) -> Vec2 {
        let s = self.wrap(s);
        let n = self.vertices.len();
        let i = self.segment_at(s);
        let (a, b) = (self.vertices[i], self.vertices[(i + 1) % n]);
        let length = self.cumulative[i + 1] - self.cumulative[i];
        let f = if length > 0.0 {
            (s - self.cumulative[i]) / length
        } else {
            0.0
        };
        a + (b - a) * f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pts(raw: &[[f32; 2]]) -> heapless::Vec<Vec2, MAX_VERTICES> {
        raw.iter().map(|p| Vec2::new(p[0], p[1])).collect()
    }

    const L_SHAPE: [[f32; 2]; 6] = [
        [0.0, 0.0],
        [0.62, 0.0],
        [0.62, 0.2],
        [0.2, 0.2],
        [0.2, 0.62],
        [0.0, 0.62],
    ];

    #[test]
    fn l_shape_is_simple_and_its_hull_drops_the_inner_corner() {
        let l = pts(&L_SHAPE);
        assert_eq!(check_simple_polygon(&l), Ok(()));
        let hull = ConvexHull::of(&l).expect("hull");
        assert_eq!(hull.vertices().len(), 5);
        assert!(!hull.vertices().contains(&Vec2::new(0.2, 0.2)));
        assert!(signed_area(hull.vertices()) > 0.0, "counter-clockwise");
        // The inner corner's notch is inside the hull, a point beyond the diagonal is not.
        assert!(hull.contains(Vec2::new(0.35, 0.35), 0.0));
        assert!(!hull.contains(Vec2::new(0.45, 0.45), 0.0));
    }

    #[test]
    fn rectangle_moments_by_hand() {
        let rect = pts(&[[-0.88, -0.1], [0.88, -0.1], [0.88, 0.1], [-0.88, 0.1]]);
        let m = area_moments(&rect);
        assert!((m.area - 0.352).abs() < 1e-6);
        assert!(m.centroid.norm() < 1e-6);
        // b h^3 / 12 about each axis.
        assert!((m.xx - 0.2 * 1.76f32.powi(3) / 12.0).abs() < 1e-5, "{m:?}");
        assert!((m.yy - 1.76 * 0.2f32.powi(3) / 12.0).abs() < 1e-6, "{m:?}");
        let mut reversed = rect.clone();
        reversed.reverse();
        assert_eq!(area_moments(&reversed).area, m.area);
    }

    #[test]
    fn bow_tie_and_spike_are_rejected() {
        let bow = pts(&[[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]]);
        assert!(matches!(
            check_simple_polygon(&bow),
            Err(PolygonError::SelfIntersecting { .. })
        ));
        let spike = pts(&[[0.0, 0.0], [2.0, 0.0], [1.0, 0.0], [1.0, 1.0]]);
        assert!(check_simple_polygon(&spike).is_err());
        let line = pts(&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]);
        assert!(check_simple_polygon(&line).is_err());
    }

    #[test]
    fn exit_distance_matches_the_rectangle_by_hand() {
        let rect = pts(&[[-0.88, -0.1], [0.88, -0.1], [0.88, 0.1], [-0.88, 0.1]]);
        let hull = ConvexHull::of(&rect).expect("hull");
        let t = hull
            .exit_distance(Vec2::new(0.3, 0.0), Vec2::new(0.5, 0.0))
            .expect("inside");
        assert!((t - (0.88 - 0.3) / 0.5).abs() < 1e-5, "t = {t}");
        assert_eq!(
            hull.exit_distance(Vec2::new(1.0, 0.0), Vec2::new(1.0, 0.0)),
            None
        );
    }

    #[test]
    fn crossing_number_sees_the_l_notch_as_outside() {
        let l = pts(&L_SHAPE);
        assert!(polygon_contains(&l, Vec2::new(0.1, 0.1)));
        assert!(polygon_contains(&l, Vec2::new(0.5, 0.1)));
        assert!(!polygon_contains(&l, Vec2::new(0.4, 0.4)), "the notch");
        assert!(!polygon_contains(&l, Vec2::new(-0.1, 0.1)));
    }

    #[test]
    fn touching_edges_are_found_between_two_outlines() {
        let rect = pts(&[[-0.88, -0.1], [0.88, -0.1], [0.88, 0.1], [-0.88, 0.1]]);
        let around = pts(&[[-1.0, -0.22], [1.0, -0.22], [1.0, 0.22], [-1.0, 0.22]]);
        assert_eq!(first_touching_edges(&around, &rect), None);
        // A rail shorter than the payload crosses the payload's long edges.
        let crossing = pts(&[[-0.5, -0.22], [0.5, -0.22], [0.5, 0.22], [-0.5, 0.22]]);
        assert_eq!(first_touching_edges(&crossing, &rect), Some((1, 0)));
    }

    #[test]
    fn clearance_finds_a_far_point_between_two_near_vertices() {
        // A U-shaped payload; the rail spans the U's opening, whose middle is about 1.005 m
        // from the outline although every rail vertex is 0.14 m from it.
        let u = pts(&[
            [0.0, 0.0],
            [4.0, 0.0],
            [4.0, 3.0],
            [3.0, 3.0],
            [3.0, 1.0],
            [1.0, 1.0],
            [1.0, 3.0],
            [0.0, 3.0],
        ]);
        let rail = pts(&[[-0.1, -0.1], [4.1, -0.1], [4.1, 3.1], [-0.1, 3.1]]);
        for &v in rail.iter() {
            assert!(distance_to_outline(&u, v) < 0.15);
        }
        let (at, d) = farthest_beyond(&rail, &u, 1.0, 0.001).expect("the opening is far");
        assert!(d > 1.0 && d < 1.006, "{d}");
        assert!(
            (at.y - 3.1).abs() < 1e-6 && (at.x - 2.0).abs() < 0.1,
            "{at:?}"
        );
        assert_eq!(farthest_beyond(&rail, &u, 1.01, 0.001), None);
        let rect = pts(&[[-0.88, -0.1], [0.88, -0.1], [0.88, 0.1], [-0.88, 0.1]]);
        let around = pts(&[[-1.0, -0.22], [1.0, -0.22], [1.0, 0.22], [-1.0, 0.22]]);
        assert_eq!(farthest_beyond(&around, &rect, 0.17, 0.001), None);
        assert!(
            farthest_beyond(&around, &rect, 0.16, 0.001).is_some(),
            "corner is 0.169 m off"
        );
    }

    #[test]
    fn rail_arc_length_walks_the_rectangle() {
        let rail = Rail::new(&pts(&[
            [-1.0, -0.22],
            [1.0, -0.22],
            [1.0, 0.22],
            [-1.0, 0.22],
        ]))
        .expect("rail");
        assert!((rail.perimeter() - 4.88).abs() < 1e-5);
        let p = rail.point_at(2.22);
        assert!((p - Vec2::new(1.0, 0.0)).norm() < 1e-5, "{p:?}");
        let wrapped = rail.point_at(4.88 + 0.12);
        assert!((wrapped - Vec2::new(-0.88, -0.22)).norm() < 1e-5);
        assert!((rail.forward_gap(4.66, 0.12) - 0.34).abs() < 1e-5);
        assert!((rail.wrap(-0.5) - 4.38).abs() < 1e-5);
    }
}
