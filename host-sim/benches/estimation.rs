//! Speed of the estimator's steps as the flight controller runs them (one full pair selection
//! on the L-shape grid must stay well under 10 ms on a 480 MHz Cortex-M7).
//!
//! `cargo bench -p host-sim --bench estimation`. The figures are host times; the Cortex-M7's
//! own come from `bash .ci/target-bench` (instruction counts under QEMU).

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use host_sim::scenario_file;
use shared::estimation::{Estimator, EstimatorOptions, Measurement, ThrustScaleAxis};

fn load(name: &str) -> shared::scenario::Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/scenarios")
        .join(format!("{name}.toml"));
    scenario_file::load(&path).expect("paper scenario").scenario
}

fn selection(c: &mut Criterion) {
    for (name, label, scale) in [
        ("L-sim1", "L-shape", None),
        (
            "L-sim1",
            "L-shape with bias term",
            Some(ThrustScaleAxis::DEFAULT),
        ),
        ("rect-sim1", "rectangle", None),
    ] {
        let scenario = load(name);
        let options = EstimatorOptions {
            thrust_scale: scale,
        };
        let mut estimator = Estimator::new(&scenario, options).expect("estimator");
        // Two lifts first, so the posterior is no longer flat (a typical mid-run state).
        estimator
            .update(0, Measurement::Lifted { thrust: 6.0 })
            .expect("update");
        estimator
            .update(3, Measurement::Lifted { thrust: 7.5 })
            .expect("update");
        println!(
            "{label}: {} grid points, {} groups",
            estimator.grid().len(),
            estimator.group_count()
        );
        c.bench_function(&format!("select pair, {label}"), |b| {
            b.iter(|| black_box(estimator.select_group().expect("a group")))
        });
        let fresh = estimator.clone();
        c.bench_function(&format!("update, {label}"), |b| {
            b.iter_batched_ref(
                || fresh.clone(),
                |e| black_box(e.update(1, Measurement::Lifted { thrust: 6.5 })),
                criterion::BatchSize::SmallInput,
            )
        });
    }
}

criterion_group!(benches, selection);
criterion_main!(benches);
