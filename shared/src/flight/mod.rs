//! The flight stack (docs/system.md#flight): everything between a chosen formation and
//! the rotors, as one component that the mission, the simulator's `fly`, the benchmarks and
//! the firmware all step the same way.
//!
//! - [`model`]: the vehicle model and the mixer built from a formation and an estimate (a
//!   matrix inverse: built once, off the control tick).
//! - [`stack`]: the 400 Hz flight: cascade, mixer, plan walked on the vehicle's state,
//!   take-off check, land detector, failsafes and the operator's land and kill commands.
//! - [`manual`]: Position mode's setpoint, steered by a person's sticks.
//! - [`trim`]: the payload's COM and mass from the wrench that holds it in a hover.
//! - [`adapt`]: the formation re-solved and the robots moved in flight when the load shifts.
//! - [`route`]: a ground station's mission items in the local frame, checked.
//! - [`rotor_monitor`]: rotors that stop or fade in flight, found from the vehicle's response
//!   and the ESCs' RPM; [`rotor_isolation`]: which one or two rotors a change is;
//!   [`rotor_findings`]: the ESCs' word and the rotors found stopped.

pub mod adapt;
pub mod manual;
pub mod model;
pub mod rotor_findings;
pub mod rotor_isolation;
pub mod rotor_monitor;
pub mod route;
pub mod stack;
pub mod trim;

pub use adapt::{AdaptConfig, AdaptEvent, Adapter};
pub use manual::{ManualLimits, ManualSetpoint, ManualVelocity};
pub use model::FlightModel;
pub use rotor_monitor::{RotorMonitor, RotorMonitorConfig};
pub use route::{Route, RouteError, RouteItem, RoutePoint, RouteProblem};
pub use stack::{
    CascadeSetpoints, EscTelemetry, FlightCommand, FlightConfig, FlightEvent, FlightOutput,
    FlightStack, FlightStop, LandingCause, RotorOut,
};
