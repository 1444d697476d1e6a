//! The robots on the rail (SPEC.md section 1; section 2, steps 1.2 and 3): the stepper drive
//! and its motion profiles, and moves of all robots that keep their order and spacing.

pub mod moves;
pub mod stepper;
