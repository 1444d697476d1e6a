//! PID with derivative on the measurement through a first-order low-pass, a clamped integral
//! that only runs when allowed (anti-windup), and an output limit (docs/models.md#flight-cascade).

use crate::control::vector::Vec3;
use crate::math;

/// One PID axis.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pid {
    /// Proportional gain.
    pub kp: f32,
    /// Integral gain.
    pub ki: f32,
    /// Derivative gain (on the measurement).
    pub kd: f32,
    /// Bound on the integral's contribution.
    pub integral_limit: f32,
    /// Bound on the output.
    pub output_limit: f32,
    /// Derivative low-pass cut-off, Hz.
    pub d_cutoff_hz: f32,
    integral: f32,
    derivative: f32,
    last_measurement: Option<f32>,
}

impl Pid {
    /// A PID with the given gains and limits, at rest.
    pub fn new(
        kp: f32,
        ki: f32,
        kd: f32,
        integral_limit: f32,
        output_limit: f32,
        d_cutoff_hz: f32,
    ) -> Self {
        Self {
            kp,
            ki,
            kd,
            integral_limit,
            output_limit,
            d_cutoff_hz,
            ..Self::default()
        }
    }

    /// One step: `integrate` false freezes the integral (on the ground, or while the output it
    /// feeds is saturated).
    pub fn step(&mut self, setpoint: f32, measurement: f32, dt: f32, integrate: bool) -> f32 {
        let error = setpoint - measurement;
        if dt > 0.0 {
            if let Some(last) = self.last_measurement {
                let raw = -(measurement - last) / dt;
                let tau = 1.0 / (core::f32::consts::TAU * math::max(self.d_cutoff_hz, 1e-3));
                let alpha = dt / (dt + tau);
                self.derivative += alpha * (raw - self.derivative);
            }
            if integrate {
                self.integral = math::clamp(
                    self.integral + self.ki * error * dt,
                    -self.integral_limit,
                    self.integral_limit,
                );
            }
        }
        self.last_measurement = Some(measurement);
        math::clamp(
            self.kp * error + self.integral + self.kd * self.derivative,
            -self.output_limit,
            self.output_limit,
        )
    }

    /// The integral's current contribution.
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// Back to rest: integral and derivative cleared.
    pub fn reset(&mut self) {
        self.integral = 0.0;
        self.derivative = 0.0;
        self.last_measurement = None;
    }
}

/// Three PID axes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pid3 {
    /// x, y, z (or roll, pitch, yaw).
    pub axes: [Pid; 3],
}

impl Pid3 {
    /// Three axes from per-axis gains and limits.
    pub fn new(
        kp: Vec3,
        ki: Vec3,
        kd: Vec3,
        integral_limit: Vec3,
        output_limit: Vec3,
        d_cutoff_hz: f32,
    ) -> Self {
        let (kp, ki, kd) = (kp.to_array(), ki.to_array(), kd.to_array());
        let (il, ol) = (integral_limit.to_array(), output_limit.to_array());
        Self {
            axes: [0, 1, 2].map(|a| Pid::new(kp[a], ki[a], kd[a], il[a], ol[a], d_cutoff_hz)),
        }
    }

    /// One step of every axis; `integrate[a]` false freezes axis `a`'s integral.
    pub fn step(
        &mut self,
        setpoint: Vec3,
        measurement: Vec3,
        dt: f32,
        integrate: [bool; 3],
    ) -> Vec3 {
        let (s, m) = (setpoint.to_array(), measurement.to_array());
        let mut out = [0.0; 3];
        for a in 0..3 {
            out[a] = self.axes[a].step(s[a], m[a], dt, integrate[a]);
        }
        Vec3::from_array(out)
    }

    /// Every axis back to rest.
    pub fn reset(&mut self) {
        self.axes.iter_mut().for_each(Pid::reset);
    }

    /// The integrals' contributions.
    pub fn integral(&self) -> Vec3 {
        Vec3::from_array(self.axes.map(|a| a.integral()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// First-order plant `x' = u`: a PI loop settles on the setpoint without overshooting past
    /// its limit, and a frozen integral stays where it was.
    #[test]
    fn pi_loop_settles_and_frozen_integral_does_not_wind_up() {
        let mut pid = Pid::new(2.0, 1.0, 0.0, 5.0, 10.0, 20.0);
        let (mut x, dt) = (0.0f32, 0.0025);
        for _ in 0..4000 {
            let u = pid.step(1.0, x, dt, true);
            x += (u - 0.5) * dt; // constant disturbance the integral must cancel
        }
        assert!((x - 1.0).abs() < 1e-3, "{x}");
        assert!((pid.integral() - 0.5).abs() < 1e-2, "{}", pid.integral());

        let mut grounded = Pid::new(2.0, 1.0, 0.0, 5.0, 10.0, 20.0);
        for _ in 0..4000 {
            grounded.step(1.0, 0.0, dt, false); // sitting on the ground: error persists
        }
        assert_eq!(grounded.integral(), 0.0);
        let mut windup = Pid::new(2.0, 1.0, 0.0, 0.3, 10.0, 20.0);
        for _ in 0..4000 {
            windup.step(1.0, 0.0, dt, true);
        }
        assert!((windup.integral() - 0.3).abs() < 1e-6, "integral clamped");
    }

    #[test]
    fn derivative_acts_on_the_measurement_not_on_setpoint_steps() {
        let mut pid = Pid::new(0.0, 0.0, 1.0, 1.0, 100.0, 1000.0);
        pid.step(0.0, 0.0, 0.0025, true);
        assert_eq!(
            pid.step(5.0, 0.0, 0.0025, true),
            0.0,
            "no kick on a setpoint step"
        );
        let out = pid.step(5.0, 0.01, 0.0025, true);
        assert!(out < 0.0, "a rising measurement damps: {out}");
    }
}
