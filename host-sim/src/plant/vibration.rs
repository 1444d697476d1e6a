//! The IMU's raw path with the frame's vibration (docs/formats.md#the-plant-section, `[plant]`
//! `imu_vibration`, `gyro_vibration`): the plant makes the ICM-42688-P's 2 kHz samples with
//! each rotor's vibration at its rotation and blade-pass frequencies (from its RPM, growing with
//! its thrust), white noise and the sensor's range clipping (+-16 g, +-2000 deg/s), and they go
//! through the board's own front end ([`drivers::imu::ImuFrontEnd`]: the rotors' notches fed
//! by the ESCs' RPM, the 80 Hz anti-alias filter, decimation to the tick), so the simulator
//! flies that code too.
//!
//! Each rotor contributes a sine per harmonic and per channel, with a phase drawn from the
//! seed; the amplitude is such that with every rotor at hover thrust each axis's RMS is the
//! configured figure, half its power at the rotation frequency (imbalance), half at the blade
//! pass, and each rotor's share grows in proportion to its thrust. The white noise on the raw
//! samples is such that after the anti-alias filter each tick carries the sensors' usual
//! noise ([`super::sensors::GYRO_NOISE`], [`super::sensors::ACCEL_NOISE`]).

use drivers::biquad::{Biquad, BiquadCoefficients};
use drivers::imu::{ImuFault, ImuFrontEnd, Mounting};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use shared::control::vector::Vec3;
use shared::scenario::MAX_ROBOTS;

use super::sensors::{ACCEL_NOISE, GYRO_NOISE};

/// The raw sample rate, Hz (the ICM-42688-P's output data rate on the Pixhawk 6C).
pub const RAW_HZ: f32 = 2000.0;
/// The board's anti-alias cutoff, Hz (as the firmware's IMU task).
pub const CUTOFF_HZ: f32 = 80.0;
/// The accelerometer's full scale, m/s^2 (+-16 g).
pub const ACCEL_RANGE: f32 = 16.0 * 9.806_65;
/// The gyro's full scale, rad/s (+-2000 deg/s).
pub const GYRO_RANGE: f32 = 2000.0 * core::f32::consts::PI / 180.0;
/// Harmonics of each rotor's rotation that shake the frame: rotation, two-blade pass.
const HARMONICS: usize = 2;

/// The frame's vibration as configured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vibration {
    /// m/s^2 RMS per accelerometer axis with every rotor at hover thrust.
    pub accel_rms: f32,
    /// rad/s RMS per gyro axis, likewise.
    pub gyro_rms: f32,
    /// One rotor's hover thrust, N (the vehicle's weight over its rotors).
    pub hover_thrust: f32,
}

/// One rotor's harmonic: its phase and, per channel, the phase offset's sine and cosine.
#[derive(Clone, Copy)]
struct Shake {
    phase: f32,
    offset: [(f32, f32); 6],
}

/// The raw IMU and the board's front end behind it.
pub struct VibratingImu {
    vibration: Vibration,
    front: ImuFrontEnd<MAX_ROBOTS>,
    shakes: Vec<[Shake; HARMONICS]>,
    rng: ChaCha8Rng,
    raw_noise: [f32; 2],
    rpm: Vec<f32>,
    thrust: Vec<f32>,
}

/// The RMS of white noise after the board's anti-alias filter, per unit RMS before it.
fn filter_noise_gain() -> f32 {
    let mut lp = Biquad::new(BiquadCoefficients::low_pass(CUTOFF_HZ, RAW_HZ));
    let mut energy = 0.0;
    for k in 0..2000 {
        let h = lp.apply(if k == 0 { 1.0 } else { 0.0 });
        energy += h * h;
    }
    energy.sqrt()
}

impl VibratingImu {
    /// The raw path for `rotors` rotors shaking as `vibration`, phases and noise from `seed`.
    pub fn new(vibration: Vibration, rotors: usize, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5EA1_C0DE);
        let shakes = (0..rotors)
            .map(|_| {
                [(); HARMONICS].map(|()| Shake {
                    phase: rng.random_range(0.0..core::f32::consts::TAU),
                    offset: [(); 6].map(|()| {
                        let o: f32 = rng.random_range(0.0..core::f32::consts::TAU);
                        (o.sin(), o.cos())
                    }),
                })
            })
            .collect();
        let gain = filter_noise_gain();
        Self {
            vibration,
            front: ImuFrontEnd::new(Mounting::Identity, RAW_HZ, CUTOFF_HZ),
            shakes,
            rng,
            raw_noise: [GYRO_NOISE / gain, ACCEL_NOISE / gain],
            rpm: vec![0.0; rotors],
            thrust: vec![0.0; rotors],
        }
    }

    /// The rotors' speeds (RPM) and thrusts (N) now; the ESCs report the same speeds to the
    /// front end's notches.
    pub fn rotors(&mut self, rpm: impl Iterator<Item = f32>, thrust: &[f32]) {
        self.rpm.clear();
        self.rpm.extend(rpm);
        self.thrust.clear();
        self.thrust.extend_from_slice(thrust);
        self.front.follow_rotors(&self.rpm);
    }

    /// One tick (`dt` s) of raw samples of the true rate (with the gyro's bias) and specific
    /// force, body axes, through the front end: the tick's sample, or the fault the front end
    /// finds (the sample is then the latest it has, as the board flies on it while landing).
    pub fn tick(&mut self, rate: Vec3, specific: Vec3, dt: f32) -> ([Vec3; 2], Option<ImuFault>) {
        let samples = (dt * RAW_HZ).round().max(1.0) as usize;
        let raw_dt = 1.0 / RAW_HZ;
        let per_rotor = 1.0 / (self.shakes.len().max(1) as f32).sqrt();
        let hover = self.vibration.hover_thrust.max(f32::MIN_POSITIVE);
        let [gyro_sigma, accel_sigma] = self.raw_noise;
        for _ in 0..samples {
            let mut shake = [0.0f32; 6];
            for (k, rotor) in self.shakes.iter_mut().enumerate() {
                let turns_hz = self.rpm.get(k).copied().unwrap_or(0.0) / 60.0;
                let size = self.thrust.get(k).copied().unwrap_or(0.0).max(0.0) / hover;
                // Each harmonic carries half the power: an amplitude of RMS * sqrt(2 / 2).
                let amplitude = size * per_rotor;
                for (h, harmonic) in rotor.iter_mut().enumerate() {
                    let (s, c) = harmonic.phase.sin_cos();
                    for (v, (os, oc)) in shake.iter_mut().zip(harmonic.offset) {
                        *v += amplitude * (s * oc + c * os);
                    }
                    harmonic.phase = (harmonic.phase
                        + core::f32::consts::TAU * turns_hz * (h + 1) as f32 * raw_dt)
                        % core::f32::consts::TAU;
                }
            }
            let mut noise =
                |sigma: f32| Normal::new(0.0, sigma).map_or(0.0, |n| n.sample(&mut self.rng));
            let (true_rate, true_force) = (
                [rate.x, rate.y, rate.z],
                [specific.x, specific.y, specific.z],
            );
            let (mut g, mut a) = ([0.0f32; 3], [0.0f32; 3]);
            let mut saturated = false;
            for axis in 0..3 {
                let gv =
                    true_rate[axis] + self.vibration.gyro_rms * shake[axis] + noise(gyro_sigma);
                let av = true_force[axis]
                    + self.vibration.accel_rms * shake[3 + axis]
                    + noise(accel_sigma);
                saturated |= gv.abs() >= GYRO_RANGE || av.abs() >= ACCEL_RANGE;
                g[axis] = gv.clamp(-GYRO_RANGE, GYRO_RANGE);
                a[axis] = av.clamp(-ACCEL_RANGE, ACCEL_RANGE);
            }
            self.front.push(g, a, saturated);
        }
        let fault = self.front.tick().err();
        let out = self.front.latest().map_or([rate, specific], |s| {
            [
                Vec3::new(s.gyro[0], s.gyro[1], s.gyro[2]),
                Vec3::new(s.accel[0], s.accel[1], s.accel[2]),
            ]
        });
        (out, fault)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shared::control::imu_monitor::{ImuMonitor, JUMP_ACCEL, JUMP_GYRO};
    use shared::control::navigator::ImuSample;

    /// The largest tick-to-tick changes (gyro, accelerometer) over 2 s of `rotors` rotors at
    /// `rpm` and hover thrust, with or without the ESCs' speeds reaching the notches, and
    /// whether the IMU monitor called the IMU noisy.
    fn shaken(rpm: &[f32], notched: bool) -> (f32, f32, bool) {
        let vibration = Vibration {
            accel_rms: 10.0,
            gyro_rms: 0.3,
            hover_thrust: 5.0,
        };
        let mut imu = VibratingImu::new(vibration, rpm.len(), 1);
        let thrust = vec![5.0; rpm.len()];
        let (mut dg, mut da, mut noisy) = (0.0f32, 0.0f32, false);
        let mut monitor = ImuMonitor::new();
        let mut last: Option<[Vec3; 2]> = None;
        // The rotors spin up from rest over the first 0.1 s, as on the vehicle (a filter that
        // starts on a shaking signal rings for its first ticks).
        for tick in 0..800 {
            let share = (tick as f32 / 40.0).min(1.0);
            let spin: Vec<f32> = thrust.iter().map(|t| t * share).collect();
            imu.rotors(rpm.iter().map(|r| r * share.sqrt()), &spin);
            if !notched {
                imu.front.follow_rotors(&[]);
            }
            let (s, fault) = imu.tick(Vec3::ZERO, Vec3::new(0.0, 0.0, -9.81), 1.0 / 400.0);
            assert_eq!(fault, None);
            if let Some([g, a]) = last {
                dg = dg.max((s[0] - g).norm());
                da = da.max((s[1] - a).norm());
            }
            last = Some(s);
            noisy |= monitor
                .check(
                    &ImuSample {
                        gyro: s[0],
                        accel: s[1],
                    },
                    true,
                )
                .is_some();
        }
        (dg, da, noisy)
    }

    #[test]
    fn the_notches_leave_the_monitor_a_quiet_imu_and_without_them_it_is_noisy() {
        let rpm = [7_000.0, 7_400.0, 7_800.0, 8_200.0, 8_600.0, 9_000.0];
        let (dg, da, noisy) = shaken(&rpm, false);
        assert!(
            noisy && da > JUMP_ACCEL,
            "unnotched: {dg} rad/s, {da} m/s^2"
        );
        let (dg, da, noisy) = shaken(&rpm, true);
        assert!(!noisy, "notched: {dg} rad/s, {da} m/s^2");
        assert!(
            dg < 0.5 * JUMP_GYRO && da < 0.5 * JUMP_ACCEL,
            "{dg} rad/s, {da} m/s^2"
        );
    }
}
