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

/// The rotors a change is judged against: their columns in newtons and expected thrusts.
#[derive(Clone, Copy, Debug)]
pub struct Columns {
    /// Each rotor's column (thrust, roll and pitch torque times the scale), N per N.
    a: [[f32; 3]; MAX_ROBOTS],
    /// Each column's squared norm.
    aa: [f32; MAX_ROBOTS],
    /// Each rotor's expected thrust, N.
    thrust: [f32; MAX_ROBOTS],
    /// Rotors that can be named (flown, turning, not known out), bit `i` for rotor `i`.
    eligible: u16,
    count: usize,
}

impl Columns {
    /// The columns of `count` rotors, `column(j)` giving rotor `j`'s (thrust, roll, pitch),
    /// torques times `scale`; a rotor is eligible when its bit of `eligible` is set, its
    /// column is not zero and its expected thrust `thrust[j]` is at least `min_thrust`.
    pub fn new(
        count: usize,
        column: impl Fn(usize) -> [f32; 3],
        scale: f32,
        thrust: &[f32; MAX_ROBOTS],
        eligible: u16,
        min_thrust: f32,
    ) -> Self {
        let count = count.min(MAX_ROBOTS);
        let mut out = Self {
            a: [[0.0; 3]; MAX_ROBOTS],
            aa: [0.0; MAX_ROBOTS],
            thrust: *thrust,
            eligible: 0,
            count,
        };
        for (j, &t) in thrust.iter().enumerate().take(count) {
            let c = column(j);
            let a = [c[0], c[1] * scale, c[2] * scale];
            let aa = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
            out.a[j] = a;
            out.aa[j] = aa;
            if eligible & (1 << j) != 0 && c[0] != 0.0 && aa > 0.0 && t >= min_thrust {
                out.eligible |= 1 << j;
            }
        }
        out
    }

    /// Rotor `j`'s column (thrust, roll and pitch times the scale).
    pub fn column(&self, j: usize) -> [f32; 3] {
        self.a.get(j).copied().unwrap_or([0.0; 3])
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
}

/// The stopped rotors that explain a change `d` (thrust N, roll and pitch torque times the
/// columns' scale), bit `i` for rotor `i`, if one or two do.
pub fn explain(d: &[f32; 3], columns: &Columns, config: &RotorMonitorConfig, how: Judging) -> u16 {
    let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    // Zero, or NaN from a non-finite input: nothing to explain.
    if dd.is_nan() || dd <= 0.0 {
        return 0;
    }
    // b_j = -d . a_j: the loss's projection on each column.
    let mut b = [0.0f32; MAX_ROBOTS];
    for j in eligible(columns) {
        let a = &columns.a[j];
        b[j] = -(d[0] * a[0] + d[1] * a[1] + d[2] * a[2]);
    }
    let fits = |j: usize, lost: f32, sized: bool| {
        let t = columns.thrust[j];
        let small = if sized { config.min_fraction * t } else { 0.0 };
        lost > small && lost <= config.max_fraction * t
    };
    // The collective shows at least `min_fraction` of the thrust the rotors lost.
    let shown = |lost_thrust: f32| !how.thrust_shown || -d[0] >= config.min_fraction * lost_thrust;
    let mut single: Option<(usize, f32)> = None;
    for j in eligible(columns) {
        let lost = b[j] / columns.aa[j];
        if !fits(j, lost, how.sized) || !shown(lost) {
            continue;
        }
        let explained = b[j] * b[j] / (columns.aa[j] * dd);
        if single.is_none_or(|(_, e)| explained > e) {
            single = Some((j, explained));
        }
    }
    // Two rotors stopped together lose `mu (T_j a_j + T_k a_k)` as the change rises: one
    // direction per pair, judged as a single rotor's (two free sizes would fit almost any
    // change with two rotors on the same side).
    let mut pair: Option<(usize, usize, f32)> = None;
    // The collective must show at least `min_fraction` of half the least two rotors' thrust:
    // most ticks of a flight spare the pairs' search here.
    let least = eligible(columns).fold(f32::INFINITY, |m, j| math::min(m, columns.thrust[j]));
    let pairs_possible =
        how.pairs && -d[0] >= config.min_fraction * config.min_fraction * 2.0 * least;
    for j in eligible(columns).filter(|_| pairs_possible) {
        for k in eligible(columns).filter(|&k| k > j) {
            let (tj, tk) = (columns.thrust[j], columns.thrust[k]);
            let (aj, ak) = (&columns.a[j], &columns.a[k]);
            let v: [f32; 3] = core::array::from_fn(|r| tj * aj[r] + tk * ak[r]);
            let vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            if vv <= 0.0 {
                continue;
            }
            // b_j T_j + b_k T_k = -d . v.
            let along = tj * b[j] + tk * b[k];
            let mu = along / vv;
            // Two rotors' loss always shows in the collective.
            let lost = mu * (tj + tk);
            if mu <= config.min_fraction
                || mu > config.max_fraction
                || -d[0] < config.min_fraction * lost
            {
                continue;
            }
            let explained = along * along / (vv * dd);
            if pair.is_none_or(|(_, _, e)| explained > e) {
                pair = Some((j, k, explained));
            }
        }
    }
    let single = single.filter(|&(_, e)| e >= config.min_explained);
    let pair = pair.filter(|&(_, _, e)| e >= config.min_explained);
    match (single, pair) {
        (Some((_, e1)), Some((j, k, e2))) if 1.0 - e2 < PAIR_MARGIN * (1.0 - e1) => {
            (1 << j) | (1 << k)
        }
        (Some((j, _)), _) => 1 << j,
        (None, Some((j, k, _))) => (1 << j) | (1 << k),
        (None, None) => 0,
    }
}

/// The eligible rotors' indices.
fn eligible(columns: &Columns) -> impl Iterator<Item = usize> + '_ {
    (0..columns.count).filter(|&j| columns.eligible & (1 << j) != 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eight rotors on a 2 m x 0.44 m rectangle's rail, unevenly spaced, the COM off the
    /// middle (evenly spaced about the COM, opposite corners' pairs would make the same
    /// change: no wrench tells them apart).
    fn columns(thrust: f32) -> Columns {
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
        Columns::new(
            8,
            |j| [1.0, -points[j][1], points[j][0]],
            1.0 / 0.6,
            &[thrust; MAX_ROBOTS],
            0xff,
            1.0,
        )
    }

    const SIZED: Judging = Judging {
        sized: true,
        thrust_shown: false,
        pairs: true,
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
        let c = columns(5.0);
        for j in 0..8 {
            let d = loss(&c, &[(j, 5.0)]);
            assert_eq!(explain(&d, &c, &RotorMonitorConfig::DEFAULT, SIZED), 1 << j);
        }
    }

    #[test]
    fn every_pair_is_named_as_a_pair_or_one_making_the_same_wrench() {
        let c = columns(5.0);
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
    fn a_torque_without_thrust_or_a_small_change_is_no_rotor() {
        let c = columns(5.0);
        let config = RotorMonitorConfig::DEFAULT;
        assert_eq!(explain(&[0.0, 3.0, 0.0], &c, &config, SIZED), 0);
        assert_eq!(explain(&[-0.5, 0.0, 0.3], &c, &config, SIZED), 0);
        assert_eq!(explain(&[f32::NAN, 0.0, 0.0], &c, &config, SIZED), 0);
        assert_eq!(explain(&[0.0; 3], &c, &config, SIZED), 0);
    }

    #[test]
    fn after_a_finding_the_thrust_row_must_show_the_loss() {
        let c = columns(5.0);
        let config = RotorMonitorConfig::DEFAULT;
        let guarded = Judging {
            sized: true,
            thrust_shown: true,
            pairs: true,
        };
        let mut d = loss(&c, &[(6, 5.0)]);
        assert_eq!(explain(&d, &c, &config, guarded), 1 << 6);
        // The same torque with the collective unchanged: the recovery's, not a rotor's.
        d[0] = 0.0;
        assert_eq!(explain(&d, &c, &config, guarded), 0);
    }

    #[test]
    fn rotors_not_eligible_are_never_named() {
        let mut thrust = [5.0; MAX_ROBOTS];
        thrust[3] = 0.5;
        let points = |j: usize| [1.0, if j % 2 == 0 { 0.22 } else { -0.22 }, j as f32 * 0.3];
        let c = Columns::new(8, points, 1.5, &thrust, 0xff & !(1 << 5), 1.0);
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
