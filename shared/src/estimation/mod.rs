//! Estimation of theta = [COM x, COM y, mass] before take-off, by lifting one edge with
//! adjacent groups of robots (docs/system.md#estimation-loop; docs/system.md#paper-cases).
//!
//! - [`grid`]: the grid of theta (and an optional thrust-scale axis).
//! - [`groups`]: lifting groups of adjacent candidates.
//! - [`guard`]: one layer beyond each face of the grid, to tell a truth outside it.
//! - [`likelihood`]: the reading's model, with censoring at the robots' maximum thrust.
//! - [`posterior`]: the log-domain grid posterior, its MAP and the stopping rule's mass.
//! - [`information`]: mutual information of each group's next reading.
//! - [`estimator`]: the loop that ties them together.

pub mod estimator;
pub mod grid;
pub mod groups;
pub mod guard;
pub mod information;
pub mod likelihood;
pub mod posterior;

pub use estimator::{Estimate, EstimationError, Estimator, EstimatorOptions, GroupChoice, Status};
pub use grid::ThrustScaleAxis;
pub use likelihood::Measurement;
