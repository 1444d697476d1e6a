//! Faults for `campaign --faults` (docs/commands.md#campaign): about half the trials get one
//! fault, drawn from the injections `mission --inject` has (docs/failures.md#failures), and
//! what the vehicle must answer it with. A faulted trial that stops or lands for its fault's
//! reason has found it, as has one that said it met the fault while it already landed; one
//! that aborts for another reason, or not at all, has missed it.

use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use shared::mission::AbortReason;

use crate::inject::{Fault, Injection, Since};

/// The share of trials that get a fault.
pub const FAULT_SHARE: f64 = 0.5;
/// When an in-flight fault comes, s after take-off began (the flight lasts some 17 s: take-off,
/// transit, hover, landing from about 13.5 s).
pub const FAULT_AFTER: [f32; 2] = [1.0, 12.0];
/// An IMU's noise, times the simulated sensor's (docs/failures.md: 20 and above is flagged).
pub const IMU_NOISE: [f32; 2] = [20.0, 1000.0];
/// The pack's voltage after a drop, V: below `BAT_CRIT_V` (13.2 V), the vehicle lands in place.
pub const BATTERY_VOLTS: [f32; 2] = [10.0, 13.0];

/// The kinds drawn, each as `--inject` names it.
pub const KINDS: [&str; 7] = [
    "rotor-out",
    "imu-stuck",
    "imu-noise",
    "mocap-loss",
    "gcs-loss",
    "battery",
    "stepper-stall",
];

/// The kind of `fault`, as `--inject` names it.
pub fn kind(fault: &Fault) -> &'static str {
    match fault {
        Fault::LoadShift(_) => "load-shift",
        Fault::StepperStall(_) => "stepper-stall",
        Fault::ImuStuck => "imu-stuck",
        Fault::ImuNoise(_) => "imu-noise",
        Fault::GcsLoss => "gcs-loss",
        Fault::Battery(_) => "battery",
        Fault::RotorOut(_) => "rotor-out",
        Fault::RotorFade(..) => "rotor-fade",
        Fault::MocapLoss => "mocap-loss",
    }
}

/// A fault for a vehicle of `robots` robots, or none (with probability `1 - FAULT_SHARE`).
pub fn draw(rng: &mut ChaCha8Rng, robots: usize) -> Option<Injection> {
    if !rng.random_bool(FAULT_SHARE) {
        return None;
    }
    let robot = rng.random_range(0..robots.max(1));
    let after = (rng.random_range(FAULT_AFTER[0]..=FAULT_AFTER[1]) * 10.0).round() / 10.0;
    let fault = match KINDS[rng.random_range(0..KINDS.len())] {
        "rotor-out" => Fault::RotorOut(robot),
        "imu-stuck" => Fault::ImuStuck,
        "imu-noise" => Fault::ImuNoise(rng.random_range(IMU_NOISE[0]..=IMU_NOISE[1]).round()),
        "mocap-loss" => Fault::MocapLoss,
        "gcs-loss" => Fault::GcsLoss,
        "battery" => Fault::Battery(
            (rng.random_range(BATTERY_VOLTS[0]..=BATTERY_VOLTS[1]) * 10.0).round() / 10.0,
        ),
        _ => Fault::StepperStall(robot),
    };
    let after = if matches!(fault, Fault::StepperStall(_)) {
        0.0
    } else {
        after
    };
    Some(Injection {
        fault,
        after,
        since: Since::Takeoff,
    })
}

/// Whether `reason` is the vehicle's answer to `fault`.
pub fn found(fault: &Fault, reason: &AbortReason) -> bool {
    match fault {
        Fault::RotorOut(_) | Fault::RotorFade(..) => matches!(reason, AbortReason::RotorOut { .. }),
        Fault::ImuStuck => matches!(reason, AbortReason::ImuStuck | AbortReason::ImuFault),
        Fault::ImuNoise(_) => matches!(reason, AbortReason::ImuNoisy | AbortReason::ImuFault),
        Fault::MocapLoss => matches!(reason, AbortReason::PositionLost),
        Fault::GcsLoss => matches!(reason, AbortReason::GcsLost),
        Fault::Battery(_) => matches!(
            reason,
            AbortReason::BatteryCritical { .. } | AbortReason::BatteryLow { .. }
        ),
        Fault::StepperStall(_) => matches!(reason, AbortReason::RobotStalled { .. }),
        // A shifted load is answered by re-forming in flight, not by stopping.
        Fault::LoadShift(_) => false,
    }
}

/// Whether the vehicle said it met `fault` in `notice` (a text it sent): a ground link or a
/// pack lost while the vehicle already lands is said, and the landing goes on (no abort: the
/// failsafe's answer is the landing under way).
pub fn said(fault: &Fault, notice: &str) -> bool {
    match fault {
        Fault::GcsLoss => notice.starts_with("ground link lost"),
        Fault::Battery(_) => notice.starts_with("battery critical"),
        _ => false,
    }
}
