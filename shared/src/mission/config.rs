//! Everything the mission may be tuned with beyond the scenario (docs/system.md#mission-phases),
//! with the defaults the simulated vehicle was characterised with.

use crate::control::allocation::MixerKind;
use crate::estimation::EstimatorOptions;
use crate::flight::{AdaptConfig, FlightConfig};
use crate::liftoff_detector::LiftoffConfig;
use crate::manual::ManualConfig;
use crate::mission::bringup::SensorOffsets;
use crate::mission::hardware::HardwareConfig;
use crate::mission::supervision::SupervisionConfig;
use crate::rail::stepper::MotionLimits;

/// Default standard deviation of a lift reading, N (see [`MissionConfig::lift_noise_sigma`]).
pub const DETECTOR_SIGMA: f32 = 0.5;

/// The mission's tuning.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MissionConfig {
    /// Estimator options (the thrust-scale bias term).
    pub estimator: EstimatorOptions,
    /// Standard deviation of a lift reading from this vehicle's detector, N: the estimator's
    /// noise model for the lifts. `None` uses the scenario's `noise_sigma` (the paper's
    /// simulated measurement noise). A real vehicle sets it from bench lifts of a known load.
    /// The default, 0.5 N, bounds what the detector showed in the simulated vehicle: 63 lifts
    /// over 18 missions read the model's lift-off with an RMS error of 0.14 N, worst 0.77 N.
    pub lift_noise_sigma: Option<f32>,
    /// Lift-off detection.
    pub liftoff: LiftoffConfig,
    /// Rail motion limits.
    pub rail_limits: MotionLimits,
    /// The flight: gains, plan, nets.
    pub flight: FlightConfig,
    /// Mixer for the flight.
    pub mixer: MixerKind,
    /// The formation's adaptation in flight to a load that shifts.
    pub adapt: AdaptConfig,
    /// Largest share of the rotors' total thrust the heaviest plausible payload (the
    /// posterior's 95 % upper bound on the mass) may need to hover; above it the mission
    /// refuses to take off.
    pub max_hover_fraction: f32,
    /// Refuse a formation that cannot hold the flight's design torque about every axis
    /// (docs/failures.md#refused-before-take-off). Off only to show what such a formation
    /// does (the campaign flies a sample of the refused so).
    pub refuse_weak_formation: bool,
    /// Time on the ground, rotors off, before the estimation starts (the attitude estimator
    /// learns the gyro bias meanwhile), s.
    pub checks_time: f32,
    /// Time with rotors off after each lift, s.
    pub relax_time: f32,
    /// Consecutive lifts after which the stopping rule must hold before the estimate is taken
    /// (1: the paper's rule; 2: one confirmation lift after it first holds).
    pub confirmations: u32,
    /// Time armed on the ground before take-off, s.
    pub arm_time: f32,
    /// The drivers' settings (not used by the mission itself).
    pub hardware: HardwareConfig,
    /// The ground link's and the battery's failsafes.
    pub supervision: SupervisionConfig,
    /// The IMU's calibrated offsets, taken off every sample (docs/ground-link.md#bring-up-commands).
    pub sensors: SensorOffsets,
    /// Manual control: its sources, the kill switch, the modes, its loss (docs/manual-control.md).
    pub manual: ManualConfig,
}

impl MissionConfig {
    /// The defaults the simulated vehicle was characterised with.
    pub const DEFAULT: Self = Self {
        estimator: EstimatorOptions { thrust_scale: None },
        lift_noise_sigma: Some(DETECTOR_SIGMA),
        liftoff: LiftoffConfig::DEFAULT,
        rail_limits: MotionLimits::DEFAULT,
        flight: FlightConfig::DEFAULT,
        mixer: MixerKind::EqualSplit,
        adapt: AdaptConfig::DEFAULT,
        max_hover_fraction: 0.7,
        refuse_weak_formation: true,
        checks_time: 5.0,
        relax_time: 2.0,
        confirmations: 1,
        arm_time: 1.0,
        hardware: HardwareConfig::DEFAULT,
        supervision: SupervisionConfig::DEFAULT,
        sensors: SensorOffsets::ZERO,
        manual: ManualConfig::DEFAULT,
    };
}

impl Default for MissionConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}
