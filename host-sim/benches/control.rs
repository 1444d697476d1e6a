//! One full 400 Hz flight tick as the firmware runs it, with 8 rotors: the navigator (attitude
//! filter, position observer) and the flight stack (plan, nets, cascade, allocation), hovering
//! (it must take a few microseconds on the target).
//!
//! `cargo bench -p host-sim --bench control`. Host figures; `.ci/target-bench` counts the same
//! tick's instructions on the Cortex-M7.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use shared::control::allocation::MixerKind;
use shared::control::navigator::{ImuSample, MocapFix};
use shared::control::vector::{Quat, Vec3};

fn control_step(c: &mut Criterion) {
    for kind in [MixerKind::EqualSplit, MixerKind::Allocation] {
        let Some((mut navigator, mut flight)) = shared::paper::hovering_flight(kind) else {
            panic!("the paper's rotors build a mixer");
        };
        let mut now_us = 0u64;
        c.bench_function(&format!("400 Hz tick, 8 rotors, {kind:?}"), |b| {
            b.iter(|| {
                now_us += 2500;
                let dt = 0.0025;
                if now_us.is_multiple_of(10_000) {
                    // Motion capture at 100 Hz keeps the position valid: hovering, not
                    // failing safe.
                    navigator.motion_capture(&MocapFix {
                        position: Vec3::new(0.0, 0.0, -0.5),
                        attitude: Quat::IDENTITY,
                        stamp_us: now_us,
                    });
                }
                let imu = ImuSample {
                    gyro: black_box(Vec3::new(0.01, -0.02, 0.005)),
                    accel: black_box(Vec3::new(0.1, -0.05, -9.7)),
                };
                let nav = navigator.update(&imu, dt, now_us);
                black_box(flight.step(&nav, None, dt))
            })
        });
        assert!(
            flight.stopped().is_none(),
            "still flying after the benchmark"
        );
    }
}

criterion_group!(benches, control_step);
criterion_main!(benches);
