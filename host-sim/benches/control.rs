//! One full 400 Hz control step as the firmware runs it, with 8 rotors: attitude estimator
//! update, position prediction, cascade, allocation (issue: a few microseconds on the target).
//!
//! `cargo bench -p host-sim --bench control`. Host figures; see the issue note for the
//! Cortex-M7 estimate.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use shared::control::allocation::{Mixer, MixerKind, RotorLayout, Saturation};
use shared::control::attitude_estimator::{AttitudeEstimator, AttitudeEstimatorGains};
use shared::control::controller::{ControlInputs, FlightController};
use shared::control::params::ControlParams;
use shared::control::position_estimator::{PositionEstimator, PositionEstimatorGains};
use shared::control::trajectory::{FlightPlan, PlanLimits};
use shared::control::vector::Vec3;
use shared::control::vehicle::VehicleModel;
use shared::geometry::Vec2;

fn control_step(c: &mut Criterion) {
    let points = shared::paper::RECT_ROTORS;
    let spin = shared::paper::ALTERNATING_SPIN;
    let footprint = [
        Vec2::new(-0.88, -0.1),
        Vec2::new(0.88, -0.1),
        Vec2::new(0.88, 0.1),
        Vec2::new(-0.88, 0.1),
    ];
    let com = Vec2::new(0.12, 0.01);
    let model = VehicleModel::from_payload(&footprint, com, 3.5, &points, 0.1, 14.2);
    for kind in [MixerKind::EqualSplit, MixerKind::Allocation] {
        let layout = RotorLayout {
            points: &points,
            spin: &spin,
            com,
            torque_per_thrust: 0.016,
            max_thrust: 14.2,
        };
        let mixer = Mixer::build(kind, &layout).expect("mixer");
        let plan = FlightPlan::new(Vec3::ZERO, [0.3, 1.98, 0.5], 0.0, PlanLimits::default());
        let mut attitude = AttitudeEstimator::new(AttitudeEstimatorGains::default());
        let mut position = PositionEstimator::new(PositionEstimatorGains::default());
        let mut controller = FlightController::new(ControlParams::default(), model);
        let mut saturation = Saturation::default();
        let mut now_us = 0u64;
        position.predict(Vec3::ZERO, 0.0025, now_us);
        position.correct(Vec3::ZERO, now_us);
        c.bench_function(&format!("400 Hz step, 8 rotors, {kind:?}"), |b| {
            b.iter(|| {
                now_us += 2500;
                let dt = 0.0025;
                let gyro = black_box(Vec3::new(0.01, -0.02, 0.005));
                let accel = black_box(Vec3::new(0.1, -0.05, -9.7));
                let a = attitude.update(gyro, accel, dt, now_us);
                let world_accel = a.attitude.rotate(accel) + Vec3::DOWN * 9.80665;
                position.predict(world_accel, dt, now_us);
                let (setpoint, _) = plan.sample(now_us as f32 * 1e-6);
                let inputs = ControlInputs {
                    setpoint,
                    attitude: a,
                    position: position.state(),
                    airborne: true,
                    saturation,
                };
                let out = controller.step(&inputs, dt);
                let alloc = mixer.allocate(&out.wrench);
                saturation = alloc.saturation;
                black_box(alloc)
            })
        });
    }
}

criterion_group!(benches, control_step);
criterion_main!(benches);
