//! Bringing a formation onto the balance constraints `|sum b1| <= eps`, `|sum b2| <= eps`
//! (docs/models.md#formation-search): the robots' centroid onto the estimated COM.
//!
//! Damped least-norm Newton steps along the rail, with the spacing constraints as an active
//! set: with `t_j` the rail direction at robot `j` and `h = sum (p_j - c)`, the smallest move
//! `ds` with `sum t_j ds_j = -h` is `ds_j = -t_j . (sum t t^T)^-1 h`. Neighbours whose gap that
//! step would close below `min_spacing` are merged into a block that moves as one (block `B`
//! moves `ds_B = -T_B . lambda / |B|` with `T_B = sum_{j in B} t_j`), until no gap closes too
//! far; the 2 x 2 system is damped (Levenberg-Marquardt) so that a formation whose blocks can
//! only move the centroid one way still steps that way. Each step is capped at a trust radius (the rail is linear only between vertices) and
//! halved while it does not reduce `|h|`.

use crate::formation::search::{SPACING_MARGIN, order_and_spacing_hold, sides};
use crate::geometry::{Rail, Vec2};
use crate::scenario::MAX_ROBOTS;

/// Newton iterations before giving up.
const MAX_ITERATIONS: usize = 60;
/// Step halvings before giving up on an iteration.
const MAX_HALVINGS: usize = 24;
/// Largest move of one robot in one step, m: the rail is linear only between vertices.
const TRUST_RADIUS: f32 = 0.15;

/// Moves `positions` (arc lengths, rail order) until both balance sums about `com` are within
/// `tolerance`, keeping order and `min_spacing`. Returns whether it got there.
pub fn project_to_balance(
    rail: &Rail,
    com: Vec2,
    min_spacing: f32,
    tolerance: f32,
    positions: &mut [f32],
) -> bool {
    let n = positions.len().min(MAX_ROBOTS);
    let positions = &mut positions[..n];
    for _ in 0..MAX_ITERATIONS {
        let h = positions
            .iter()
            .fold(Vec2::default(), |acc, &s| acc + (rail.point_at(s) - com));
        if h.x.abs() <= tolerance && h.y.abs() <= tolerance {
            return true;
        }
        let mut tangents = [Vec2::default(); MAX_ROBOTS];
        for (t, &s) in tangents.iter_mut().zip(positions.iter()) {
            *t = sides(rail, s).0.tangent;
        }
        let Some(step) = block_step(rail, positions, &tangents[..n], h, min_spacing) else {
            return false;
        };
        let size = |p: &[f32]| {
            p.iter()
                .fold(Vec2::default(), |acc, &s| acc + (rail.point_at(s) - com))
                .norm()
        };
        let before = h.norm();
        let mut trial = [0.0f32; MAX_ROBOTS];
        let mut factor = 1.0;
        let mut accepted = false;
        for _ in 0..MAX_HALVINGS {
            for j in 0..n {
                trial[j] = rail.wrap(positions[j] + factor * step[j]);
            }
            if order_and_spacing_hold(rail, &trial[..n], min_spacing + 0.5 * SPACING_MARGIN)
                && size(&trial[..n]) < before
            {
                accepted = true;
                break;
            }
            factor *= 0.5;
        }
        if !accepted {
            return false;
        }
        positions.copy_from_slice(&trial[..n]);
    }
    false
}

/// The least-norm step that cancels `h`, with neighbours that would come closer than
/// `min_spacing` moving together. `None` when no block structure can move the centroid.
fn block_step(
    rail: &Rail,
    positions: &[f32],
    tangents: &[Vec2],
    h: Vec2,
    min_spacing: f32,
) -> Option<[f32; MAX_ROBOTS]> {
    let n = positions.len();
    // block[j]: the block robot j belongs to (the index of its first robot).
    let mut block = [0usize; MAX_ROBOTS];
    for (j, b) in block.iter_mut().enumerate().take(n) {
        *b = j;
    }
    let mut step = [0.0f32; MAX_ROBOTS];
    for _ in 0..=n {
        let mut direction = [Vec2::default(); MAX_ROBOTS];
        let mut members = [0.0f32; MAX_ROBOTS];
        for j in 0..n {
            direction[block[j]] = direction[block[j]] + tangents[j];
            members[block[j]] += 1.0;
        }
        let (mut a00, mut a01, mut a11) = (0.0f32, 0.0f32, 0.0f32);
        for b in 0..n {
            if members[b] > 0.0 {
                let t = direction[b];
                a00 += t.x * t.x / members[b];
                a01 += t.x * t.y / members[b];
                a11 += t.y * t.y / members[b];
            }
        }
        // Damped least squares: where the blocks cannot move the centroid in some direction
        // (a rank-deficient system), step as far as they can towards it.
        let damping = 1e-4 * (a00 + a11);
        let (a00, a11) = (a00 + damping, a11 + damping);
        let det = a00 * a11 - a01 * a01;
        if det.is_nan() || det <= 0.0 {
            return None;
        }
        let lambda = Vec2::new((a11 * h.x - a01 * h.y) / det, (a00 * h.y - a01 * h.x) / det);
        for j in 0..n {
            let b = block[j];
            step[j] = -direction[b].dot(lambda) / members[b];
        }
        let longest = step[..n].iter().fold(0.0f32, |a, v| a.max(v.abs()));
        if longest > TRUST_RADIUS {
            let cap = TRUST_RADIUS / longest;
            step[..n].iter_mut().for_each(|v| *v *= cap);
        }
        // Merge the first pair of neighbours whose gap the step would close too far.
        let closing = (0..n).find(|&j| {
            let next = (j + 1) % n;
            let gap = rail.forward_gap(positions[j], positions[next]);
            block[j] != block[next]
                && step[j] > step[next]
                && gap + step[next] - step[j] < min_spacing + SPACING_MARGIN
        });
        let Some(j) = closing else {
            return Some(step);
        };
        let (keep, gone) = (block[j], block[(j + 1) % n]);
        for b in block.iter_mut().take(n) {
            if *b == gone {
                *b = keep;
            }
        }
    }
    None
}
