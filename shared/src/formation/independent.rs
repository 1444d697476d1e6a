//! An independent global search to compare the solver with (tests only): thousands of random
//! formations, each polished by COBYLA (a general-purpose constrained local method) on the
//! problem as stated (Oishi & Jimbo (2025), eq. (4); docs/models.md#formation-search), in
//! `f64`, with its own rail walk and its own `det(B B^T)`. It shares no code with the solver.

#![cfg(test)]

use core::cell::RefCell;
use std::boxed::Box;
use std::format;
use std::string::String;
use std::vec;
use std::vec::Vec;

use cobyla::{Func, RhoBeg, StopTols, minimize};
use proptest::prelude::*;

use crate::formation::search::SPACING_MARGIN;
use crate::formation::{FormationError, FormationProblem, solve};
use crate::geometry::{Rail, Vec2};

/// A closed polygonal rail in `f64`, walked by arc length.
struct Loop {
    vertices: Vec<[f64; 2]>,
    cumulative: Vec<f64>,
}

impl Loop {
    fn new(vertices: &[[f64; 2]]) -> Self {
        let mut cumulative = vec![0.0];
        for i in 0..vertices.len() {
            let (a, b) = (vertices[i], vertices[(i + 1) % vertices.len()]);
            let length = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
            cumulative.push(cumulative[i] + length);
        }
        Self {
            vertices: vertices.to_vec(),
            cumulative,
        }
    }

    fn length(&self) -> f64 {
        self.cumulative[self.vertices.len()]
    }

    fn at(&self, s: f64) -> [f64; 2] {
        let s = s.rem_euclid(self.length());
        let n = self.vertices.len();
        let i = (0..n).rev().find(|&i| self.cumulative[i] <= s).unwrap_or(0);
        let f = (s - self.cumulative[i]) / (self.cumulative[i + 1] - self.cumulative[i]);
        let (a, b) = (self.vertices[i], self.vertices[(i + 1) % n]);
        [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]
    }
}

/// The problem as stated: maximise `det(B B^T)` with both balance sums within `eps`, cyclic
/// order and `spacing` along the rail.
struct Stated<'a> {
    rail: &'a Loop,
    spin: &'a [f64],
    com: [f64; 2],
    cq: f64,
    spacing: f64,
    eps: f64,
    last: RefCell<Option<Evaluated>>,
}

/// A point and its `det(B B^T)` and balance sums.
type Evaluated = (Vec<f64>, (f64, [f64; 2]));

impl Stated<'_> {
    /// `det(B B^T)` as a plain 3 x 3 determinant, and the balance sums (the last answer is
    /// kept: COBYLA asks for the objective and each constraint at the same point).
    fn det_and_balance(&self, s: &[f64]) -> (f64, [f64; 2]) {
        if let Some((at, answer)) = self.last.borrow().as_ref() {
            if at.as_slice() == s {
                return *answer;
            }
        }
        let mut m = [[0.0f64; 3]; 3];
        let mut sum = [0.0, 0.0];
        for (j, &sj) in s.iter().enumerate() {
            let p = self.rail.at(sj);
            let b = [
                p[0] - self.com[0],
                p[1] - self.com[1],
                self.spin[j] * self.cq,
            ];
            for row in 0..3 {
                for col in 0..3 {
                    m[row][col] += b[row] * b[col];
                }
            }
            sum[0] += b[0];
            sum[1] += b[1];
        }
        let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        *self.last.borrow_mut() = Some((s.to_vec(), (det, sum)));
        (det, sum)
    }

    /// Forward gaps of arc lengths given in order (unrolled: increasing).
    fn gaps(&self, s: &[f64]) -> Vec<f64> {
        let n = s.len();
        (0..n)
            .map(|j| {
                if j + 1 < n {
                    s[j + 1] - s[j]
                } else {
                    s[0] + self.rail.length() - s[n - 1]
                }
            })
            .collect()
    }

    fn feasible(&self, s: &[f64]) -> bool {
        let (_, h) = self.det_and_balance(s);
        h[0].abs() <= self.eps
            && h[1].abs() <= self.eps
            && self.gaps(s).iter().all(|&g| g >= self.spacing - 1e-9)
    }

    /// Each of `starts` random formations (random gaps: min spacing plus a uniform share of
    /// the free rail) polished by COBYLA minimising `objective`, keeping order and `spacing`
    /// and, with `balanced`, the balance within eps/2; `each` gets every polished formation.
    fn polish_random_starts(
        &self,
        starts: usize,
        seed: u64,
        xtol: f64,
        objective: impl Fn(&[f64], &mut ()) -> f64,
        balanced: bool,
        mut each: impl FnMut(Vec<f64>),
    ) {
        let n = self.spin.len();
        let length = self.rail.length();
        let room = length - n as f64 * self.spacing;
        let mut rng = SplitMix(seed);
        let mut constraints: Vec<Box<dyn Func<()> + '_>> = Vec::new();
        for j in 0..n {
            constraints.push(Box::new(move |s: &[f64], _: &mut ()| {
                let gap = if j + 1 < n {
                    s[j + 1] - s[j]
                } else {
                    s[0] + length - s[n - 1]
                };
                gap - self.spacing
            }));
        }
        if balanced {
            for axis in 0..2 {
                for sign in [1.0, -1.0] {
                    constraints.push(Box::new(move |s: &[f64], _: &mut ()| {
                        0.5 * self.eps - sign * self.det_and_balance(s).1[axis]
                    }));
                }
            }
        }
        let bounds = vec![(-length, 3.0 * length); n];
        for _ in 0..starts {
            let mut share: Vec<f64> = (0..n).map(|_| -rng.uniform().ln()).collect();
            let total: f64 = share.iter().sum();
            share.iter_mut().for_each(|w| *w *= 0.999 * room / total);
            let mut s = vec![rng.uniform() * length];
            for j in 1..n {
                s.push(s[j - 1] + self.spacing + share[j - 1]);
            }
            let stop = StopTols {
                xtol_abs: vec![xtol; n],
                ..StopTols::default()
            };
            let polished = match minimize(
                &objective,
                &s,
                &bounds,
                &constraints,
                (),
                1500,
                RhoBeg::All(0.1),
                Some(stop),
            ) {
                Ok((_, x, _)) | Err((_, x, _)) => x,
            };
            each(polished);
        }
    }

    /// Best feasible `det(B B^T)` over `starts` random formations polished by COBYLA, and
    /// the formation that has it.
    fn best(&self, starts: usize, seed: u64) -> Option<(f64, Vec<f64>)> {
        let mut best: Option<(f64, Vec<f64>)> = None;
        let objective = |s: &[f64], _: &mut ()| -1e3 * self.det_and_balance(s).0;
        self.polish_random_starts(starts, seed, 1e-8, objective, true, |polished| {
            if self.feasible(&polished) {
                let det = self.det_and_balance(&polished).0;
                if best.as_ref().is_none_or(|(b, _)| det > *b) {
                    best = Some((det, polished));
                }
            }
        });
        best
    }
}

impl Stated<'_> {
    /// Smallest `|sum b|` over `starts` random formations polished by COBYLA towards balance,
    /// keeping order and `spacing` (the eps and det play no part).
    fn closest(&self, starts: usize, seed: u64) -> f64 {
        let mut best = f64::INFINITY;
        let objective = |s: &[f64], _: &mut ()| {
            let h = self.det_and_balance(s).1;
            1e3 * (h[0] * h[0] + h[1] * h[1])
        };
        self.polish_random_starts(starts, seed, 1e-9, objective, false, |polished| {
            if self
                .gaps(&polished)
                .iter()
                .all(|&g| g >= self.spacing - 1e-9)
            {
                let h = self.det_and_balance(&polished).1;
                best = best.min(h[0].hypot(h[1]));
            }
        });
        best
    }
}

/// SplitMix64: uniform numbers for the random starts, reproducible from a seed.
struct SplitMix(u64);

impl SplitMix {
    /// Uniform in (0, 1].
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }
}

/// Runs the solver and the independent search on one payload and compares them.
fn compare(vertices: &[[f64; 2]], com: [f64; 2], eps: f64, starts: usize) -> Result<(), String> {
    let spin_i8 = [1i8, -1, 1, -1, 1, -1, 1, -1];
    let spin: Vec<f64> = spin_i8.iter().map(|&s| f64::from(s)).collect();
    let rail_f32: Vec<Vec2> = vertices
        .iter()
        .map(|v| Vec2::new(v[0] as f32, v[1] as f32))
        .collect();
    let rail = Rail::new(&rail_f32).map_err(|e| format!("rail: {e:?}"))?;
    let walk = Loop::new(vertices);
    let stated = Stated {
        rail: &walk,
        spin: &spin,
        com,
        cq: 0.016,
        spacing: 0.25,
        eps,
        last: RefCell::new(None),
    };
    let problem = FormationProblem {
        rail: &rail,
        spin: &spin_i8,
        min_spacing: 0.25,
        com: Vec2::new(com[0] as f32, com[1] as f32),
        torque_per_thrust: 0.016,
        balance_eps: eps as f32,
        current: None,
    };
    let independent = stated.best(starts, 7);
    match (solve(&problem), independent) {
        (Ok(f), best) => {
            // Unroll the solver's positions (rail order from robot 0) and judge them with the
            // independent model.
            let mut s: Vec<f64> = f.positions.iter().map(|&p| f64::from(p)).collect();
            for j in 1..s.len() {
                while s[j] < s[j - 1] {
                    s[j] += walk.length();
                }
            }
            if !stated.feasible(&s) {
                return Err(format!("solver's formation breaks a constraint: {s:?}"));
            }
            let det = stated.det_and_balance(&s).0;
            if let Some((best, at)) = best {
                if det < best * (1.0 - 0.005) {
                    return Err(format!(
                        "solver det {det:.6e} more than 0.5 % below the independent {best:.6e} \
                         (COM {com:?}, rail {vertices:?}; solver at {s:?}, independent at {at:?})"
                    ));
                }
            }
            Ok(())
        }
        (Err(FormationError::Unbalanceable { closest, .. }), None) => {
            // The refusal must tell the truth: the closest balance it reports is no farther
            // from zero than the independent search gets at the solver's spacing (`min_spacing`
            // plus its margin, which the report is taken at).
            let reported = f64::from(closest[0]).hypot(f64::from(closest[1]));
            let at_solver_spacing = Stated {
                spacing: 0.25 + f64::from(SPACING_MARGIN),
                last: RefCell::new(None),
                ..stated
            };
            let independent = at_solver_spacing.closest(CLOSEST_STARTS, 11);
            if reported > independent * 1.001 + 1e-5 {
                return Err(format!(
                    "the refusal reports a closest balance |sum b| = {reported:.6e} where the \
                     independent search reaches {independent:.6e} (COM {com:?}, rail {vertices:?})"
                ));
            }
            Ok(())
        }
        (Err(e), best) => Err(format!(
            "solver refused ({e}) where the independent search found {:?} (COM {com:?})",
            best.map(|(det, _)| det)
        )),
    }
}

const RECT_RAIL: [[f64; 2]; 4] = [[-1.0, -0.22], [1.0, -0.22], [1.0, 0.22], [-1.0, 0.22]];
const L_RAIL: [[f64; 2]; 6] = [
    [-0.12, -0.12],
    [0.74, -0.12],
    [0.74, 0.32],
    [0.32, 0.32],
    [0.32, 0.74],
    [-0.12, 0.74],
];

/// Starts of the independent search per payload.
const STARTS: usize = 1000;
/// Starts of the independent search for the closest balance, when the solver refuses.
const CLOSEST_STARTS: usize = 300;

#[test]
fn the_paper_cases_reach_the_independent_optimum() {
    for (rail, com, eps) in [
        (&RECT_RAIL[..], [0.33, 0.01], 1e-5),
        (&RECT_RAIL[..], [0.4, 0.01], 1e-5),
        (&RECT_RAIL[..], [0.21, 0.0], 1e-5),
        (&RECT_RAIL[..], [-0.17, 0.014], 1e-5),
        (&L_RAIL[..], [0.31, 0.1], 1e-4),
        (&L_RAIL[..], [0.4, 0.1], 1e-4),
    ] {
        if let Err(e) = compare(rail, com, eps, STARTS) {
            panic!("{e}");
        }
    }
}

/// A convex rail: `corners` points on an ellipse at sorted random angles.
fn convex_rail(a: f64, b: f64, angles: &[f64]) -> Vec<[f64; 2]> {
    let mut t: Vec<f64> = angles.to_vec();
    t.sort_by(|x, y| x.partial_cmp(y).unwrap_or(std::cmp::Ordering::Equal));
    t.dedup_by(|x, y| (*x - *y).abs() < 0.2);
    t.iter().map(|&t| [a * t.cos(), b * t.sin()]).collect()
}

/// A non-convex rail: an L (one arm `w` by `h`, the other `h2` by `w2`) or, with `notch`,
/// a U (a rectangle with a notch cut into its top edge).
fn nonconvex_rail(w: f64, h: f64, w2: f64, h2: f64, notch: bool) -> Vec<[f64; 2]> {
    if notch {
        let (nx, ny) = (0.3 * w, 0.5 * h2.min(h));
        vec![
            [0.0, 0.0],
            [w, 0.0],
            [w, h],
            [0.5 * w + nx, h],
            [0.5 * w + nx, h - ny],
            [0.5 * w - nx, h - ny],
            [0.5 * w - nx, h],
            [0.0, h],
        ]
    } else {
        vec![
            [0.0, 0.0],
            [w, 0.0],
            [w, h],
            [w2, h],
            [w2, h + h2],
            [0.0, h + h2],
        ]
    }
}

/// A COM a fraction `(fx, fy)` across the rail's bounding box.
fn com_in_box(vertices: &[[f64; 2]], fx: f64, fy: f64) -> [f64; 2] {
    let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
    for v in vertices {
        for k in 0..2 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    [lo[0] + fx * (hi[0] - lo[0]), lo[1] + fy * (hi[1] - lo[1])]
}

/// proptest's first random case in a CI run (seed `cc 4182fe14...` in
/// `proptest-regressions/formation/independent.txt`): the solver stopped at 2.145216e-3, a
/// local maximum one edge away from the independent search's 2.156586e-3.
#[test]
fn convex_regression_4182fe14() {
    let rail = convex_rail(
        0.8237543072534541,
        0.5652836807904986,
        &[
            3.1085271977159046,
            5.184111203321445,
            1.7333508139821485,
            3.7279721136107424,
        ],
    );
    let com = com_in_box(&rail, 0.6286600377342274, 0.39799403808617234);
    if let Err(e) = compare(&rail, com, 1e-4, STARTS) {
        panic!("{e}");
    }
}

/// The rail of proptest's case `cc 89deb478` (`proptest-regressions/formation/independent.txt`):
/// a convex pentagon whose first vertex has a short segment (0.137 m) behind it.
fn rail_89deb478() -> Vec<[f64; 2]> {
    convex_rail(
        0.7198313286383888,
        0.5730618955053353,
        &[
            0.02026902550288104,
            3.4508551482318452,
            2.1314586186553734,
            6.0638019024847285,
            3.170981187753376,
        ],
    )
}

/// proptest's case `cc 89deb478`: the solver refused (`Unbalanceable`, reporting a closest
/// balance of 3.88e-3 m) where the independent search found a balanced formation with
/// `det(B B^T)` 2.1833e-4. Its best formation puts five robots on the first segment and the
/// last robot on the short segment before the first vertex, so the gap that wraps round the
/// rail is tight; the assignment's reachable ranges ignored that gap, every start of the face
/// solver broke it and the assignment was skipped (here and in the closest-balance search).
#[test]
fn convex_regression_89deb478() {
    let rail = rail_89deb478();
    let com = com_in_box(&rail, 0.6727286910824352, 0.4599253876349734);
    if let Err(e) = compare(&rail, com, 1e-4, STARTS) {
        panic!("{e}");
    }
}

/// The same rail with the COM just beyond the robots' reach: the solver refuses, and the
/// closest balance it reports is the one the independent search reaches (the formation
/// closest to balance needs the assignment that wraps round the first vertex).
#[test]
fn refusal_reports_the_closest_balance_89deb478() {
    let rail = rail_89deb478();
    let near = com_in_box(&rail, 0.6727286910824352, 0.4599253876349734);
    let com = [near[0] + 0.003, near[1] + 0.003];
    let rail_f32: Vec<Vec2> = rail
        .iter()
        .map(|v| Vec2::new(v[0] as f32, v[1] as f32))
        .collect();
    let problem = FormationProblem {
        rail: &Rail::new(&rail_f32).expect("a rail"),
        spin: &[1, -1, 1, -1, 1, -1, 1, -1],
        min_spacing: 0.25,
        com: Vec2::new(com[0] as f32, com[1] as f32),
        torque_per_thrust: 0.016,
        balance_eps: 1e-4,
        current: None,
    };
    let refusal = solve(&problem);
    assert!(
        matches!(refusal, Err(FormationError::Unbalanceable { .. })),
        "{refusal:?}"
    );
    if let Err(e) = compare(&rail, com, 1e-4, STARTS) {
        panic!("{e}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4, ..ProptestConfig::default() })]

    #[test]
    fn random_convex_payloads_reach_the_independent_optimum(
        a in 0.5f64..1.2, b in 0.25f64..0.7,
        angles in proptest::collection::vec(0.0f64..std::f64::consts::TAU, 4..8),
        fx in 0.3f64..0.7, fy in 0.3f64..0.7,
    ) {
        let rail = convex_rail(a, b, &angles);
        prop_assume!(rail.len() >= 3);
        let walk = Loop::new(&rail);
        prop_assume!(walk.length() > 8.0 * 0.25 + 0.3);
        let com = com_in_box(&rail, fx, fy);
        compare(&rail, com, 1e-4, STARTS).map_err(TestCaseError::fail)?;
    }

    #[test]
    fn random_nonconvex_payloads_reach_the_independent_optimum(
        w in 0.7f64..1.6, h in 0.3f64..0.6, w2f in 0.3f64..0.7, h2 in 0.3f64..0.8,
        notch in any::<bool>(), fx in 0.3f64..0.7, fy in 0.2f64..0.5,
    ) {
        let rail = nonconvex_rail(w, h, w2f * w, h2, notch);
        let com = com_in_box(&rail, fx, fy);
        compare(&rail, com, 1e-4, STARTS).map_err(TestCaseError::fail)?;
    }
}
