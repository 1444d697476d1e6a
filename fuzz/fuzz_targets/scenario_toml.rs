//! The host's scenario TOML loader (the `scenario-toml` crate's `parse`, which the simulator uses): any text as a
//! scenario file. Never a panic; an accepted scenario encodes as a payload description that
//! the vehicle's decoder and checks accept too (the host and the vehicle refuse the same).
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use shared::scenario_wire::{MAX_ENCODED_LEN, decode_and_check, encode_scenario};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(loaded) = scenario_toml::parse(text, Path::new("fuzz.toml")) else {
        return;
    };
    let mut out = [0u8; MAX_ENCODED_LEN];
    let len = encode_scenario(&loaded.name, &loaded.scenario, &mut out)
        .expect("an accepted scenario encodes");
    if let Err(e) = decode_and_check(&out[..len]) {
        panic!("the host accepts a scenario the vehicle refuses: {e}");
    }
});
