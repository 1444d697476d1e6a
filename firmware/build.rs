//! Hands the linker the memory map of the board being built, with cortex-m-rt's and (Pixhawk)
//! defmt's linker scripts: the repository's `memory.x` holds both boards' regions, and
//! `board-memory.x` (written here) makes the built board's cortex-m-rt's FLASH and RAM:
//! - `pixhawk6c`: the Pixhawk 6C application map behind the bootloader;
//! - `qemu`: mps2-an500's, and an empty `device.x` (this crate's vector table,
//!   `board::qemu::__INTERRUPTS`, names every handler itself).

use std::{env, fs, path::PathBuf};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("set by cargo"));
    // The memory map is the repository's `memory.x` (cortex-m-rt's convention; the linker
    // runs in the workspace root and finds it there for either board). It names each board's
    // regions; this picks the board's as cortex-m-rt's FLASH and RAM.
    let qemu = env::var_os("CARGO_FEATURE_QEMU").is_some();
    let (flash, ram) = if qemu {
        ("QEMU_CODE", "QEMU_DATA")
    } else {
        ("PIXHAWK6C_FLASH", "PIXHAWK6C_RAM")
    };
    fs::write(
        out.join("board-memory.x"),
        format!("REGION_ALIAS(\"FLASH\", {flash});\nREGION_ALIAS(\"RAM\", {ram});\n"),
    )
    .expect("OUT_DIR is writable");
    if qemu {
        fs::write(
            out.join("device.x"),
            "/* mps2-an500: the vector table names its handlers (board/qemu/mod.rs). */\n",
        )
        .expect("OUT_DIR is writable");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=../memory.x");
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
