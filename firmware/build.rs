//! Hands the workspace's `memory.x` (the Pixhawk 6C application map behind the bootloader)
//! to the linker, with cortex-m-rt's and defmt's linker scripts.

use std::{env, fs, path::PathBuf};

fn main() {
    let manifest_dir = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let memory_x = manifest_dir.join("..").join("memory.x");
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("set by cargo"));
    let contents =
        fs::read(&memory_x).unwrap_or_else(|e| panic!("cannot read {}: {e}", memory_x.display()));
    fs::write(out.join("memory.x"), contents).expect("OUT_DIR is writable");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed={}", memory_x.display());
    println!("cargo:rerun-if-changed=build.rs");

    // Only the thumb target links a firmware image; a host `cargo check` of this crate would
    // not find these scripts.
    if env::var("TARGET").is_ok_and(|t| t.starts_with("thumb")) {
        println!("cargo:rustc-link-arg-bins=--nmagic");
        println!("cargo:rustc-link-arg-bins=-Tlink.x");
        println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
    }
}
