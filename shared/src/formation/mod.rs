//! Formation decision: where every robot stands on the rail for flight (SPEC.md section 2,
//! step 2; section 3, "Controllability and the mixer").
//!
//! - [`objective`]: `det(B B^T)` and the balance sums of a formation.
//! - [`balance`]: bringing a formation onto the balance constraints.
//! - [`search`]: balance-keeping moves with exact line searches.
//! - [`solver`]: seeds, search, polish and the exact constraint check.

pub mod balance;
pub mod objective;
pub mod search;
pub mod solver;

pub use objective::{FormationFigures, Moments, figures};
pub use solver::{
    Formation, FormationError, FormationProblem, Positions, even_positions, satisfies_constraints,
    solve,
};
