//! Cheap tests of one segment assignment before it is solved (docs/models.md#formation-search):
//! whether its robots can balance at all, and an upper bound on `det(S)` over it.
//!
//! The bound: for any `W` with `det W = 1` and `S` positive semidefinite,
//! `det(S) <= (tr(W S) / 2)^2` (the arithmetic-geometric mean of the eigenvalues of `W S`).
//! With `v = sum s_i r_i`, `-(v^T W v) / n <= n mu^T W^-1 mu - 2 mu^T v` for any `mu`, and
//! on balanced formations `eta^T sum r_i = 0`, so
//! `tr(W S) <= sum_i (r_i^T W r_i - 2 s_i mu^T r_i + eta^T r_i) + n mu^T W^-1 mu`,
//! a sum of one convex quadratic per robot: each is largest at an end of the range the robot
//! can reach on its segment. `W`, `mu` are taken from the best formation so far (where the
//! bound is tight), `eta` from a few trials.

use crate::formation::assignment::Layout;
use crate::geometry::Vec2;
use crate::math;

/// The shape a bound is taken in: `W` (determinant 1) and `mu`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundShape {
    /// `W = [[w00, w01], [w01, w11]]`.
    pub w: [f32; 3],
    /// `mu`.
    pub mu: Vec2,
}

impl BoundShape {
    /// `W = I`, `mu = 0`.
    pub const ROUND: Self = Self {
        w: [1.0, 0.0, 1.0],
        mu: Vec2::new(0.0, 0.0),
    };

    /// The shape that makes the bound tight at a formation with Schur matrix
    /// `[[s00, s01], [s01, s11]]` and spin sum `v`: `W = S^-1 sqrt(det S)`, `mu = W v / n`.
    pub fn at(s: [f32; 3], v: Vec2, n: usize) -> Self {
        let det = s[0] * s[2] - s[1] * s[1];
        if det.is_nan() || det <= 0.0 {
            return Self::ROUND;
        }
        let root = math::sqrt(det);
        let w = [s[2] / root, -s[1] / root, s[0] / root];
        let mu = Vec2::new(w[0] * v.x + w[1] * v.y, w[1] * v.x + w[2] * v.y) * (1.0 / n as f32);
        Self { w, mu }
    }

    fn form(&self, p: Vec2) -> f32 {
        p.x * (self.w[0] * p.x + self.w[1] * p.y) + p.y * (self.w[1] * p.x + self.w[2] * p.y)
    }

    fn inverse_form(&self, p: Vec2) -> f32 {
        // W^-1 = adj(W) for det W = 1.
        p.x * (self.w[2] * p.x - self.w[1] * p.y) + p.y * (-self.w[1] * p.x + self.w[0] * p.y)
    }
}

/// True when the box of the points the robots can reach holds a balanced formation (sums
/// within `tolerance` of zero) — necessary, not sufficient.
pub fn may_balance(layout: &Layout, tolerance: f32) -> bool {
    let (mut lo, mut hi) = (Vec2::default(), Vec2::default());
    for i in 0..layout.n {
        let (a, b) = layout.reach[i];
        let (p, q) = (layout.point(i, a), layout.point(i, b));
        lo = lo + Vec2::new(p.x.min(q.x), p.y.min(q.y));
        hi = hi + Vec2::new(p.x.max(q.x), p.y.max(q.y));
    }
    lo.x <= tolerance && lo.y <= tolerance && hi.x >= -tolerance && hi.y >= -tolerance
}

/// Upper bound on `det(S)` over the balanced formations of `layout`.
pub fn det_bound(layout: &Layout, shape: &BoundShape) -> f32 {
    let n = layout.n;
    let constant = n as f32 * shape.inverse_form(shape.mu);
    let sum_at = |eta: Vec2| {
        let mut total = constant;
        for i in 0..n {
            let (a, b) = layout.reach[i];
            let linear = eta - shape.mu * (2.0 * layout.spin[i]);
            let f = |p: Vec2| shape.form(p) + linear.dot(p);
            total += f(layout.point(i, a)).max(f(layout.point(i, b)));
        }
        total
    };
    // eta: zero, then a few steps against the direction the unbalanced extremes lean.
    let mut best = sum_at(Vec2::default());
    let mut eta = Vec2::default();
    let mut step = 0.5;
    for _ in 0..6 {
        let mut lean = Vec2::default();
        for i in 0..n {
            let (a, b) = layout.reach[i];
            let linear = eta - shape.mu * (2.0 * layout.spin[i]);
            let (p, q) = (layout.point(i, a), layout.point(i, b));
            let f = |p: Vec2| shape.form(p) + linear.dot(p);
            lean = lean + if f(p) >= f(q) { p } else { q };
        }
        let norm = lean.norm();
        if norm < 1e-9 {
            break;
        }
        let trial = eta - lean * (step / norm);
        let value = sum_at(trial);
        if value < best {
            best = value;
            eta = trial;
        } else {
            step *= 0.3;
        }
    }
    let half = 0.5 * best.max(0.0);
    half * half
}
