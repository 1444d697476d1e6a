//! Speed of the formation decision as the flight controller runs it, on the paper's cases.
//!
//! `cargo bench -p host-sim --bench formation`. Host figures; `bash .ci/target-bench` counts
//! the Cortex-M7's instructions for the same cases.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use host_sim::scenario_file;
use shared::formation::{FormationProblem, solve};

fn formation(c: &mut Criterion) {
    for name in ["rect-sim1", "rect-ex1", "L-sim1", "L-sim2"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../tests/scenarios")
            .join(format!("{name}.toml"));
        let s = scenario_file::load(&path).expect("paper scenario").scenario;
        let truth = s.truth.expect("paper cases carry their truth");
        let problem = FormationProblem::for_scenario(&s, truth.com, Some(&s.robots.initial));
        let f = solve(&problem).expect("a formation");
        println!(
            "{name}: det {:.4e}, {} assignments ({} pruned by the bound, {} starts balanced), {} Newton iterations",
            f.figures.det, f.assignments, f.pruned, f.seeds_balanced, f.sweeps
        );
        c.bench_function(&format!("formation, {name}"), |b| {
            b.iter(|| black_box(solve(&problem).expect("a formation")))
        });
    }
}

criterion_group!(benches, formation);
criterion_main!(benches);
