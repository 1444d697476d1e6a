//! The miniature world the mission's sans-IO tests fly in: a payload that tips when a lift
//! passes its true lift-off thrust (docs/models.md's lift-off model, through
//! `shared::liftoff_thrust`) and moves vertically as a point mass under the rotors' total
//! thrust, so a whole mission takes a few milliseconds. It feeds the mission IMU samples (the
//! truth with a little noise), a motion-capture fix every fourth tick, the drivers' faults,
//! the ground station's heartbeat and the battery, and takes the mission's outputs back.

use shared::control::navigator::{ImuSample, MocapFix};
use shared::control::vector::{Quat, Vec3};
use shared::geometry::Vec2;
use shared::liftoff_thrust::lift_off_thrust;
use shared::manual::ManualSamples;
use shared::mission::{HardwareFaults, OperatorCommand, Supervision, TickInput, TickOutput};
use shared::paper::{checked, rect_sim1};
use shared::scenario::{FlightSetup, GRAVITY, MAX_ROBOTS, Scenario, Truth};

/// The control period, us (400 Hz).
pub const DT_US: u64 = 2500;

/// rect-sim1 with its payload of `mass` kg (COM at (0.33, 0.01) m) and a flight straight up
/// to 0.5 m and back (the world has no horizontal motion).
pub fn straight_up_scenario(mass: f32) -> Scenario {
    let mut s = checked(rect_sim1());
    s.truth = Some(Truth {
        com: Vec2::new(0.33, 0.01),
        mass,
    });
    s.flight = Some(FlightSetup {
        target: [0.0, 0.0, 0.5],
        disturbance_torque: 0.0,
    });
    s
}

/// The world's state and what a test sets in it.
#[derive(Clone, Debug)]
pub struct World {
    scenario: Scenario,
    /// Height of the payload above the ground, m.
    pub height: f32,
    /// Vertical speed, m/s (up).
    pub speed: f32,
    /// Upward acceleration of the last tick, m/s^2 (the accelerometer reads it).
    pub climb: f32,
    /// Roll tilt from a lift, rad.
    pub tilt: f32,
    /// Its rate, rad/s.
    pub tilt_rate: f32,
    /// A roll rate the test drives whatever the rotors do (a payload rolling over), rad/s.
    pub forced_tilt_rate: Option<f32>,
    /// The rotors make `1 / map_error` of what is commanded.
    pub map_error: f32,
    /// Motion capture sees the payload.
    pub mocap: bool,
    /// Highest the payload can get (an obstacle above), m.
    pub ceiling: f32,
    /// What the drivers report.
    pub faults: HardwareFaults,
    /// The IMU repeats this sample instead of measuring.
    pub frozen_imu: Option<ImuSample>,
    /// The ground station's heartbeat comes every this many ticks, from the first.
    pub heartbeat_period: u64,
    /// ... and stops before this tick.
    pub gcs_until: u64,
    /// The battery's voltage, V (none: no battery monitor).
    pub battery: Option<f32>,
}

impl World {
    /// The payload of `scenario` at rest on the ground; every sensor working, the ground
    /// station's heartbeat once a second, no battery monitor.
    pub fn new(scenario: &Scenario) -> Self {
        Self {
            scenario: scenario.clone(),
            height: 0.0,
            speed: 0.0,
            climb: 0.0,
            tilt: 0.0,
            tilt_rate: 0.0,
            forced_tilt_rate: None,
            map_error: 1.0,
            mocap: true,
            ceiling: f32::INFINITY,
            faults: HardwareFaults::NONE,
            frozen_imu: None,
            heartbeat_period: 400,
            gcs_until: u64::MAX,
            battery: None,
        }
    }

    /// The IMU's sample at `tick`: the truth with a little noise (a real sensor never repeats
    /// itself; the mission's IMU monitor flags one that does).
    pub fn imu(&self, tick: u64) -> ImuSample {
        let attitude = Quat::from_euler(self.tilt, 0.0, 0.0);
        let accel = attitude.inverse_rotate(Vec3::new(0.0, 0.0, -GRAVITY - self.climb));
        let h = tick.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40;
        let dither = (h as f32 / (1u64 << 24) as f32 - 0.5) * 2e-3;
        ImuSample {
            gyro: Vec3::new(self.tilt_rate, 0.0, dither),
            accel,
        }
    }

    /// The mission's input at `tick`, with the operator's `command`.
    pub fn input(&self, tick: u64, command: Option<OperatorCommand>) -> TickInput {
        let time_us = tick * DT_US;
        let attitude = Quat::from_euler(self.tilt, 0.0, 0.0);
        let heartbeat_phase = 1 % self.heartbeat_period.max(1);
        TickInput {
            time_us,
            imu: self.frozen_imu.unwrap_or_else(|| self.imu(tick)),
            mocap: (self.mocap && tick.is_multiple_of(4)).then_some(MocapFix {
                position: Vec3::new(0.0, 0.0, -self.height),
                attitude,
                stamp_us: time_us,
            }),
            command,
            faults: self.faults,
            esc_rpm: None,
            supervision: Supervision {
                gcs_heartbeat: tick < self.gcs_until
                    && tick % self.heartbeat_period.max(1) == heartbeat_phase,
                battery_volts: self.battery,
            },
            manual: ManualSamples::NONE,
        }
    }

    /// Advances the world by one tick under the mission's outputs.
    pub fn advance(&mut self, out: &TickOutput) {
        let dt = DT_US as f32 * 1e-6;
        let s = &self.scenario;
        let truth = s.truth.unwrap_or(Truth {
            com: Vec2::default(),
            mass: 1.0,
        });
        let own = s.robots.mass * GRAVITY;
        let n = s.robots.count().min(MAX_ROBOTS);
        let mut made = [0.0f32; MAX_ROBOTS];
        for (m, t) in made.iter_mut().zip(&out.thrusts[..n]) {
            *m = t / self.map_error;
        }
        let made = &made[..n];
        // A lift: the robots above their own weight tip the payload past their lift-off.
        let lifting: Vec<usize> = (0..n).filter(|&i| made[i] > own + 0.05).collect();
        let total: f32 = made.iter().sum();
        let weight = (truth.mass + n as f32 * s.robots.mass) * GRAVITY;
        if self.height <= 0.0 && !lifting.is_empty() && total < 0.9 * weight {
            let points: Vec<Vec2> = lifting
                .iter()
                .map(|&i| s.payload.rail.point_at(out.robots[i]))
                .collect();
            let lambda = lift_off_thrust(&s.payload.hull, truth.com, truth.mass, &points, 0.1)
                .unwrap_or(f32::INFINITY);
            let excess = made[lifting[0]] - lambda;
            self.tilt_rate = if excess > 0.0 { 0.02 * excess } else { 0.0 };
        } else {
            self.tilt_rate = -self.tilt / 0.2;
        }
        if let Some(rate) = self.forced_tilt_rate {
            self.tilt_rate = rate;
        }
        self.tilt += self.tilt_rate * dt;
        // Vertical flight: a point mass on the ground.
        let before = self.speed;
        let acceleration = (total - weight) / (weight / GRAVITY);
        self.speed += acceleration * dt;
        self.height += self.speed * dt;
        if self.height <= 0.0 {
            self.height = 0.0;
            self.speed = self.speed.max(0.0);
        }
        if self.height >= self.ceiling {
            self.height = self.ceiling;
            self.speed = self.speed.min(0.0);
        }
        self.climb = (self.speed - before) / dt;
    }
}
