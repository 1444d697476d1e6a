//! Writes the seed corpora of `link_input` and `payload_wire` into `fuzz/seeds/TARGET/`
//! (each directory emptied first): `cargo run --manifest-path fuzz/Cargo.toml --example
//! seeds`. (`scenario_toml` starts from `tests/scenarios` and `tests/broken-scenarios`
//! themselves.) Each `link_input` seed is run through the vehicle once, so a seed that breaks
//! an invariant is caught here.

use std::fs;
use std::path::Path;

fn write(dir: &Path, seeds: &[(String, Vec<u8>)]) {
    let _ = fs::remove_dir_all(dir);
    fs::create_dir_all(dir).expect("seed directory");
    for (name, bytes) in seeds {
        fs::write(dir.join(name), bytes).expect("seed written");
    }
    let total: usize = seeds.iter().map(|(_, b)| b.len()).sum();
    println!("{}: {} seeds, {} bytes", dir.display(), seeds.len(), total);
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let link = fuzz::seeds::link_inputs();
    for (name, bytes) in &link {
        let vehicle = fuzz::vehicle::run(bytes).expect("a seed has its header");
        println!(
            "  {name}: {} steps, {} frames sent, phases {:?}",
            vehicle.steps, vehicle.sent, vehicle.phases
        );
        vehicle.restart_check();
    }
    write(&root.join("seeds/link_input"), &link);
    write(
        &root.join("seeds/payload_wire"),
        &fuzz::seeds::payload_inputs(),
    );
}
