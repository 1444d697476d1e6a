//! Hands the linker the memory map of the board being built, with cortex-m-rt's and (Pixhawk)
//! defmt's linker scripts:
//! - `pixhawk6c`: `memory-pixhawk6c.x` (the Pixhawk 6C application map behind the
//!   bootloader);
//! - `qemu`: `memory-qemu.x` (mps2-an500), and an empty `device.x` (this crate's vector table,
//!   `board::qemu::__INTERRUPTS`, names every handler itself).

use std::{env, fs, path::PathBuf};

fn main() {
    let manifest_dir = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("set by cargo"));
    // The maps are not named memory.x in the source tree: the linker runs in the workspace root
    // and would find a file of that name there before this one.
    let qemu = env::var_os("CARGO_FEATURE_QEMU").is_some();
    let memory_x = if qemu {
        manifest_dir.join("memory-qemu.x")
    } else {
        manifest_dir.join("memory-pixhawk6c.x")
    };
    let contents =
        fs::read(&memory_x).unwrap_or_else(|e| panic!("cannot read {}: {e}", memory_x.display()));
    fs::write(out.join("memory.x"), contents).expect("OUT_DIR is writable");
    if qemu {
        fs::write(
            out.join("device.x"),
            "/* mps2-an500: the vector table names its handlers (board/qemu/mod.rs). */\n",
        )
        .expect("OUT_DIR is writable");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed={}", memory_x.display());
    println!("cargo:rerun-if-changed=build.rs");

    // Only the thumb target links a firmware image.
    if env::var("TARGET").is_ok_and(|t| t.starts_with("thumb")) {
        println!("cargo:rustc-link-arg-bins=--nmagic");
        println!("cargo:rustc-link-arg-bins=-Tlink.x");
        if !qemu {
            println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
        }
    }
}
