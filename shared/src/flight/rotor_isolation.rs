//! Which stopped rotors explain a change of the vehicle's wrench: one rotor, or two at once
//! (docs/failures.md#rotors-that-stop-in-flight).
//!
//! What it implements: isolation by the residual's direction (J. Gertler, "Fault Detection
//! and Diagnosis in Engineering Systems", 1998, directional residuals), extended to two
//! simultaneous faults by least squares on pairs of fault directions.
//!
//! A rotor `j` that stops takes `T_j a_j` away, `T_j` its expected thrust and `a_j` its column
//! (thrust, roll, pitch; the torques divided by the rotors' RMS arm so all rows are in
//! newtons). A change `d` is
//! - one rotor's loss when `-d ≈ x a_j`, `x` (least squares) within
//!   [`RotorMonitorConfig::min_fraction`]..[`RotorMonitorConfig::max_fraction`] of `T_j`;
//! - two rotors' when `-d ≈ mu (T_j a_j + T_k a_k)`, `mu` within those bounds: both stopped
//!   at once lose their own thrusts, and the change rises along that one direction. Fitting
//!   the two sizes freely would explain almost any change by two rotors on one side of the
//!   payload: three rows (thrust, roll, pitch) cannot tell those pairs apart, their thrusts
//!   can.
//!
//! Either explanation must account for [`RotorMonitorConfig::min_explained`] of the change
//! (squared norm). Two rotors are the answer only when one rotor cannot be, or when the pair
//! leaves less than [`PAIR_MARGIN`] of what the best single rotor leaves unexplained.
//!
//! What it cannot tell apart: pairs whose thrusts make the same wrench (on a symmetric layout,
//! two opposite corners and the other two). Naming the wrong one leaves the true pair's loss
//! unexplained, and it is found next: four rotors out, the vehicle still flying if the rest
//! can hold it.

use crate::flight::rotor_monitor::RotorMonitorConfig;
use crate::math;
use crate::scenario::MAX_ROBOTS;

/// A pair is preferred to the best single rotor when it leaves less than this share of what
/// the single rotor leaves unexplained.
pub const PAIR_MARGIN: f32 = 0.25;

/// A decisive single rotor leaves less than this share of what the next best leaves
/// unexplained.
pub const DECISIVE_MARGIN: f32 = 0.5;

/// The rotors a change is judged against: a view of the mixer's columns and the rotors'
/// expected thrusts (borrowed, not built: the columns are read in place).
#[derive(Clone, Copy, Debug)]
pub struct Columns<'a> {
    /// Each rotor's column of the effectiveness matrix, four numbers per rotor (thrust N and
    /// roll, pitch, yaw torque N m per N of the rotor's thrust).
    raw: &'a [f32],
    /// The torques' scale, 1/m: torques times it are newtons.
    scale: f32,
    /// Each rotor's expected thrust, N.
    thrust: &'a [f32; MAX_ROBOTS],
    /// Rotors the caller lets be named (not known out), bit `i` for rotor `i`; of those, the
    /// judgement takes the flown ones (a column) with at least `min_thrust`.
    eligible: u16,
    /// The least expected thrust of a rotor judged, N.
    min_thrust: f32,
    count: usize,
}

impl<'a> Columns<'a> {
    /// The columns of `count` rotors from `raw` (four numbers per rotor: thrust, roll, pitch
    /// and yaw per newton, as the mixer stores them), torques times `scale`; a rotor is
    /// eligible when its bit of `eligible` is set, its column is not zero and its expected
    /// thrust `thrust[j]` is at least `min_thrust`.
    pub fn new(
        count: usize,
        raw: &'a [f32],
        scale: f32,
        thrust: &'a [f32; MAX_ROBOTS],
        eligible: u16,
        min_thrust: f32,
    ) -> Self {
        Self {
            raw,
            scale,
            thrust,
            eligible,
            min_thrust,
            count: count.min(MAX_ROBOTS).min(raw.len() / 4),
        }
    }

    /// Rotor `j`'s column (thrust, roll and pitch times the scale).
    pub fn column(&self, j: usize) -> [f32; 3] {
        if j >= self.count {
            return [0.0; 3];
        }
        match self.raw.get(4 * j..4 * j + 3) {
            Some(&[t, r, p]) => [t, r * self.scale, p * self.scale],
            _ => [0.0; 3],
        }
    }

    /// Rotor `j`'s expected thrust, N.
    pub fn thrust(&self, j: usize) -> f32 {
        self.thrust.get(j).copied().unwrap_or(0.0)
    }
}

/// How a change is judged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Judging {
    /// Only rotors whose loss has the change's size are candidates (is it a rotor at all?);
    /// without, a single rotor is named by direction alone (which rotor?: the change may
    /// still be rising). Each rotor of a pair must always have lost a rotor's share.
    pub sized: bool,
    /// The thrust row alone must show the loss too (at least
    /// [`RotorMonitorConfig::min_fraction`] of the thrust lost): just after a rotor was
    /// found, when the recovery's large torques make residuals of a rotor's size through the
    /// inertia's error, but not in the collective.
    pub thrust_shown: bool,
    /// Pairs are candidates too (a slow drift is judged against single rotors only).
    pub pairs: bool,
    /// The best single rotor must leave less than [`DECISIVE_MARGIN`] of what the next best
    /// leaves unexplained (a slow drift carries the disturbance's wander, and neighbours'
    /// columns are close: the answer waits until the drift has grown to tell them apart).
    pub decisive: bool,
}

/// How many pairs a swept search ([`explain_swept`]) judges anew in one tick.
pub const PAIRS_PER_TICK: usize = 10;

/// A search of the pairs of rotors spread over ticks ([`explain_swept`]): each tick judges
/// [`PAIRS_PER_TICK`] pairs more, and the best pair of the sweep under way and of the last
/// whole sweep again (against that tick's change). A whole sweep takes 3 ticks at eight
/// rotors and 12 at sixteen (120 pairs), well within the time a finding is confirmed; a tick
/// costs a bounded number of pairs however many rotors fly.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PairSweep {
    /// The next pair to judge, rotors (j, k) with j < k.
    next: (u8, u8),
    /// The best pair of the sweep under way.
    current: Option<(u8, u8)>,
    /// The best pair of the last whole sweep.
    last: Option<(u8, u8)>,
}

impl PairSweep {
    /// A sweep that starts afresh, no pair judged yet.
    pub const fn new() -> Self {
        Self {
            next: (0, 1),
            current: None,
            last: None,
        }
    }
}

/// The stopped rotors that explain a change `d` (thrust N, roll and pitch torque times the
/// columns' scale), bit `i` for rotor `i`, if one or two do: every pair judged.
pub fn explain(d: &[f32; 3], columns: &Columns, config: &RotorMonitorConfig, how: Judging) -> u16 {
    judge(d, columns, config, how, None)
}

/// As [`explain`], the pairs judged a few a tick (`sweep` carries the search from tick to
/// tick): the control tick's budget at sixteen rotors. Single rotors are all judged each tick.
pub fn explain_swept(
    d: &[f32; 3],
    columns: &Columns,
    config: &RotorMonitorConfig,
    how: Judging,
    sweep: &mut PairSweep,
) -> u16 {
    judge(d, columns, config, how, Some(sweep))
}

fn judge(
    d: &[f32; 3],
    columns: &Columns,
    config: &RotorMonitorConfig,
    how: Judging,
    sweep: Option<&mut PairSweep>,
) -> u16 {
    let dd = dot(d, d);
    // Zero, or NaN from a non-finite input: nothing to explain.
    if dd.is_nan() || dd <= 0.0 {
        return 0;
    }
    // The control tick's budget: no division in the loops (ratios are compared crosswise)
    // and each column read once. Per eligible rotor `j`: its column a_j, |a_j|^2, and
    // b_j = -d . a_j, the loss's projection on it.
    let (min, max) = (config.min_fraction, config.max_fraction);
    let lost_collective = -d[0];
    let mut candidates = 0u16;
    // Per rotor: its loss's direction T_j a_j, the change's projection T_j b_j, and T_j.
    let mut lost = [[0.0f32; 5]; MAX_ROBOTS];
    let mut lightest = f32::INFINITY;
    // The best single rotor: its b_j^2 and |a_j|^2 (explained = b^2 / (|a|^2 dd)); and the
    // next best's.
    let mut single: Option<(usize, f32, f32)> = None;
    let mut runner_up: Option<(f32, f32)> = None;
    for j in (0..columns.count).filter(|&j| columns.eligible & (1 << j) != 0) {
        let a = columns.column(j);
        let t = columns.thrust[j];
        let aa = dot(&a, &a);
        // A rotor not flown (zero column), barely turning, or not a number is no candidate.
        if !(a[0] != 0.0 && aa > 0.0 && t >= columns.min_thrust) {
            continue;
        }
        let b = -dot(d, &a);
        candidates |= 1 << j;
        lost[j] = [t * a[0], t * a[1], t * a[2], t * b, t];
        lightest = math::min(lightest, t);
        // Its loss b / |a|^2 within the bounds (sized: at least `min_fraction` of `t`), and
        // the collective showing `min_fraction` of it when that is asked.
        let small = if how.sized { min * t * aa } else { 0.0 };
        let fits = b > small && b <= max * t * aa;
        let shown = !how.thrust_shown || lost_collective * aa >= min * b;
        if !(fits && shown) {
            continue;
        }
        if single.is_none_or(|(_, bb, aa0)| b * b * aa0 > bb * aa) {
            runner_up = single.map(|(_, bb, aa0)| (bb, aa0));
            single = Some((j, b * b, aa));
        } else if runner_up.is_none_or(|(bb, aa0)| b * b * aa0 > bb * aa) {
            runner_up = Some((b * b, aa));
        }
    }
    // Two rotors stopped together lose `mu (T_j a_j + T_k a_k)` as the change rises: one
    // direction per pair, judged as a single rotor's (two free sizes would fit almost any
    // change with two rotors on the same side). Pair (j, k)'s -d . v squared and |v|^2, if
    // it is a candidate: `mu` within the bounds, and its loss, mu (T_j + T_k), shown in the
    // collective.
    let pair_fit = |j: usize, k: usize| -> Option<(f32, f32)> {
        if (candidates >> j) & (candidates >> k) & 1 == 0 {
            return None;
        }
        let (p, q) = (lost.get(j)?, lost.get(k)?);
        let v = [p[0] + q[0], p[1] + q[1], p[2] + q[2]];
        let vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        let along = p[3] + q[3];
        if vv <= 0.0 || along <= min * vv || along > max * vv {
            return None;
        }
        if lost_collective * vv < min * along * (p[4] + q[4]) {
            return None;
        }
        Some((along * along, vv))
    };
    // The better of two fits, compared crosswise (along^2 / vv).
    let better = |fit: (f32, f32), than: Option<(usize, usize, f32, f32)>| {
        than.is_none_or(|(_, _, best, vv0)| fit.0 * vv0 > best * fit.1)
    };
    // The collective must show at least `min_fraction` of half the least two rotors' thrust:
    // most ticks of a flight spare the pairs' search here.
    let mut pair: Option<(usize, usize, f32, f32)> = None;
    if how.pairs && lost_collective >= min * min * 2.0 * lightest {
        let n = columns.count;
        match sweep {
            None => {
                for j in 0..n {
                    for k in j + 1..n {
                        if let Some(fit) = pair_fit(j, k)
                            && better(fit, pair)
                        {
                            pair = Some((j, k, fit.0, fit.1));
                        }
                    }
                }
            }
            Some(sweep) => {
                let consider = |pair: &mut Option<(usize, usize, f32, f32)>, j, k| {
                    if let Some(fit) = pair_fit(j, k)
                        && better(fit, *pair)
                    {
                        *pair = Some((j, k, fit.0, fit.1));
                    }
                };
                // The sweep's best so far, again against this change; then new pairs.
                let mut current = None;
                if let Some((j, k)) = sweep.current {
                    consider(&mut current, usize::from(j), usize::from(k));
                }
                let (mut j, mut k) = (usize::from(sweep.next.0), usize::from(sweep.next.1));
                let mut judged = 0;
                while judged < PAIRS_PER_TICK {
                    if k >= n {
                        j += 1;
                        k = j + 1;
                    }
                    if k >= n {
                        // A whole sweep: its best is the last sweep's from now on.
                        sweep.last = current.map(|(j, k, _, _)| (j as u8, k as u8));
                        current = None;
                        (j, k) = (0, 1);
                        break;
                    }
                    consider(&mut current, j, k);
                    judged += 1;
                    k += 1;
                }
                sweep.next = (j as u8, k as u8);
                sweep.current = current.map(|(j, k, _, _)| (j as u8, k as u8));
                pair = current;
                if let Some((j, k)) = sweep.last {
                    consider(&mut pair, usize::from(j), usize::from(k));
                }
            }
        }
    }
    let enough = |num: f32, den: f32| num >= config.min_explained * den * dd;
    // Unexplained shares crosswise: dd - bb/aa < margin (dd - bb2/aa2), times aa aa2.
    let decisive = |bb: f32, aa: f32| {
        runner_up
            .is_none_or(|(bb2, aa2)| (dd * aa - bb) * aa2 < DECISIVE_MARGIN * (dd * aa2 - bb2) * aa)
    };
    let single = single
        .filter(|&(_, bb, aa)| enough(bb, aa) && (!how.decisive || decisive(bb, aa)))
        .map(|(j, bb, aa)| (j, bb / (aa * dd)));
    let pair = pair
        .filter(|&(_, _, along2, vv)| enough(along2, vv))
        .map(|(j, k, along2, vv)| (j, k, along2 / (vv * dd)));
    match (single, pair) {
        (Some((_, e1)), Some((j, k, e2))) if 1.0 - e2 < PAIR_MARGIN * (1.0 - e1) => {
            (1 << j) | (1 << k)
        }
        (Some((j, _)), _) => 1 << j,
        (None, Some((j, k, _))) => (1 << j) | (1 << k),
        (None, None) => 0,
    }
}

/// The dot product of two changes or columns (thrust, roll, pitch; torques already scaled).
pub(crate) fn dot(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eight rotors on a 2 m x 0.44 m rectangle's rail, unevenly spaced, the COM off the
    /// middle (evenly spaced about the COM, opposite corners' pairs would make the same
    /// change: no wrench tells them apart).
    fn rect() -> [f32; 32] {
        let points: [[f32; 2]; 8] = [
            [-0.95, -0.22],
            [-0.8, 0.22],
            [-0.35, -0.22],
            [-0.2, 0.22],
            [0.25, -0.22],
            [0.45, 0.22],
            [0.7, -0.22],
            [0.95, 0.22],
        ];
        raw(|j| [1.0, -points[j][1], points[j][0]])
    }

    /// The columns of [`rect`] with each rotor expected at `thrust`.
    fn columns<'a>(raw: &'a [f32; 32], thrust: &'a [f32; MAX_ROBOTS]) -> Columns<'a> {
        Columns::new(8, raw, 1.0 / 0.6, thrust, 0xff, 1.0)
    }

    /// Eight rotors' columns as the mixer stores them (four numbers each, no yaw).
    fn raw(column: impl Fn(usize) -> [f32; 3]) -> [f32; 32] {
        let mut raw = [0.0f32; 32];
        for j in 0..8 {
            raw[4 * j..4 * j + 3].copy_from_slice(&column(j));
        }
        raw
    }

    const FIVE: [f32; MAX_ROBOTS] = [5.0; MAX_ROBOTS];

    const SIZED: Judging = Judging {
        sized: true,
        thrust_shown: false,
        pairs: true,
        decisive: false,
    };

    fn loss(columns: &Columns, lost: &[(usize, f32)]) -> [f32; 3] {
        let mut d = [0.0; 3];
        for &(j, x) in lost {
            let a = columns.column(j);
            for r in 0..3 {
                d[r] -= x * a[r];
            }
        }
        d
    }

    #[test]
    fn one_rotor_is_named_alone() {
        let r = rect();
        let c = columns(&r, &FIVE);
        for j in 0..8 {
            let d = loss(&c, &[(j, 5.0)]);
            assert_eq!(explain(&d, &c, &RotorMonitorConfig::DEFAULT, SIZED), 1 << j);
        }
    }

    #[test]
    fn every_pair_is_named_as_a_pair_or_one_making_the_same_wrench() {
        let r = rect();
        let c = columns(&r, &FIVE);
        let mut exact = 0;
        for j in 0..8 {
            for k in j + 1..8 {
                let d = loss(&c, &[(j, 5.0), (k, 5.0)]);
                let named = explain(&d, &c, &RotorMonitorConfig::DEFAULT, SIZED);
                assert_eq!(named.count_ones(), 2, "rotors {j} and {k}: {named:#b}");
                if named == (1 << j) | (1 << k) {
                    exact += 1;
                    continue;
                }
                // Another pair: it must make the same change (no wrench tells them apart).
                let (p, q) = (
                    named.trailing_zeros() as usize,
                    15 - named.leading_zeros() as usize,
                );
                let other = loss(&c, &[(p, 5.0), (q, 5.0)]);
                for r in 0..3 {
                    assert!(
                        (other[r] - d[r]).abs() < 1e-3,
                        "rotors {j} and {k} named {p} and {q}: {other:?} against {d:?}"
                    );
                }
            }
        }
        // Of the 28 pairs, those the layout makes alike are few.
        assert!(exact >= 24, "{exact} of 28 named exactly");
    }

    #[test]
    fn a_swept_search_names_what_the_whole_search_does_within_a_sweep() {
        let r = rect();
        let c = columns(&r, &FIVE);
        let config = RotorMonitorConfig::DEFAULT;
        // 28 pairs, PAIRS_PER_TICK a tick: a whole sweep and the tick that judges its best.
        let ticks = 28usize.div_ceil(PAIRS_PER_TICK) + 1;
        for j in 0..8 {
            for k in j + 1..8 {
                let d = loss(&c, &[(j, 5.0), (k, 5.0)]);
                let whole = explain(&d, &c, &config, SIZED);
                let mut sweep = PairSweep::new();
                let mut named = 0;
                for _ in 0..ticks {
                    named = explain_swept(&d, &c, &config, SIZED, &mut sweep);
                }
                assert_eq!(named, whole, "rotors {j} and {k}");
                // And it stays so as the sweep goes on.
                for _ in 0..ticks {
                    assert_eq!(explain_swept(&d, &c, &config, SIZED, &mut sweep), whole);
                }
            }
            // One rotor: named from the first tick.
            let d = loss(&c, &[(j, 5.0)]);
            let mut sweep = PairSweep::new();
            assert_eq!(explain_swept(&d, &c, &config, SIZED, &mut sweep), 1 << j);
        }
    }

    #[test]
    fn a_torque_without_thrust_or_a_small_change_is_no_rotor() {
        let r = rect();
        let c = columns(&r, &FIVE);
        let config = RotorMonitorConfig::DEFAULT;
        assert_eq!(explain(&[0.0, 3.0, 0.0], &c, &config, SIZED), 0);
        assert_eq!(explain(&[-0.5, 0.0, 0.3], &c, &config, SIZED), 0);
        assert_eq!(explain(&[f32::NAN, 0.0, 0.0], &c, &config, SIZED), 0);
        assert_eq!(explain(&[0.0; 3], &c, &config, SIZED), 0);
    }

    #[test]
    fn after_a_finding_the_thrust_row_must_show_the_loss() {
        let r = rect();
        let c = columns(&r, &FIVE);
        let config = RotorMonitorConfig::DEFAULT;
        let guarded = Judging {
            sized: true,
            thrust_shown: true,
            pairs: true,
            decisive: false,
        };
        let mut d = loss(&c, &[(6, 5.0)]);
        assert_eq!(explain(&d, &c, &config, guarded), 1 << 6);
        // The same torque with the collective unchanged: the recovery's, not a rotor's.
        d[0] = 0.0;
        assert_eq!(explain(&d, &c, &config, guarded), 0);
    }

    #[test]
    fn a_decisive_answer_waits_until_one_rotor_clearly_fits_better_than_the_next() {
        let r = rect();
        let c = columns(&r, &FIVE);
        let config = RotorMonitorConfig::DEFAULT;
        let decisive = Judging {
            sized: false,
            thrust_shown: true,
            pairs: false,
            decisive: true,
        };
        // Rotor 3's loss alone: decisive.
        let d = loss(&c, &[(3, 4.0)]);
        assert_eq!(explain(&d, &c, &config, decisive), 1 << 3);
        // Mostly rotor 3's, part its neighbour 1's (the disturbance's wander): rotor 3 fits
        // best, but not clearly enough to name it.
        let d = loss(&c, &[(3, 2.5), (1, 1.5)]);
        let undecided = Judging {
            decisive: false,
            ..decisive
        };
        assert_eq!(explain(&d, &c, &config, undecided), 1 << 3);
        assert_eq!(explain(&d, &c, &config, decisive), 0);
    }

    #[test]
    fn rotors_not_eligible_are_never_named() {
        let mut thrust = [5.0; MAX_ROBOTS];
        thrust[3] = 0.5;
        let points = |j: usize| [1.0, if j % 2 == 0 { 0.22 } else { -0.22 }, j as f32 * 0.3];
        let r = raw(points);
        let c = Columns::new(8, &r, 1.5, &thrust, 0xff & !(1 << 5), 1.0);
        let d = loss(&c, &[(3, 5.0)]);
        assert_eq!(
            explain(&d, &c, &RotorMonitorConfig::DEFAULT, SIZED) & (1 << 3),
            0
        );
        let d = loss(&c, &[(5, 5.0)]);
        assert_eq!(
            explain(&d, &c, &RotorMonitorConfig::DEFAULT, SIZED) & (1 << 5),
            0
        );
    }
}
