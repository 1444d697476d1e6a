//! The formation's objective and constraints
//! (docs/models.md#formation-objective-and-balance-constraints; Oishi & Jimbo (2025), eq. (4)).
//!
//! With rotor `j` at `r^j` from the COM, thrust as the input (`c_t = 1`), torque coefficient
//! `c_q` and spin `s_j`, `B = [r1^1 .. r1^n ; r2^1 .. r2^n ; s_1 c_q .. s_n c_q]` and
//!
//! ```text
//! B B^T = [ Sxx      Sxy      c_q vx ]     Sxx = sum r1^2, Sxy = sum r1 r2, Syy = sum r2^2
//!         [ Sxy      Syy      c_q vy ]     vx  = sum s_j r1^j, vy = sum s_j r2^j
//!         [ c_q vx   c_q vy   n c_q^2]
//! ```
//!
//! Its Schur complement on the constant corner gives `det(B B^T) = n c_q^2 det(S)` with
//! `S = [[Sxx - vx^2/n, Sxy - vx vy/n], [Sxy - vx vy/n, Syy - vy^2/n]]`: the solver maximises
//! `det(S)`, which is the same optimum for any `c_q > 0` and keeps a useful objective when
//! `c_q = 0`. The balance constraints are `|sum r1| <= eps`, `|sum r2| <= eps`.

use crate::geometry::{Rail, Vec2};

/// Sums of the rotor positions relative to the COM that `B B^T` is made of.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Moments {
    /// Number of robots.
    pub n: f32,
    /// `sum r^j`: the balance sums `[sum b1, sum b2]`.
    pub sum: Vec2,
    /// `sum r1^2`.
    pub sxx: f32,
    /// `sum r1 r2`.
    pub sxy: f32,
    /// `sum r2^2`.
    pub syy: f32,
    /// `sum s_j r1^j`.
    pub vx: f32,
    /// `sum s_j r2^j`.
    pub vy: f32,
}

impl Moments {
    /// Moments of rotor points `points` (body frame) about `com`, with spins `spin`.
    pub fn of(points: &[Vec2], com: Vec2, spin: &[i8]) -> Self {
        let mut m = Self {
            n: points.len() as f32,
            ..Self::default()
        };
        for (&p, &s) in points.iter().zip(spin) {
            let r = p - com;
            let s = f32::from(s);
            m.sum = m.sum + r;
            m.sxx += r.x * r.x;
            m.sxy += r.x * r.y;
            m.syy += r.y * r.y;
            m.vx += s * r.x;
            m.vy += s * r.y;
        }
        m
    }

    /// `det(S)`, the Schur complement's determinant (m^4).
    pub fn schur_det(&self) -> f32 {
        let s00 = self.sxx - self.vx * self.vx / self.n;
        let s11 = self.syy - self.vy * self.vy / self.n;
        let s01 = self.sxy - self.vx * self.vy / self.n;
        s00 * s11 - s01 * s01
    }

    /// `det(B B^T)` for torque coefficient `cq` (`c_q / c_t`, metres), as a plain 3 x 3
    /// determinant.
    pub fn gramian_det(&self, cq: f32) -> f32 {
        let m = [
            [self.sxx, self.sxy, cq * self.vx],
            [self.sxy, self.syy, cq * self.vy],
            [cq * self.vx, cq * self.vy, self.n * cq * cq],
        ];
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }

    /// The balance sums `[sum b1, sum b2]` (m).
    pub fn balance(&self) -> [f32; 2] {
        [self.sum.x, self.sum.y]
    }
}

/// A formation's figures: what flight tests compare between formations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FormationFigures {
    /// `det(B B^T)`.
    pub det: f32,
    /// `[sum b1, sum b2]`, m.
    pub balance: [f32; 2],
    /// Smallest arc length between neighbours, m.
    pub min_gap: f32,
}

/// Smallest forward gap between consecutive robots (in rail order), m; the whole perimeter for
/// a single robot.
pub fn min_gap(rail: &Rail, positions: &[f32]) -> f32 {
    let n = positions.len();
    if n < 2 {
        return rail.perimeter();
    }
    (0..n)
        .map(|j| rail.forward_gap(positions[j], positions[(j + 1) % n]))
        .fold(f32::INFINITY, f32::min)
}

/// The figures of robots at arc lengths `positions` on `rail`.
pub fn figures(
    rail: &Rail,
    positions: &[f32],
    spin: &[i8],
    com: Vec2,
    cq: f32,
) -> FormationFigures {
    let mut points = [Vec2::default(); crate::scenario::MAX_ROBOTS];
    let n = positions.len().min(points.len());
    for (p, &s) in points.iter_mut().zip(positions) {
        *p = rail.point_at(s);
    }
    let m = Moments::of(&points[..n], com, spin);
    FormationFigures {
        det: m.gramian_det(cq),
        balance: m.balance(),
        min_gap: min_gap(rail, positions),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schur_form_equals_the_plain_determinant() {
        let points = [
            Vec2::new(-0.9, -0.22),
            Vec2::new(0.2, -0.22),
            Vec2::new(1.0, 0.1),
            Vec2::new(0.4, 0.22),
            Vec2::new(-1.0, 0.05),
        ];
        let spin = [1, -1, 1, -1, 1];
        let m = Moments::of(&points, Vec2::new(0.1, 0.01), &spin);
        let cq = 0.016;
        let plain = m.gramian_det(cq);
        let schur = m.n * cq * cq * m.schur_det();
        assert!(
            (plain - schur).abs() <= 1e-4 * plain.abs(),
            "{plain} vs {schur}"
        );
        assert!(plain > 0.0);
    }
}
