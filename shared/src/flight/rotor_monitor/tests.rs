//! Tests of the rotor monitor in a simulated hover: every rotor that stops is found quickly and
//! no other, disturbances that are no rotor's are let be, nothing is judged on the ground or
//! before settling, a rotor marked out is not found again, and the monitor's state is small.

use super::*;
use crate::control::allocation::{MixerKind, RotorLayout};
use crate::paper::{ALTERNATING_SPIN, RECT_ROTORS};
use crate::scenario::GRAVITY;

/// Well off the IMU (the payload frame's origin): the accelerometer's lever
/// matters.
const COM: Vec2 = Vec2::new(0.3, 0.05);
const DT: f32 = 0.0025;

fn mixer() -> Mixer {
    Mixer::build(
        MixerKind::Allocation,
        &RotorLayout {
            points: &RECT_ROTORS,
            spin: &ALTERNATING_SPIN,
            com: COM,
            torque_per_thrust: 0.016,
            max_thrust: 14.2,
        },
    )
    .expect("controllable")
}

fn vehicle() -> VehicleModel {
    // The paper's rectangle, 1.76 m x 0.2 m.
    let plate = [
        Vec2::new(-0.88, -0.1),
        Vec2::new(0.88, -0.1),
        Vec2::new(0.88, 0.1),
        Vec2::new(-0.88, 0.1),
    ];
    VehicleModel::from_payload(&plate, COM, 3.5, &RECT_ROTORS, 0.1, 14.2)
}

/// A rigid payload on the rotors, its inertia 70 % of the model's, its attitude held by a
/// PD: rotor thrusts follow their commands with a 20 ms lag; `lost` rotors make nothing
/// from `lost_at` s; `extra` is a torque (N m) and a thrust (N) the model does not know,
/// as a function of time. Returns the rotor found and when.
fn fly(
    lost: &[usize],
    lost_at: f32,
    extra: impl Fn(f32) -> (Vec3, f32),
    seconds: f32,
) -> Option<(usize, f32)> {
    let mixer = mixer();
    let v = vehicle();
    let mut monitor = RotorMonitor::new();
    let mut rotor = [0.0f32; MAX_ROBOTS];
    let mut w = Vec3::ZERO;
    let mut tilt = Vec3::ZERO;
    let mut accel_z = -GRAVITY;
    let steps = (seconds / DT) as usize;
    for k in 0..steps {
        let t = k as f32 * DT;
        // Hold the attitude (a PD of 10 rad/s with the model's inertia) and the weight.
        let hold = (tilt * 100.0 + w * 20.0).component_mul(v.inertia) * -1.0;
        let wrench = crate::control::allocation::Wrench {
            thrust: v.hover_thrust(),
            torque: Vec3::new(hold.x, hold.y, 0.0),
        };
        let thrusts = mixer.allocate(&wrench).thrusts;
        let found = monitor.update(&MonitorInput {
            config: &RotorMonitorConfig::DEFAULT,
            mixer: &mixer,
            vehicle: &v,
            com: COM,
            thrusts: &thrusts[..8],
            rpm: None,
            rpm_per_message: false,
            rate: w,
            accel: Vec3::new(0.0, 0.0, accel_z),
            flying: true,
            active: true,
            dt: DT,
        });
        if found != 0 {
            assert_eq!(found.count_ones(), 1, "one rotor named: {found:#b}");
            return Some((found.trailing_zeros() as usize, t));
        }
        for (i, r) in rotor.iter_mut().enumerate().take(8) {
            let target = if lost.contains(&i) && t >= lost_at {
                0.0
            } else {
                thrusts[i]
            };
            *r += (target - *r) * DT / 0.02;
        }
        let true_wrench = mixer.wrench_of(&rotor[..8]);
        let (torque, thrust) = extra(t);
        let torque = true_wrench.torque + torque;
        // The true inertia is 70 % of the model's (the model's plate about the estimated
        // COM; the simulator's plant is 40 % lighter in pitch on rect-sim2).
        let w_dot = Vec3::new(
            torque.x / (0.7 * v.inertia.x),
            torque.y / (0.7 * v.inertia.y),
            0.0,
        );
        w += w_dot * DT;
        tilt += w * DT;
        // The IMU at the origin, the COM at `COM` from it: f_imu = f_com - dw/dt x COM
        // (w x (w x COM) has no z part with w in the plane).
        let f_com = -(true_wrench.thrust + thrust) / v.mass;
        accel_z = f_com - (w_dot.x * COM.y - w_dot.y * COM.x);
    }
    None
}

#[test]
fn every_rotor_that_stops_is_found_quickly_and_no_other() {
    for j in 0..8 {
        let (found, at) = fly(&[j], 1.0, |_| (Vec3::ZERO, 0.0), 2.0)
            .unwrap_or_else(|| panic!("rotor {j} not found"));
        assert_eq!(found, j);
        let late = at - 1.0;
        assert!(
            (0.05..0.15).contains(&late),
            "rotor {j} found {late} s late"
        );
    }
}

#[test]
fn a_steady_flight_and_slow_or_torque_only_disturbances_are_no_rotor() {
    assert_eq!(fly(&[], 0.0, |_| (Vec3::ZERO, 0.0), 5.0), None);
    // The paper's disturbance: 0.3 N m on roll and pitch at 0.37 and 0.53 Hz.
    let paper = |t: f32| {
        let tau = 2.0 * core::f32::consts::PI;
        (
            Vec3::new(
                0.3 * math::sin(tau * 0.37 * t),
                0.3 * math::sin(tau * 0.53 * t),
                0.0,
            ),
            0.0,
        )
    };
    assert_eq!(fly(&[], 0.0, paper, 5.0), None);
    // A load sliding 0.15 m along x in half a second: a pitch torque the size of a
    // rotor's, and no change of thrust.
    let shift = |t: f32| {
        let x = math::clamp((t - 1.0) / 0.5, 0.0, 1.0) * 0.15;
        (Vec3::new(0.0, -x * 3.5 * GRAVITY, 0.0), 0.0)
    };
    assert_eq!(fly(&[], 0.0, shift, 4.0), None);
    // A loss of lift seven rotors' worth, no torque (a downdraft): too large for one
    // rotor or two (a rotor's own worth near the COM, or two balanced rotors' worth,
    // could not be told from them).
    let gust = |t: f32| (Vec3::ZERO, if t > 1.0 { -30.0 } else { 0.0 });
    assert_eq!(fly(&[], 0.0, gust, 3.0), None);
}

#[test]
fn nothing_is_judged_on_the_ground_or_before_settling() {
    let mixer = mixer();
    let v = vehicle();
    let mut monitor = RotorMonitor::new();
    let thrusts = [5.0f32; 8];
    // A huge imbalance, but not active (on the ground): nothing.
    for _ in 0..400 {
        let found = monitor.update(&MonitorInput {
            config: &RotorMonitorConfig::DEFAULT,
            mixer: &mixer,
            vehicle: &v,
            com: COM,
            thrusts: &thrusts,
            rpm: None,
            rpm_per_message: false,
            rate: Vec3::new(3.0, -3.0, 0.0),
            accel: Vec3::new(0.0, 0.0, 0.0),
            flying: false,
            active: false,
            dt: DT,
        });
        assert_eq!(found, 0);
    }
    assert_eq!(monitor.change(), [0.0; 3]);
    // Garbage input: no panic, nothing found.
    let found = monitor.update(&MonitorInput {
        config: &RotorMonitorConfig::DEFAULT,
        mixer: &mixer,
        vehicle: &v,
        com: COM,
        thrusts: &[f32::NAN; 8],
        rpm: Some(&[f32::NAN; 8]),
        rpm_per_message: false,
        rate: Vec3::new(f32::NAN, 0.0, 0.0),
        accel: Vec3::ZERO,
        flying: true,
        active: true,
        dt: -1.0,
    });
    assert_eq!(found, 0);
}

#[test]
fn a_rotor_marked_out_is_not_found_again() {
    let mut monitor = RotorMonitor::new();
    let mixer = mixer();
    monitor.mark_out(1 << 3, &mixer, &RotorMonitorConfig::DEFAULT);
    assert_eq!(monitor.out(), 1 << 3);
    monitor.mark_out(1 << 5, &mixer, &RotorMonitorConfig::DEFAULT);
    assert_eq!(monitor.out(), (1 << 3) | (1 << 5));
}

#[test]
fn its_state_is_small() {
    // The flight controller keeps it in its static mission (the Pixhawk image's static
    // RAM is within its budget with some 7 KiB to spare).
    let size = core::mem::size_of::<RotorMonitor>();
    assert!(size <= 320, "{size} bytes");
}

/// Ticks until the RPM path names rotor 2, whose RPM falls to a tenth after a second of
/// hover (each reading a tick of its own, or the latest message held: `per_message`), and
/// what it names.
fn ticks_to_name_by_rpm(per_message: bool) -> (u32, u16) {
    let mixer = mixer();
    let v = vehicle();
    let mut monitor = RotorMonitor::new();
    let thrusts = [v.hover_thrust() / 8.0; 8];
    for k in 0..2000u32 {
        let mut rpm = [5_000.0f32; 8];
        if k >= 800 {
            rpm[2] = 500.0;
        }
        let found = monitor.update(&MonitorInput {
            config: &RotorMonitorConfig::DEFAULT,
            mixer: &mixer,
            vehicle: &v,
            com: COM,
            thrusts: &thrusts,
            rpm: Some(&rpm),
            rpm_per_message: per_message,
            rate: Vec3::ZERO,
            accel: Vec3::new(0.0, 0.0, -GRAVITY),
            flying: true,
            active: true,
            dt: DT,
        });
        if found != 0 {
            return (k - 800, found);
        }
    }
    (u32::MAX, 0)
}

#[test]
fn a_low_rpm_confirms_in_ten_ms_of_readings_a_tick_or_in_one_held_message() {
    // Bidirectional DShot: a reading each tick, 10 ms of them (four ticks, the fourth names).
    assert_eq!(ticks_to_name_by_rpm(false), (3, 1 << 2));
    // DroneCAN: the ESC's Status, held between messages: the first low one names it.
    assert_eq!(ticks_to_name_by_rpm(true), (0, 1 << 2));
}
