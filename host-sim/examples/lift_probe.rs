//! Prints the plant's lift-off readings against the model for every pair of a scenario, with
//! the robots starting from the initial formation and from the formation an earlier lift left:
//! `cargo run --release -p host-sim --example lift_probe -- tests/scenarios/rect-ex1.toml [map_error]`.

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .map_or("tests/scenarios/rect-ex1.toml", String::as_str);
    let map_error: f32 = args.get(2).map_or(Ok(1.0), |s| s.parse())?;
    let s = host_sim::scenario_file::load(std::path::Path::new(path))?.scenario;
    let rail = &s.payload.rail;
    let c = &s.payload.candidates;
    let after_last =
        shared::rail::moves::lift_targets(rail, &s.robots.initial, &[c[c.len() - 1], c[0]], 0.25)
            .map(|p| p.to_vec())
            .unwrap_or_else(|| s.robots.initial.to_vec());
    for group in 0..c.len() {
        for (label, from) in [
            ("initial", s.robots.initial.to_vec()),
            ("after last pair", after_last.clone()),
        ] {
            match host_sim::harness::run_lift_from(&s, group, &from, 3, map_error) {
                Ok(o) => println!(
                    "pair {group:2} from {label:<15}: model {:6.3} N, read {:?}",
                    o.model, o.measured
                ),
                Err(e) => println!("pair {group:2}: {e}"),
            }
        }
    }
    Ok(())
}
