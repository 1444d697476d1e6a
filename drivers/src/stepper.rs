//! One robot's rail axis on a TMC2209: the rack and pinion turn metres of arc into
//! microsteps; the axis follows the commanded position (`shared`'s trapezoidal rail profiles,
//! sampled each update) by velocity (`VACTUAL`), and keeps its own arc length from the
//! velocities it actually commanded, as the driver has no position counter over UART. A
//! StallGuard monitor turns a run of low `SG_RESULT` readings at speed into a stall.

use shared::math;
use shared::rail::stepper::DriveConfig;

use crate::tmc2209;

/// An axis: its drive train (`shared`'s, which turns metres into microsteps) and its top
/// speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisConfig {
    /// Motor steps, microsteps and pinion.
    pub drive: DriveConfig,
    /// Fastest the axis may move, m/s.
    pub max_speed_m_s: f32,
}

/// A robot's axis: where it is (by the commanded velocities) and what to command next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RailAxis {
    config: AxisConfig,
    position_m: f32,
    vactual: i32,
}

impl RailAxis {
    /// An axis at `position_m`, stopped.
    pub fn new(config: AxisConfig, position_m: f32) -> Self {
        Self {
            config,
            position_m,
            vactual: 0,
        }
    }

    /// The arc length the axis has reached, m.
    pub fn position_m(&self) -> f32 {
        self.position_m
    }

    /// The last `VACTUAL` commanded.
    pub fn vactual(&self) -> i32 {
        self.vactual
    }

    /// One update of `dt` seconds towards `target_m` (the profile's position at the end of
    /// the update): the `VACTUAL` that arrives there, limited to the axis's top speed and
    /// quantised to the driver's unit. The axis's arc length moves by what that `VACTUAL`
    /// really runs, so quantisation never accumulates: the next update makes it up. A
    /// non-finite target or `dt` stops the axis.
    pub fn update(&mut self, target_m: f32, dt: f32) -> i32 {
        if !(target_m.is_finite() && dt.is_finite() && dt > 0.0) {
            self.vactual = 0;
            return 0;
        }
        let per_m = self.config.drive.steps_per_metre();
        let limit = math::abs(self.config.max_speed_m_s);
        let speed = math::clamp((target_m - self.position_m) / dt, -limit, limit);
        self.vactual = tmc2209::vactual(speed * per_m);
        self.position_m += tmc2209::velocity_of(self.vactual) / per_m * dt;
        self.vactual
    }

    /// Stops the axis (the arc length stays where it is).
    pub fn stop(&mut self) {
        self.vactual = 0;
    }
}

/// StallGuard4 stall detection: the motor is stalled when `SG_RESULT <= 2 * SGTHRS` (datasheet
/// section 11) for `needed` readings in a row while it runs fast enough for StallGuard.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StallMonitor {
    threshold: u8,
    needed: u8,
    min_microsteps_per_s: f32,
    run: u8,
}

impl StallMonitor {
    /// A monitor with `SGTHRS` `threshold`, `needed` low readings in a row, and StallGuard
    /// trusted above `min_microsteps_per_s`.
    pub const fn new(threshold: u8, needed: u8, min_microsteps_per_s: f32) -> Self {
        Self {
            threshold,
            needed: if needed < 1 { 1 } else { needed },
            min_microsteps_per_s,
            run: 0,
        }
    }

    /// One `SG_RESULT` reading taken while the axis runs at `vactual`: whether it is stalled.
    pub fn update(&mut self, sg_result: u32, vactual: i32) -> bool {
        let fast = math::abs(tmc2209::velocity_of(vactual)) >= self.min_microsteps_per_s;
        if fast && sg_result <= 2 * u32::from(self.threshold) {
            self.run = self.run.saturating_add(1);
        } else {
            self.run = 0;
        }
        self.run >= self.needed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 200 steps, 16 microsteps, a 20 mm pinion: 3200 microsteps per 62.83 mm of arc.
    const CONFIG: AxisConfig = AxisConfig {
        drive: DriveConfig {
            steps_per_rev: 200,
            microsteps: 16,
            pinion_pitch_diameter: 0.020,
        },
        max_speed_m_s: 0.2,
    };

    #[test]
    fn microsteps_per_metre_by_hand() {
        assert!((CONFIG.drive.steps_per_metre() - 50_929.58).abs() < 0.1);
    }

    /// A trapezoid of 0.3 m (accelerate 0.5 m/s^2 to 0.1 m/s), sampled at 50 Hz: the axis's
    /// arc length follows it within a microstep and ends on it.
    #[test]
    fn follows_a_trapezoid_without_drift() {
        let mut axis = RailAxis::new(CONFIG, 1.0);
        let (accel, cruise, length) = (0.5f32, 0.1f32, 0.3f32);
        let t_ramp = cruise / accel;
        let t_cruise = (length - cruise * t_ramp) / cruise;
        let total = 2.0 * t_ramp + t_cruise;
        let profile = |t: f32| -> f32 {
            let t = t.clamp(0.0, total);
            let s = if t < t_ramp {
                0.5 * accel * t * t
            } else if t < t_ramp + t_cruise {
                0.5 * accel * t_ramp * t_ramp + cruise * (t - t_ramp)
            } else {
                let r = total - t;
                length - 0.5 * accel * r * r
            };
            1.0 + s
        };
        let dt = 0.02;
        let microstep = 1.0 / CONFIG.drive.steps_per_metre();
        for k in 1..=250 {
            let t = k as f32 * dt;
            axis.update(profile(t), dt);
            assert!(
                (axis.position_m() - profile(t)).abs() < 2.0 * microstep,
                "at {t} s"
            );
        }
        assert!((axis.position_m() - 1.3).abs() < microstep);
        assert!(
            axis.vactual().abs() <= 1,
            "at rest at the end: {}",
            axis.vactual()
        );
    }

    #[test]
    fn speed_is_limited_and_bad_targets_stop() {
        let mut axis = RailAxis::new(CONFIG, 0.0);
        let v = axis.update(5.0, 0.02);
        let expected = tmc2209::vactual(0.2 * CONFIG.drive.steps_per_metre());
        assert_eq!(v, expected);
        assert!((axis.position_m() - 0.004).abs() < 1e-5);
        assert_eq!(axis.update(f32::NAN, 0.02), 0);
        assert_eq!(axis.update(1.0, 0.0), 0);
    }

    #[test]
    fn a_stall_needs_low_readings_in_a_row_at_speed() {
        let mut stall = StallMonitor::new(50, 3, 500.0);
        let fast = tmc2209::vactual(2000.0);
        assert!(!stall.update(90, fast));
        assert!(!stall.update(100, fast));
        assert!(!stall.update(101, fast), "above 2 x SGTHRS");
        assert!(!stall.update(40, fast));
        assert!(!stall.update(40, fast));
        assert!(stall.update(40, fast), "the third in a row");
        // Slow moves never count: StallGuard does not work there.
        let mut slow = StallMonitor::new(50, 1, 500.0);
        assert!(!slow.update(0, tmc2209::vactual(100.0)));
        assert!(slow.update(0, fast));
    }
}
