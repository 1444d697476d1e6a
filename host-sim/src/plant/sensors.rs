//! The sensors of the simulated vehicle, seeded and reproducible (docs/system.md#hardware):
//! an IMU at the payload frame's origin and a motion-capture system.
//!
//! - IMU: gyro with a constant bias (drawn from the seed, or given: `hil --gyro-bias`) and
//!   white noise; accelerometer reading the specific force
//!   (acceleration minus gravity) in the body frame, with white noise. Sampled at the control
//!   rate; as a real IMU's anti-alias filter and delta-angle output do, each sample carries
//!   the motion over the whole period: the acceleration is the origin's velocity change over
//!   it and the rate the attitude's change over it (a knock lasting less than a period is
//!   not lost between two samples). Its output
//!   lags [`IMU_DELAY_SAMPLES`] samples (the sensor's filter and transfer): part of the delay
//!   the lift-off detection must live with.
//! - Motion capture: position and attitude of the payload frame at [`MOCAP_HZ`], with noise,
//!   delivered [`MOCAP_LATENCY`] after it was taken.

use std::collections::VecDeque;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use shared::control::navigator::{ImuSample, MocapFix};
use shared::control::vector::{Quat, Vec3};
use shared::scenario::GRAVITY;

use drivers::imu::ImuFault;
use scenario_toml::PlantDepartures;

use super::vibration::{VibratingImu, Vibration};
use crate::plant::{Plant, TrueState};

/// Gyro white noise, rad/s (1 sigma).
pub const GYRO_NOISE: f32 = 0.005;
/// Gyro bias magnitude per axis, rad/s.
pub const GYRO_BIAS: f32 = 0.01;
/// Largest gyro bias that may be given (`hil --gyro-bias`), rad/s per axis: far above any MEMS
/// gyro's. (The firmware's gyro calibration refuses offsets past 0.35 rad/s, so a bias between
/// the two tries that refusal.)
pub const MAX_GIVEN_GYRO_BIAS: f32 = 0.5;
/// Accelerometer white noise, m/s^2 (1 sigma).
pub const ACCEL_NOISE: f32 = 0.05;
/// IMU output delay, samples (5 ms at 400 Hz).
pub const IMU_DELAY_SAMPLES: usize = 2;
/// Motion-capture rate, Hz.
pub const MOCAP_HZ: f32 = 100.0;
/// Motion-capture latency, s.
pub const MOCAP_LATENCY: f32 = 0.01;
/// Motion-capture position noise, m (1 sigma).
pub const MOCAP_POSITION_NOISE: f32 = 0.001;
/// Motion-capture attitude noise, rad per axis (1 sigma).
pub const MOCAP_ATTITUDE_NOISE: f32 = 0.005;

/// Extra white noise on the IMU's samples (the `imu-noise` injection), from its own seeded
/// stream so the sensors' noise stays what it is without it.
pub struct ImuNoise {
    rng: ChaCha8Rng,
    scale: f32,
}

impl ImuNoise {
    /// Noise of `scale` times [`GYRO_NOISE`] and [`ACCEL_NOISE`], from `seed`.
    pub fn new(seed: u64, scale: f32) -> Self {
        Self {
            rng: ChaCha8Rng::seed_from_u64(seed ^ 0x1A0_0015E),
            scale,
        }
    }

    /// `sample` with the noise added to every axis.
    pub fn add(&mut self, sample: ImuSample) -> ImuSample {
        let rng = &mut self.rng;
        let mut n = |s: f32| Vec3::new(noise(rng, s), noise(rng, s), noise(rng, s));
        ImuSample {
            gyro: sample.gyro + n(self.scale * GYRO_NOISE),
            accel: sample.accel + n(self.scale * ACCEL_NOISE),
        }
    }
}

/// The vehicle's sensors.
pub struct Sensors {
    rng: ChaCha8Rng,
    gyro_bias: Vec3,
    last_velocity: Option<Vec3>,
    last_attitude: Option<Quat>,
    imu_queue: VecDeque<ImuSample>,
    pending: VecDeque<(f32, MocapFix)>,
    next_fix: f32,
    /// Motion capture's latency, s.
    mocap_latency: f32,
    /// The fraction of fixes lost, in bursts, and the draws that lose them (a stream of its
    /// own: without dropout the sensors' noise is what it was).
    mocap_dropout: f32,
    dropout_rng: ChaCha8Rng,
    in_dropout: bool,
    /// The raw 2 kHz path through the board's front end, when the frame vibrates.
    raw: Option<VibratingImu>,
    /// What the front end last found wrong with the IMU.
    imu_fault: Option<ImuFault>,
}

/// Mean length of a burst of lost motion-capture fixes (occlusions last tens of ms).
const DROPOUT_BURST_FIXES: f32 = 5.0;

/// The body rate that turns `from` into `to` in `dt` seconds, rad/s (body axes): the rotation
/// vector of `from^-1 to` over `dt`.
fn mean_rate(from: Quat, to: Quat, dt: f32) -> Vec3 {
    let delta = from.conjugate() * to;
    let sign = if delta.w < 0.0 { -1.0 } else { 1.0 };
    let v = delta.vector() * sign;
    let half_sin = v.norm();
    if half_sin < 1e-9 {
        return Vec3::ZERO;
    }
    let angle = 2.0 * half_sin.atan2(delta.w * sign);
    v * (angle / (half_sin * dt))
}

fn noise(rng: &mut ChaCha8Rng, sigma: f32) -> f32 {
    Normal::new(0.0, sigma).map_or(0.0, |n| n.sample(rng))
}

impl Sensors {
    /// Sensors with noise streams from `seed`.
    pub fn new(seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut bias = || noise(&mut rng, GYRO_BIAS);
        let gyro_bias = Vec3::new(bias(), bias(), bias());
        Self {
            rng,
            gyro_bias,
            last_velocity: None,
            last_attitude: None,
            imu_queue: VecDeque::new(),
            pending: VecDeque::new(),
            next_fix: 0.0,
            mocap_latency: MOCAP_LATENCY,
            mocap_dropout: 0.0,
            dropout_rng: ChaCha8Rng::seed_from_u64(seed ^ 0xD209_0F75),
            in_dropout: false,
            raw: None,
            imu_fault: None,
        }
    }

    /// Sensors for `plant` as the scenario's `[plant]` `departures` make them (motion
    /// capture's latency and dropout, the frame's vibration), noise from `seed`.
    pub fn departed(seed: u64, departures: &PlantDepartures, plant: &Plant) -> Self {
        Self::new(seed)
            .with_mocap_departures(departures.mocap_latency, departures.mocap_dropout)
            .with_vibration(
                departures.imu_vibration,
                departures.gyro_vibration,
                plant,
                seed,
            )
    }

    /// The IMU's samples made raw at 2 kHz with the frame's `accel_rms` (m/s^2) and `gyro_rms`
    /// (rad/s) vibration and passed through the board's front end (the scenario's `[plant]`
    /// `imu_vibration`, `gyro_vibration`: [`super::vibration`]), for `plant`'s rotors; without
    /// vibration the samples stay the tick-rate model's.
    pub fn with_vibration(
        mut self,
        accel_rms: f32,
        gyro_rms: f32,
        plant: &Plant,
        seed: u64,
    ) -> Self {
        if accel_rms > 0.0 || gyro_rms > 0.0 {
            let rotors = plant.thrusts().len();
            let vibration = Vibration {
                accel_rms,
                gyro_rms,
                hover_thrust: plant.total_mass() * GRAVITY / rotors.max(1) as f32,
            };
            self.raw = Some(VibratingImu::new(vibration, rotors, seed));
        }
        self
    }

    /// The rotors' speeds and thrusts now, for the vibration and the front end's notches (a
    /// no-op without vibration).
    pub fn hear_rotors(&mut self, plant: &Plant) {
        if let Some(raw) = &mut self.raw {
            raw.rotors(plant.rotor_rpm(), plant.thrusts());
        }
    }

    /// What the board's front end found wrong with the IMU at the last sample (saturated,
    /// stalled), on the raw path; `None` on the tick-rate model.
    pub fn imu_fault(&self) -> Option<ImuFault> {
        self.imu_fault
    }

    /// Motion capture `latency` s late, losing `dropout` of its fixes in bursts (the
    /// scenario's `[plant]` `mocap_latency`, `mocap_dropout`).
    pub fn with_mocap_departures(mut self, latency: f32, dropout: f32) -> Self {
        self.mocap_latency = latency.max(0.0);
        self.mocap_dropout = dropout.clamp(0.0, 0.99);
        self
    }

    /// Whether the next fix is lost: a two-state chain whose bursts last
    /// [`DROPOUT_BURST_FIXES`] on average and whose share of lost fixes is the dropout.
    fn fix_lost(&mut self) -> bool {
        let d = self.mocap_dropout;
        if d <= 0.0 {
            return false;
        }
        let leave = 1.0 / DROPOUT_BURST_FIXES;
        let enter = (d * leave / (1.0 - d)).min(1.0);
        let u: f32 = rand::RngExt::random(&mut self.dropout_rng);
        self.in_dropout = if self.in_dropout {
            u >= leave
        } else {
            u < enter
        };
        self.in_dropout
    }

    /// The same sensors with the gyro's constant bias `bias` (rad/s, body axes) in place of the
    /// one drawn from the seed; the noise streams stay those of the seed.
    pub fn with_gyro_bias(mut self, bias: Vec3) -> Self {
        self.gyro_bias = bias;
        self
    }

    /// The gyro's constant bias, rad/s.
    pub fn gyro_bias(&self) -> Vec3 {
        self.gyro_bias
    }

    /// An IMU sample of `truth`, `dt` seconds after the previous one.
    pub fn imu(&mut self, truth: &TrueState, dt: f32) -> ImuSample {
        let acceleration = match self.last_velocity.replace(truth.velocity) {
            Some(v) if dt > 0.0 => (truth.velocity - v) * (1.0 / dt),
            _ => Vec3::ZERO,
        };
        let specific = truth
            .attitude
            .inverse_rotate(acceleration - Vec3::DOWN * GRAVITY);
        let rate = match self.last_attitude.replace(truth.attitude) {
            Some(q) if dt > 0.0 => mean_rate(q, truth.attitude, dt),
            _ => truth.rate,
        };
        let sample = if let Some(raw) = &mut self.raw {
            let ([gyro, accel], fault) = raw.tick(rate + self.gyro_bias, specific, dt);
            self.imu_fault = fault;
            ImuSample { gyro, accel }
        } else {
            let rng = &mut self.rng;
            let mut n = |s: f32| Vec3::new(noise(rng, s), noise(rng, s), noise(rng, s));
            ImuSample {
                gyro: rate + self.gyro_bias + n(GYRO_NOISE),
                accel: specific + n(ACCEL_NOISE),
            }
        };
        self.imu_queue.push_back(sample);
        if self.imu_queue.len() > IMU_DELAY_SAMPLES {
            self.imu_queue.pop_front().unwrap_or(sample)
        } else {
            self.imu_queue.front().copied().unwrap_or(sample)
        }
    }

    /// Takes a fix when one is due at time `now_us` and returns the oldest fix whose latency
    /// has passed (one per call: at most one a control tick reaches the flight controller).
    pub fn mocap(&mut self, truth: &TrueState, now_us: u64) -> Option<MocapFix> {
        let t = now_us as f32 * 1e-6;
        if t + 1e-6 >= self.next_fix {
            self.next_fix += 1.0 / MOCAP_HZ;
            let rng = &mut self.rng;
            let p = truth.position
                + Vec3::new(
                    noise(rng, MOCAP_POSITION_NOISE),
                    noise(rng, MOCAP_POSITION_NOISE),
                    noise(rng, MOCAP_POSITION_NOISE),
                );
            let tremor = Vec3::new(
                noise(rng, MOCAP_ATTITUDE_NOISE),
                noise(rng, MOCAP_ATTITUDE_NOISE),
                noise(rng, MOCAP_ATTITUDE_NOISE),
            );
            let fix = MocapFix {
                position: p,
                attitude: truth.attitude * Quat::from_rotation_vector(tremor),
                stamp_us: now_us,
            };
            if !self.fix_lost() {
                self.pending.push_back((t + self.mocap_latency, fix));
            }
        }
        if self.pending.front().is_some_and(|(at, _)| *at <= t + 1e-6) {
            self.pending.pop_front().map(|(_, fix)| fix)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at_rest() -> TrueState {
        TrueState {
            position: Vec3::ZERO,
            velocity: Vec3::ZERO,
            attitude: Quat::IDENTITY,
            rate: Vec3::ZERO,
        }
    }

    /// A rotation that comes and goes between two samples (a knock shorter than a period):
    /// the sample after it carries the whole turn, as a real IMU's delta angle does, though
    /// the body is at rest again when it is taken.
    #[test]
    fn a_turn_between_samples_is_in_the_next_sample() {
        let dt = 0.0025;
        let mut sensors = Sensors::new(3).with_gyro_bias(Vec3::ZERO);
        let mut turned = at_rest();
        let mut total = 0.0f32;
        for k in 0..40 {
            if k == 20 {
                // 0.01 rad about x between samples 19 and 20; at rest when sampled.
                turned.attitude = Quat::from_rotation_vector(Vec3::new(0.01, 0.0, 0.0));
            }
            let sample = sensors.imu(&turned, dt);
            total += sample.gyro.x * dt;
        }
        // The turn less the white noise's share (40 samples of 5 mrad/s over 2.5 ms).
        assert!((total - 0.01).abs() < 5e-4, "integrated {total} rad");
        assert!(
            (mean_rate(Quat::IDENTITY, turned.attitude, dt).x - 4.0).abs() < 1e-3,
            "0.01 rad over 2.5 ms is 4 rad/s"
        );
    }

    #[test]
    fn a_given_gyro_bias_replaces_the_seeded_one_and_keeps_the_noise() {
        let bias = Vec3::new(0.02, -0.015, 0.01);
        let mut seeded = Sensors::new(7);
        let mut given = Sensors::new(7).with_gyro_bias(bias);
        assert_eq!(given.gyro_bias(), bias);
        let (n, dt) = (4000, 1.0 / 400.0);
        let mut mean = Vec3::ZERO;
        for _ in 0..n {
            let (a, b) = (seeded.imu(&at_rest(), dt), given.imu(&at_rest(), dt));
            // The same noise: the two differ by the biases alone.
            let d = (b.gyro - a.gyro) - (bias - seeded.gyro_bias());
            assert!(d.norm() < 1e-6, "{d:?}");
            mean += b.gyro * (1.0 / n as f32);
        }
        assert!((mean - bias).norm() < 3e-4, "mean gyro at rest {mean:?}");
    }
}

#[cfg(test)]
mod departure_tests {
    use super::*;

    #[test]
    fn fixes_come_late_by_the_latency_and_a_dropout_loses_its_share_in_bursts() {
        let rest = TrueState {
            position: Vec3::ZERO,
            velocity: Vec3::ZERO,
            attitude: Quat::IDENTITY,
            rate: Vec3::ZERO,
        };
        let mut s = Sensors::new(3).with_mocap_departures(0.05, 0.0);
        let first = (0..100u64)
            .find_map(|k| s.mocap(&rest, k * 2500).map(|f| (k, f)))
            .expect("a fix");
        assert_eq!(first.0 * 2500 - first.1.stamp_us, 50_000, "50 ms late");
        let mut s = Sensors::new(3).with_mocap_departures(0.01, 0.3);
        let (mut got, mut runs, mut was_lost) = (0u32, 0u32, false);
        let n = 40_000u64;
        let mut expected = 0u64;
        for k in 0..n {
            let fix = s.mocap(&rest, k * 2500);
            if k % 4 == 0 && k >= 4 {
                expected += 1;
            }
            got += u32::from(fix.is_some());
            let lost = k % 4 == 0 && k >= 4 && fix.is_none();
            runs += u32::from(lost && !was_lost);
            if k % 4 == 0 {
                was_lost = lost;
            }
        }
        let lost = 1.0 - f64::from(got) / expected as f64;
        assert!((0.25..0.35).contains(&lost), "lost {lost}");
        let mean_burst = (expected as f64 - f64::from(got)) / f64::from(runs.max(1));
        assert!(mean_burst > 3.0, "bursts of {mean_burst} fixes");
    }
}
