//! Formation decision: where every robot stands on the rail for flight
//! (docs/system.md#formation-decision; docs/models.md#formation-objective-and-balance-constraints).
//!
//! - [`objective`]: `det(B B^T)` and the balance sums of a formation.
//! - [`assignment`]: which rail segment each robot stands on, and the smooth problem of one
//!   such assignment.
//! - [`face`]: the active-set Newton solver of one assignment's problem.
//! - [`bound`]: whether an assignment can balance, and an upper bound on `det` over it.
//! - [`balance`]: bringing a formation onto the balance constraints (the final polish).
//! - [`search`]: order and spacing checks, and how a robot can move from a rail point.
//! - [`solver`]: the enumeration of assignments, pruning, polish and the exact constraint check.

pub mod assignment;
pub mod balance;
pub mod bound;
pub mod face;
mod independent;
mod newton;
pub mod objective;
pub mod search;
pub mod solver;

pub use objective::{FormationFigures, Moments, figures};
pub use solver::{
    Formation, FormationError, FormationProblem, Positions, even_positions, satisfies_constraints,
    solve,
};
