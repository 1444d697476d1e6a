//! What the flight stack learns of its rotors in flight (docs/failures.md#rotors-that-stop-in-flight):
//! the ESCs' word each tick, and the rotors found stopped, by the ESCs or the rotor monitor.

/// What the ESCs tell of their rotors this tick.
#[derive(Clone, Copy, Debug, Default)]
pub struct EscTelemetry<'a> {
    /// Each rotor's RPM (NaN where a rotor has no reading), or `None` without telemetry.
    pub rpm: Option<&'a [f32]>,
    /// Each RPM is the ESC's latest message, held between messages slower than the tick
    /// (DroneCAN): one low message confirms ([`super::rotor_monitor::MonitorInput::rpm_per_message`]).
    pub rpm_per_message: bool,
    /// Rotors whose ESC reports them stopped while commanded to turn, bit `i` for rotor `i`.
    pub stopped: u16,
}

/// A rotor found stopped in flight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotorOut {
    /// The robot whose rotor stopped, from 0.
    pub robot: u8,
    /// When it was found, s since the flight began ([`crate::flight::FlightStack::clock`]).
    pub at: f32,
    /// Its ESC reported it (rather than the monitor finding it).
    pub reported: bool,
}

/// What one tick found of the rotors: the rotors newly found stopped. Whether the rotors left
/// hold a level hover is the full mixer's to say ([`crate::control::allocation::Mixer::holds_hover`],
/// with the job that builds it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotorFinding {
    /// The first rotor newly found.
    pub first: RotorOut,
    /// Every rotor newly found this tick, bit `i` for robot `i`.
    pub newly: u16,
    /// Every rotor flown without now (these and earlier ones).
    pub out: u16,
    /// Rotors left turning.
    pub left: u8,
}

/// Rotors found stopped that a flight records (the first two: a third is flown without as
/// well, but not recorded).
pub(crate) const MAX_ROTORS_OUT: usize = 2;
