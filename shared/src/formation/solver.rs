//! The formation decision (docs/models.md#formation-search): every robot's arc length on the rail,
//! maximising `det(B B^T)` with the robots balanced about the estimated COM, in their cyclic
//! order and at least `min_spacing` apart.
//!
//! The rail's corners make the objective piecewise, and a local search from a few seeds lands
//! in the wrong piece. So the solver goes through every segment assignment (which straight
//! segment each robot stands on, [`crate::formation::assignment`]): on one assignment the
//! problem is smooth (linear constraints, a quartic objective) and is solved by an active-set
//! Newton method ([`crate::formation::face`]), first to balance, then to the best `det`.
//! An assignment whose robots cannot reach balance, or whose upper bound on `det`
//! ([`crate::formation::bound`]) is no better than the best formation found so far, is skipped
//! unsolved. The starts of one assignment can all end at local maxima below its best one, a
//! neighbouring vertex of the polytope; so from the best of them the solver climbs edges that
//! lead higher ([`Face::climb_edge`]). The best formation is polished onto the balance
//! constraints and checked against every constraint exactly as stated. Deterministic and
//! bounded: a fixed enumeration order, at most [`MAX_COUNT_VECTORS`] count vectors checked for
//! balance and [`MAX_ASSIGNMENTS`] assignments bounded or solved, a capped
//! iteration count per solve and climb, no allocation.
//!
//! When no assignment balances, the refusal reports the formation closest to balance (the
//! global minimum of `|sum r|` over every assignment, a convex problem on each).

use crate::numbers::Num;

use crate::formation::assignment::{Assignments, Layout, spin_period};
use crate::formation::balance::project_to_balance;
use crate::formation::bound::{BoundShape, det_bound, may_balance};
use crate::formation::face::{Face, Goal};
use crate::formation::objective::{FormationFigures, Moments, figures};
use crate::formation::search::{SPACING_MARGIN, order_and_spacing_hold};
use crate::geometry::{Rail, Vec2};
use crate::scenario::{MAX_ROBOTS, Scenario};

/// Most assignments solved or bounded in one decision, among those that pass the cheap
/// balance check (the paper's rails have a few hundred in all). 15 robots on a 9-segment rail
/// can have 280,000: visiting them all raised `det(B B^T)` 7 % on seed 1's trial 42 and took
/// 4.5 s on a desktop, against 0.8 s for these 20,000 (the formation job's deadline on the
/// board is 40 ms either way, docs/system.md#mission-phases).
pub const MAX_ASSIGNMENTS: u32 = 20_000;
/// Most robots-per-segment count vectors looked at in one decision. Whether an assignment can
/// balance does not depend on which robot comes first (the balance sums do not involve the
/// spins), so that check is made once per count vector: 13 to 16 robots on a 9-segment rail
/// have up to a few hundred thousand of them, times up to `n` first robots.
pub const MAX_COUNT_VECTORS: u32 = 2_000_000;
/// Starts on each assignment, as the fraction of each robot's reachable range: the
/// assignment's problem can have several local maxima (a robot pushed to either end).
const STARTS: [f32; 3] = [0.5, 0.0, 1.0];
/// Relative margin an assignment's bound must beat the best `det(S)` by to be solved.
const PRUNE_MARGIN: f32 = 1e-4;
/// Most edges climbed from an assignment's best start ([`Face::climb_edge`]); 300 random
/// rails needed at most 4.
const MAX_CLIMBS: u32 = 4;

pub use crate::rail::moves::Positions;

/// What the formation must satisfy.
#[derive(Clone, Copy, Debug)]
pub struct FormationProblem<'a> {
    /// The rail.
    pub rail: &'a Rail,
    /// Spin of each robot, in rail order; its length is the robot count.
    pub spin: &'a [i8],
    /// Smallest arc length between neighbours, m.
    pub min_spacing: f32,
    /// Estimated COM, body frame, m: the origin of `B`.
    pub com: Vec2,
    /// `c_q / c_t`, m.
    pub torque_per_thrust: f32,
    /// Bound on `|sum b1|` and `|sum b2|`, m.
    pub balance_eps: f32,
    /// Where the robots stand now, if known: among formations that are the same up to
    /// robots of equal spin trading places, the one nearest to it is chosen.
    pub current: Option<&'a [f32]>,
}

impl<'a> FormationProblem<'a> {
    /// The problem of `scenario`'s rail and robots about the COM `com`, starting from `current`.
    pub fn for_scenario(scenario: &'a Scenario, com: Vec2, current: Option<&'a [f32]>) -> Self {
        Self {
            rail: &scenario.payload.rail,
            spin: &scenario.robots.spin,
            min_spacing: scenario.robots.min_spacing,
            com,
            torque_per_thrust: scenario.robots.torque_per_thrust,
            balance_eps: scenario.formation.balance_eps,
            current,
        }
    }
}

/// Why no formation can be given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FormationError {
    /// A parameter is out of range.
    BadParameter(&'static str),
    /// The robots do not fit on the rail at `min_spacing`.
    TooManyRobots {
        /// Robots.
        count: usize,
        /// Rail they need, m.
        needed: f32,
        /// Rail there is, m.
        perimeter: f32,
    },
    /// No formation on the rail balances about the COM (it lies out of their reach).
    Unbalanceable {
        /// The COM asked for.
        com: Vec2,
        /// The balance sums `[sum b1, sum b2]` (m) of the formation closest to balance: the
        /// smallest `|sum b|` the rail allows (with the robots `min_spacing` plus the solver's
        /// 20 um margin apart).
        closest: [f32; 2],
    },
}

impl core::fmt::Display for FormationError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::BadParameter(what) => write!(f, "{what}"),
            Self::TooManyRobots {
                count,
                needed,
                perimeter,
            } => write!(
                f,
                "{count} robots need {} m of rail at min_spacing, the rail is {} m",
                Num(needed),
                Num(perimeter)
            ),
            Self::Unbalanceable { com, closest } => {
                let size = crate::math::sqrt(closest[0] * closest[0] + closest[1] * closest[1]);
                write!(
                    f,
                    "no formation on the rail balances about the COM ({}, {}): it is out of the robots' reach; \
                     the closest the rail allows leaves balance sums ({}, {}) m (|sum b| = {} m)",
                    Num(com.x),
                    Num(com.y),
                    Num(closest[0]),
                    Num(closest[1]),
                    Num(size)
                )
            }
        }
    }
}

impl core::error::Error for FormationError {}

/// The chosen formation.
#[derive(Clone, Debug, PartialEq)]
pub struct Formation {
    /// Arc length of each robot, in rail order.
    pub positions: Positions,
    /// Its figures (det, balance, smallest gap).
    pub figures: FormationFigures,
    /// Assignments that reached balance (each one a start of the `det` search).
    pub seeds_balanced: u32,
    /// Newton iterations, over all assignments solved.
    pub sweeps: u32,
    /// Assignments visited.
    pub assignments: u32,
    /// Assignments skipped because their upper bound could not beat the best.
    pub pruned: u32,
    /// True when every assignment was visited (none left out by [`MAX_COUNT_VECTORS`] or
    /// [`MAX_ASSIGNMENTS`]).
    pub exhaustive: bool,
}

/// The even formation: robot `j` at `j * perimeter / count`.
pub fn even_positions(rail: &Rail, count: usize) -> Positions {
    let count = count.min(MAX_ROBOTS);
    (0..count)
        .map(|j| j as f32 * rail.perimeter() / count as f32)
        .collect()
}

fn check(problem: &FormationProblem<'_>) -> Result<(), FormationError> {
    let n = problem.spin.len();
    if n == 0 || n > MAX_ROBOTS {
        return Err(FormationError::BadParameter("robot count must be 1 to 16"));
    }
    if !(problem.min_spacing > 0.0 && problem.min_spacing.is_finite()) {
        return Err(FormationError::BadParameter("min_spacing must be positive"));
    }
    if !(problem.balance_eps > 0.0 && problem.balance_eps.is_finite()) {
        return Err(FormationError::BadParameter("balance_eps must be positive"));
    }
    if !problem.com.is_finite() {
        return Err(FormationError::BadParameter("the COM must be finite"));
    }
    if !(problem.torque_per_thrust >= 0.0 && problem.torque_per_thrust.is_finite()) {
        return Err(FormationError::BadParameter(
            "torque_per_thrust must not be negative",
        ));
    }
    if let Some(current) = problem.current {
        if current.len() != n {
            return Err(FormationError::BadParameter(
                "current positions must have one entry per robot",
            ));
        }
    }
    let needed = n as f32 * problem.min_spacing;
    let perimeter = problem.rail.perimeter();
    if needed > perimeter {
        return Err(FormationError::TooManyRobots {
            count: n,
            needed,
            perimeter,
        });
    }
    Ok(())
}

/// True when `positions` satisfy every constraint exactly as stated: on the rail, in order,
/// `min_spacing` apart, both balance sums within `balance_eps`.
pub fn satisfies_constraints(problem: &FormationProblem<'_>, positions: &[f32]) -> bool {
    let rail = problem.rail;
    let on_rail = positions
        .iter()
        .all(|&s| s.is_finite() && (0.0..rail.perimeter()).contains(&s));
    let f = figures(
        rail,
        positions,
        problem.spin,
        problem.com,
        problem.torque_per_thrust,
    );
    on_rail
        && order_and_spacing_hold(rail, positions, problem.min_spacing)
        && f.balance[0].abs() <= problem.balance_eps
        && f.balance[1].abs() <= problem.balance_eps
}

/// `det(S)` and the pieces of the bound's shape at `positions`.
fn score(problem: &FormationProblem<'_>, positions: &[f32]) -> (f32, BoundShape) {
    let mut points = [Vec2::default(); MAX_ROBOTS];
    for (pt, &s) in points.iter_mut().zip(positions.iter()) {
        *pt = problem.rail.point_at(s);
    }
    let n = positions.len();
    let m = Moments::of(&points[..n], problem.com, problem.spin);
    let inv = 1.0 / n as f32;
    let s = [
        m.sxx - m.vx * m.vx * inv,
        m.sxy - m.vx * m.vy * inv,
        m.syy - m.vy * m.vy * inv,
    ];
    (m.schur_det(), BoundShape::at(s, Vec2::new(m.vx, m.vy), n))
}

/// Takes a solved face whose `det(S)` is `value` as the best formation if it beats `best`
/// once polished onto the balance constraints (within `tolerance`) and checked against every
/// constraint.
fn offer(
    problem: &FormationProblem<'_>,
    layout: &Layout,
    face: &Face<'_>,
    value: f32,
    tolerance: f32,
    best: &mut Option<(f32, Positions)>,
    shape: &mut BoundShape,
) {
    if best.as_ref().is_some_and(|(b, _)| value <= *b) {
        return;
    }
    let rail = problem.rail;
    let mut positions = positions_of(rail, layout, face);
    // The steps keep the balance sums in exact arithmetic; polish away the rounding.
    if !project_to_balance(
        rail,
        problem.com,
        problem.min_spacing,
        tolerance,
        &mut positions,
    ) || !satisfies_constraints(problem, &positions)
    {
        return;
    }
    let (value, at) = score(problem, &positions);
    if best.as_ref().is_none_or(|(b, _)| value > *b) {
        *best = Some((value, positions));
        *shape = at;
    }
}

/// Positions by robot from a solved face.
fn positions_of(rail: &Rail, layout: &Layout, face: &Face<'_>) -> Positions {
    let n = layout.n;
    let mut out = [0.0f32; MAX_ROBOTS];
    for i in 0..n {
        out[usize::from(layout.robot[i])] = rail.wrap(face.x[i]);
    }
    out[..n].iter().copied().collect()
}

/// Among the formations equal to `positions` up to a shift by whole spin periods, the one
/// whose robots travel least from `current`.
fn nearest_rotation(rail: &Rail, spin: &[i8], positions: &Positions, current: &[f32]) -> Positions {
    let n = positions.len();
    let period = spin_period(spin);
    let distance = |shift: usize| -> f32 {
        (0..n)
            .map(|j| {
                let d = rail.forward_gap(rail.wrap(current[j]), positions[(j + shift) % n]);
                d.min(rail.perimeter() - d)
            })
            .sum()
    };
    let best = (0..n)
        .step_by(period)
        .map(|shift| (shift, distance(shift)))
        .fold((0, f32::INFINITY), |a, b| if b.1 < a.1 { b } else { a })
        .0;
    (0..n).map(|j| positions[(j + best) % n]).collect()
}

/// Finds the formation that maximises `det(B B^T)` under the constraints.
pub fn solve(problem: &FormationProblem<'_>) -> Result<Formation, FormationError> {
    check(problem)?;
    let rail = problem.rail;
    let n = problem.spin.len();
    let spacing = problem.min_spacing + SPACING_MARGIN;
    let tolerance = 0.25 * problem.balance_eps;
    let max_iterations = 10 + 8 * n as u32;
    let mut best: Option<(f32, Positions)> = None;
    let mut shape = BoundShape::ROUND;
    let (mut seeds_balanced, mut sweeps, mut visited, mut pruned) = (0u32, 0u32, 0u32, 0u32);
    let mut assignments = Assignments::new(rail, problem.spin, spacing);
    let mut exhaustive = true;
    let (mut count_vectors, mut examined) = (0u32, 0u32);
    // Whether the current count vector's robots can stand on their segments and reach balance
    // (the same for every first robot).
    let mut counts_may_balance = false;
    for assignment in assignments.by_ref() {
        if assignment.first == 0 {
            if count_vectors >= MAX_COUNT_VECTORS {
                exhaustive = false;
                break;
            }
            count_vectors += 1;
            counts_may_balance = Layout::new(rail, problem.spin, problem.com, spacing, &assignment)
                .is_some_and(|layout| may_balance(&layout, tolerance));
        }
        visited += 1;
        if !counts_may_balance {
            continue;
        }
        if examined >= MAX_ASSIGNMENTS {
            exhaustive = false;
            break;
        }
        examined += 1;
        let Some(layout) = Layout::new(rail, problem.spin, problem.com, spacing, &assignment)
        else {
            continue;
        };
        if let Some((value, _)) = &best {
            if det_bound(&layout, &shape) <= *value * (1.0 + PRUNE_MARGIN) {
                pruned += 1;
                continue;
            }
        }
        // The best local maximum the starts reach on this assignment.
        let mut top: Option<(f32, Face<'_>)> = None;
        for lean in STARTS {
            let Some(mut face) = Face::start(&layout, lean) else {
                continue;
            };
            let reached = face.solve(Goal::Balance, tolerance, max_iterations);
            sweeps += reached.iterations;
            if reached.balance.x.abs() > tolerance || reached.balance.y.abs() > tolerance {
                // The balance is a convex problem: no other start does better.
                break;
            }
            seeds_balanced += 1;
            let outcome = face.solve(Goal::Det, tolerance, max_iterations);
            sweeps += outcome.iterations;
            offer(
                problem,
                &layout,
                &face,
                outcome.value,
                tolerance,
                &mut best,
                &mut shape,
            );
            if top.as_ref().is_none_or(|(v, _)| outcome.value > *v) {
                top = Some((outcome.value, face));
            }
        }
        // A neighbouring vertex of that maximum can be higher than any start reached: climb
        // edges from it while one leads higher, at most `MAX_CLIMBS` edges within half a
        // solve's iterations.
        if let Some((_, mut face)) = top {
            let mut budget = max_iterations / 2;
            let mut climbs = 0;
            let mut climbed = None;
            while climbs < MAX_CLIMBS && budget > 0 && face.climb_edge() {
                climbs += 1;
                let outcome = face.solve(Goal::Det, tolerance, budget);
                sweeps += outcome.iterations;
                budget = budget.saturating_sub(outcome.iterations.max(1));
                climbed = Some(outcome.value);
            }
            if let Some(value) = climbed {
                offer(
                    problem, &layout, &face, value, tolerance, &mut best, &mut shape,
                );
            }
        }
    }
    let Some((_, positions)) = best else {
        return Err(FormationError::Unbalanceable {
            com: problem.com,
            closest: closest_balance(problem),
        });
    };
    let positions = match problem.current {
        Some(current) => nearest_rotation(rail, problem.spin, &positions, current),
        None => positions,
    };
    let figures = figures(
        rail,
        &positions,
        problem.spin,
        problem.com,
        problem.torque_per_thrust,
    );
    Ok(Formation {
        positions,
        figures,
        seeds_balanced,
        sweeps,
        assignments: visited,
        pruned,
        exhaustive,
    })
}

/// The balance sums of the formation nearest to balance, over every assignment.
fn closest_balance(problem: &FormationProblem<'_>) -> [f32; 2] {
    let rail = problem.rail;
    let n = problem.spin.len();
    let spacing = problem.min_spacing + SPACING_MARGIN;
    let mut best = [f32::INFINITY; 2];
    let mut best_size = f32::INFINITY;
    // The balance sums do not involve the spins: one first robot per count vector is enough.
    let count_vectors = Assignments::new(rail, problem.spin, spacing)
        .filter(|assignment| assignment.first == 0)
        .take(MAX_COUNT_VECTORS as usize);
    for assignment in count_vectors {
        let Some(layout) = Layout::new(rail, problem.spin, problem.com, spacing, &assignment)
        else {
            continue;
        };
        let Some(mut face) = Face::start(&layout, 0.5) else {
            continue;
        };
        let h = face.solve(Goal::Balance, 0.0, 10 + 8 * n as u32).balance;
        let size = h.dot(h);
        if size < best_size {
            best_size = size;
            best = [h.x, h.y];
        }
    }
    best
}

#[cfg(test)]
mod tests;
