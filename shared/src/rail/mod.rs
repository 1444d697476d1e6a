//! The robots on the rail (docs/models.md#rail-moves): the stepper drive
//! and its motion profiles, and moves of all robots that keep their order and spacing.

pub mod moves;
pub mod stepper;
