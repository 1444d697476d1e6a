//! The damped Newton ascent step of the formation search on one face of its polytope
//! (docs/models.md#formation-search): Levenberg damping until the reduced Hessian is negative
//! definite, for [`Goal::Det`] projected onto the directions that keep both balance sums, and
//! the small Cholesky solve it rests on. Fixed-size arrays, no allocation.

use crate::formation::face::Goal;
use crate::geometry::Vec2;
use crate::math;
use crate::scenario::MAX_ROBOTS;

const N: usize = MAX_ROBOTS;

/// The damped Newton ascent step on the free blocks; for [`Goal::Det`] projected onto
/// `T u = 0`.
pub(super) fn newton_step(
    goal: Goal,
    k: usize,
    grad: &[f32; N],
    hess: &[[f32; N]; N],
    t_b: &[Vec2; N],
) -> [f32; N] {
    let mut step = [0.0f32; N];
    if k == 0 {
        return step;
    }
    // Orthonormal basis of the rows of T (the directions the balance forbids).
    let mut basis = [[0.0f32; N]; 2];
    let mut rank = 0;
    if goal == Goal::Det {
        for row in 0..2 {
            let mut q = [0.0f32; N];
            for f in 0..k {
                q[f] = if row == 0 { t_b[f].x } else { t_b[f].y };
            }
            for prev in basis.iter().take(rank) {
                let d: f32 = (0..k).map(|f| q[f] * prev[f]).sum();
                for (qf, &pf) in q.iter_mut().zip(prev).take(k) {
                    *qf -= d * pf;
                }
            }
            let norm = math::sqrt((0..k).map(|f| q[f] * q[f]).sum());
            if norm > 1e-4 {
                for qf in q.iter_mut().take(k) {
                    *qf /= norm;
                }
                basis[rank] = q;
                rank += 1;
            }
        }
    }
    if rank >= k {
        return step;
    }
    // P = I - sum q q^T
    let mut proj = [[0.0f32; N]; N];
    for a in 0..k {
        for b in 0..k {
            let mut p = if a == b { 1.0 } else { 0.0 };
            for q in basis.iter().take(rank) {
                p -= q[a] * q[b];
            }
            proj[a][b] = p;
        }
    }
    let mut pg = [0.0f32; N];
    for a in 0..k {
        pg[a] = (0..k).map(|b| proj[a][b] * grad[b]).sum();
    }
    // P (-H) P
    let mut neg = [[0.0f32; N]; N];
    let mut tmp = [[0.0f32; N]; N];
    for a in 0..k {
        for b in 0..k {
            tmp[a][b] = -(0..k).map(|c| hess[a][c] * proj[c][b]).sum::<f32>();
        }
    }
    let mut size = 0.0f32;
    for a in 0..k {
        for b in 0..k {
            neg[a][b] = (0..k).map(|c| proj[a][c] * tmp[c][b]).sum();
            size = size.max(neg[a][b].abs());
        }
    }
    let size = size.max(1e-12);
    let mut damping = match goal {
        Goal::Det => 0.0,
        Goal::Balance => 1e-6 * size,
    };
    for _ in 0..24 {
        let mut m = [[0.0f32; N]; N];
        for a in 0..k {
            for b in 0..k {
                let outside = if a == b { 1.0 } else { 0.0 } - proj[a][b];
                m[a][b] = neg[a][b] + damping * proj[a][b] + size * outside;
            }
        }
        if let Some(x) = cholesky_solve(k, &mut m, &pg) {
            // Keep it in the allowed subspace exactly.
            for a in 0..k {
                step[a] = (0..k).map(|b| proj[a][b] * x[b]).sum();
            }
            return step;
        }
        damping = if damping == 0.0 {
            1e-4 * size
        } else {
            damping * 8.0
        };
    }
    // Gradient ascent as the last resort.
    step[..k].copy_from_slice(&pg[..k]);
    step
}

/// Solves `m x = b` for a symmetric positive definite `m` (overwritten); `None` if it is not.
fn cholesky_solve(k: usize, m: &mut [[f32; N]; N], b: &[f32; N]) -> Option<[f32; N]> {
    for j in 0..k {
        let d = m[j][j] - m[j][..j].iter().map(|v| v * v).sum::<f32>();
        if d.is_nan() || d <= 1e-12 * (1.0 + m[j][j].abs()) {
            return None;
        }
        let d = math::sqrt(d);
        m[j][j] = d;
        for i in (j + 1)..k {
            let s = m[i][j] - (0..j).map(|p| m[i][p] * m[j][p]).sum::<f32>();
            m[i][j] = s / d;
        }
    }
    let mut y = [0.0f32; N];
    for i in 0..k {
        let s = b[i] - (0..i).map(|p| m[i][p] * y[p]).sum::<f32>();
        y[i] = s / m[i][i];
    }
    let mut x = [0.0f32; N];
    for i in (0..k).rev() {
        let mut s = y[i];
        for p in (i + 1)..k {
            s -= m[p][i] * x[p];
        }
        x[i] = s / m[i][i];
    }
    Some(x)
}
