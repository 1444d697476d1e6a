//! The cascaded flight controller at 400 Hz (docs/models.md#flight-cascade): position (P) ->
//! velocity (PID) -> attitude (quaternion P, tilt before yaw) -> body rate (PID), with gravity
//! compensation from the estimated mass and torques scaled by the estimated inertia.
//!
//! Integrators run only while the vehicle is airborne and the axis they feed was not cut by
//! the allocation on the previous step (anti-windup), so nothing winds up while the payload
//! still sits on the ground. No allocation and no matrix inverse happen here.

use crate::control::allocation::{Saturation, Wrench};
use crate::control::attitude_estimator::AttitudeState;
use crate::control::params::ControlParams;
use crate::control::pid::Pid3;
use crate::control::position_estimator::PositionState;
use crate::control::trajectory::Setpoint;
use crate::control::vector::{Quat, Vec3};
use crate::control::vehicle::VehicleModel;
use crate::math;
use crate::scenario::GRAVITY;

/// What the controller needs each step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlInputs {
    /// The reference to follow.
    pub setpoint: Setpoint,
    /// Attitude and rate estimate.
    pub attitude: AttitudeState,
    /// Position and velocity estimate.
    pub position: PositionState,
    /// False while the payload still rests on the ground: integrators hold.
    pub airborne: bool,
    /// What the allocation cut on the previous step.
    pub saturation: Saturation,
}

/// What the controller commands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlOutput {
    /// Collective thrust and body torque for the allocation.
    pub wrench: Wrench,
    /// Attitude the vehicle should have.
    pub attitude_setpoint: Quat,
    /// Body rate the vehicle should have, rad/s.
    pub rate_setpoint: Vec3,
    /// Acceleration asked of the vehicle, world NED, m/s^2.
    pub acceleration_setpoint: Vec3,
}

/// The cascade's state.
#[derive(Clone, Debug, PartialEq)]
pub struct FlightController {
    params: ControlParams,
    model: VehicleModel,
    velocity: Pid3,
    rate: Pid3,
    /// `tan(max_tilt)`, computed once (trigonometry is costly on the target).
    tan_max_tilt: f32,
    /// The last yaw setpoint and its cosine and sine.
    heading: (f32, f32, f32),
}

impl FlightController {
    /// A controller with `params` for the vehicle `model`, at rest.
    pub fn new(params: ControlParams, model: VehicleModel) -> Self {
        let p = params;
        let big = Vec3::new(2.0 * GRAVITY, 2.0 * GRAVITY, 2.0 * GRAVITY);
        Self {
            velocity: Pid3::new(
                p.velocity_p,
                p.velocity_i,
                p.velocity_d,
                p.velocity_integral_limit,
                big,
                p.velocity_d_cutoff_hz,
            ),
            rate: Pid3::new(
                p.rate_p,
                p.rate_i,
                p.rate_d,
                p.rate_integral_limit,
                p.max_angular_acceleration,
                p.rate_d_cutoff_hz,
            ),
            tan_max_tilt: math::sin(params.max_tilt) / math::cos(params.max_tilt),
            heading: (0.0, 1.0, 0.0),
            params,
            model,
        }
    }

    /// The vehicle model in use.
    pub fn model(&self) -> &VehicleModel {
        &self.model
    }

    /// A new vehicle model (after estimation, or when the formation changes).
    pub fn set_model(&mut self, model: VehicleModel) {
        self.model = model;
    }

    /// Clears every integrator and filter (before a take-off).
    pub fn reset(&mut self) {
        self.velocity.reset();
        self.rate.reset();
    }

    /// The velocity loop's integral (m/s^2), for logs and tests.
    pub fn velocity_integral(&self) -> Vec3 {
        self.velocity.integral()
    }

    /// The rate loop's integral (rad/s^2), for logs and tests.
    pub fn rate_integral(&self) -> Vec3 {
        self.rate.integral()
    }

    /// One step of the cascade, `dt` seconds after the previous one.
    pub fn step(&mut self, inputs: &ControlInputs, dt: f32) -> ControlOutput {
        let p = &self.params;
        let sp = &inputs.setpoint;
        let (position, velocity) = (inputs.position.position, inputs.position.velocity);
        let air = inputs.airborne;
        let sat = inputs.saturation;

        // Position -> velocity.
        let mut velocity_sp = sp.velocity + (sp.position - position).component_mul(p.position_p);
        let horizontal = Vec3::new(velocity_sp.x, velocity_sp.y, 0.0).limit_norm(p.max_speed_xy);
        velocity_sp = Vec3::new(
            horizontal.x,
            horizontal.y,
            math::clamp(velocity_sp.z, -p.max_speed_z, p.max_speed_z),
        );

        // Velocity -> acceleration (NED), gravity compensated below.
        let integrate_xy = air && !sat.roll_pitch;
        let integrate_z = air && !sat.collective;
        let mut acceleration = sp.acceleration
            + self.velocity.step(
                velocity_sp,
                velocity,
                dt,
                [integrate_xy, integrate_xy, integrate_z],
            );

        // Specific force the rotors must make: f = a - g (NED), at most max_tilt from vertical
        // and always pushing up a little.
        let mut f = acceleration - Vec3::DOWN * GRAVITY;
        f.z = math::min(f.z, -0.1 * GRAVITY);
        let max_xy = -f.z * self.tan_max_tilt;
        let fxy = Vec3::new(f.x, f.y, 0.0).limit_norm(max_xy);
        f = Vec3::new(fxy.x, fxy.y, f.z);
        acceleration = f + Vec3::DOWN * GRAVITY;
        let force = f * self.model.mass;

        // Attitude setpoint: body z along -force, heading from the setpoint's yaw.
        let z_body = (-force).normalized();
        if sp.yaw != self.heading.0 {
            self.heading = (sp.yaw, math::cos(sp.yaw), math::sin(sp.yaw));
        }
        let heading = Vec3::new(self.heading.1, self.heading.2, 0.0);
        let y_body = z_body.cross(heading).normalized();
        let x_body = y_body.cross(z_body);
        let attitude_sp = Quat::from_axes(x_body, y_body, z_body);

        // Collective: the force's component along the current body up axis.
        let q = inputs.attitude.attitude;
        let up_now = -q.rotate(Vec3::DOWN);
        let max_collective = p.max_collective_fraction * self.model.max_total_thrust;
        let thrust = math::clamp(force.dot(up_now), 0.0, max_collective);

        let rate_sp = self.attitude_rate_setpoint(q, attitude_sp);

        // Rate -> angular acceleration -> torque through the inertia (with the gyroscopic term).
        let rate = inputs.attitude.rate;
        let integrate_rate = [
            air && !sat.roll_pitch,
            air && !sat.roll_pitch,
            air && !sat.yaw,
        ];
        let alpha = self.rate.step(rate_sp, rate, dt, integrate_rate);
        let inertia = self.model.inertia;
        let torque = alpha.component_mul(inertia) + rate.cross(rate.component_mul(inertia));

        ControlOutput {
            wrench: Wrench { thrust, torque },
            attitude_setpoint: attitude_sp,
            rate_setpoint: rate_sp,
            acceleration_setpoint: acceleration,
        }
    }

    /// Quaternion P control with tilt before yaw: the full attitude error is replaced by the
    /// tilt that aligns the thrust axis plus only a share of the yaw error (the share is the
    /// ratio of the yaw gain to the roll gain). The share of the yaw rotation is taken by
    /// normalised linear interpolation from the identity (monotone, close to the exact slerp,
    /// and free of trigonometry).
    fn attitude_rate_setpoint(&self, q: Quat, q_sp: Quat) -> Vec3 {
        let p = &self.params;
        let e_z = q.rotate(Vec3::DOWN);
        let e_z_sp = q_sp.rotate(Vec3::DOWN);
        let tilt_only = Quat::between(e_z, e_z_sp) * q;
        let mut yaw_part = tilt_only.conjugate() * q_sp;
        if yaw_part.w < 0.0 {
            yaw_part = Quat {
                w: -yaw_part.w,
                x: -yaw_part.x,
                y: -yaw_part.y,
                z: -yaw_part.z,
            };
        }
        let share = if p.attitude_p.x > 0.0 {
            math::clamp(p.attitude_p.z / p.attitude_p.x, 0.0, 1.0)
        } else {
            0.0
        };
        let reduced_yaw = Quat {
            w: 1.0 - share + share * yaw_part.w,
            x: 0.0,
            y: 0.0,
            z: share * yaw_part.z,
        }
        .normalized();
        let target = tilt_only * reduced_yaw;
        let error = q.conjugate() * target;
        let sign = if error.w < 0.0 { -1.0 } else { 1.0 };
        let e = error.vector() * (2.0 * sign);
        let gain = Vec3::new(p.attitude_p.x, p.attitude_p.y, p.attitude_p.x);
        e.component_mul(gain).clamp_each(p.max_rate)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::allocation::{Mixer, MixerKind, RotorLayout};
    use crate::geometry::Vec2;

    const POINTS: [Vec2; 8] = crate::paper::RECT_ROTORS;
    const SPIN: [i8; 8] = crate::paper::ALTERNATING_SPIN;

    /// A rigid body with eight lagging rotors, perfect state feedback, 400 Hz control.
    struct Bench {
        controller: FlightController,
        mixer: Mixer,
        model: VehicleModel,
        position: Vec3,
        velocity: Vec3,
        attitude: Quat,
        rate: Vec3,
        thrusts: [f32; 8],
        saturation: Saturation,
        max_tilt: f32,
    }

    impl Bench {
        fn new(com: Vec2) -> Self {
            let footprint = [
                Vec2::new(-0.88, -0.1),
                Vec2::new(0.88, -0.1),
                Vec2::new(0.88, 0.1),
                Vec2::new(-0.88, 0.1),
            ];
            let model = VehicleModel::from_payload(&footprint, com, 3.5, &POINTS, 0.1, 14.2);
            let layout = RotorLayout {
                points: &POINTS,
                spin: &SPIN,
                com,
                torque_per_thrust: 0.016,
                max_thrust: 14.2,
            };
            let mixer = Mixer::build(MixerKind::Allocation, &layout).unwrap();
            let hover = mixer.allocate(&Wrench {
                thrust: model.hover_thrust(),
                torque: Vec3::ZERO,
            });
            let mut thrusts = [0.0; 8];
            thrusts.copy_from_slice(&hover.thrusts[..8]);
            Self {
                controller: FlightController::new(ControlParams::default(), model),
                mixer,
                model,
                position: Vec3::new(0.0, 0.0, -1.0),
                velocity: Vec3::ZERO,
                attitude: Quat::IDENTITY,
                rate: Vec3::ZERO,
                thrusts,
                saturation: Saturation::default(),
                max_tilt: 0.0,
            }
        }

        /// Runs `seconds` towards `setpoint` with a body disturbance torque.
        fn run(&mut self, setpoint: Setpoint, seconds: f32, disturbance: Vec3) {
            let dt = 0.0025;
            for _ in 0..(seconds / dt) as usize {
                let inputs = ControlInputs {
                    setpoint,
                    attitude: AttitudeState {
                        attitude: self.attitude,
                        rate: self.rate,
                        gyro_bias: Vec3::ZERO,
                    },
                    position: PositionState {
                        position: self.position,
                        velocity: self.velocity,
                        valid: true,
                    },
                    airborne: true,
                    saturation: self.saturation,
                };
                let out = self.controller.step(&inputs, dt);
                let alloc = self.mixer.allocate(&out.wrench);
                self.saturation = alloc.saturation;
                // Physics at 2 kHz with a 20 ms motor lag.
                for _ in 0..5 {
                    let h = dt / 5.0;
                    for i in 0..8 {
                        self.thrusts[i] += (alloc.thrusts[i] - self.thrusts[i]) * (h / 0.02);
                    }
                    let w = self.mixer.wrench_of(&self.thrusts);
                    let force = self.attitude.rotate(Vec3::new(0.0, 0.0, -w.thrust))
                        + Vec3::DOWN * (GRAVITY * self.model.mass);
                    self.velocity += force * (h / self.model.mass);
                    self.position += self.velocity * h;
                    let i = self.model.inertia;
                    let torque =
                        w.torque + disturbance - self.rate.cross(self.rate.component_mul(i));
                    self.rate += Vec3::new(torque.x / i.x, torque.y / i.y, torque.z / i.z) * h;
                    self.attitude =
                        (self.attitude * Quat::from_rotation_vector(self.rate * h)).normalized();
                }
                let tilt = math::acos(self.attitude.rotate(Vec3::DOWN).z);
                self.max_tilt = self.max_tilt.max(tilt);
            }
        }
    }

    #[test]
    fn position_step_settles_without_large_overshoot() {
        let mut bench = Bench::new(Vec2::new(0.1, 0.0));
        let target = Vec3::new(1.0, -0.5, -1.5);
        let setpoint = Setpoint {
            position: target,
            yaw: 0.3,
            ..Setpoint::default()
        };
        let mut worst_overshoot = 0.0f32;
        for _ in 0..40 {
            bench.run(setpoint, 0.25, Vec3::ZERO);
            // Overshoot: distance past the target along the step direction.
            let along = (bench.position - target).dot(Vec3::new(1.0, -0.5, -0.5).normalized());
            worst_overshoot = worst_overshoot.max(along);
        }
        assert!(
            (bench.position - target).norm() < 0.05,
            "{:?}",
            bench.position
        );
        std::println!(
            "step: final error {:.4} m, overshoot {worst_overshoot:.3} m, max tilt {:.3} rad",
            (bench.position - target).norm(),
            bench.max_tilt
        );
        assert!(worst_overshoot < 0.2, "overshoot {worst_overshoot}");
        assert!(bench.max_tilt < 0.35 + 0.1, "tilt {}", bench.max_tilt);
        let yaw = bench.attitude.to_euler().z;
        assert!((yaw - 0.3).abs() < 0.05, "yaw {yaw}");
    }

    #[test]
    fn integrators_cancel_a_constant_disturbance_torque() {
        let mut bench = Bench::new(Vec2::new(0.1, 0.0));
        let hold = Setpoint {
            position: Vec3::new(0.0, 0.0, -1.0),
            ..Setpoint::default()
        };
        bench.run(hold, 12.0, Vec3::new(0.3, -0.3, 0.05));
        assert!(
            (bench.position - hold.position).norm() < 0.05,
            "{:?}",
            bench.position
        );
        let tilt = math::acos(bench.attitude.rotate(Vec3::DOWN).z);
        assert!(tilt < 0.05, "level again: {tilt}");
        assert!(
            bench.controller.rate_integral().norm() > 0.5,
            "the integral took the load"
        );
    }

    #[test]
    fn nothing_winds_up_on_the_ground() {
        let model = Bench::new(Vec2::default()).model;
        let mut c = FlightController::new(ControlParams::default(), model);
        let inputs = ControlInputs {
            setpoint: Setpoint {
                position: Vec3::new(0.5, 0.0, -1.0),
                ..Setpoint::default()
            },
            attitude: AttitudeState {
                attitude: Quat::from_euler(0.05, 0.0, 0.0), // resting slightly tilted
                rate: Vec3::ZERO,
                gyro_bias: Vec3::ZERO,
            },
            position: PositionState {
                position: Vec3::ZERO,
                velocity: Vec3::ZERO,
                valid: true,
            },
            airborne: false,
            saturation: Saturation::default(),
        };
        for _ in 0..4000 {
            c.step(&inputs, 0.0025);
        }
        assert_eq!(c.velocity_integral(), Vec3::ZERO);
        assert_eq!(c.rate_integral(), Vec3::ZERO);
    }
}
