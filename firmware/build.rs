//! Hands the linker the memory map of the board being built, with cortex-m-rt's and (Pixhawk)
//! defmt's linker scripts: the repository's `memory.x` holds both boards' regions, and
//! `board-memory.x` (written here) makes the built board's cortex-m-rt's FLASH and RAM:
//! - `pixhawk6c`: the Pixhawk 6C application map behind the bootloader;
//! - `qemu`: mps2-an500's, and an empty `device.x` (this crate's vector table,
//!   `board::qemu::__INTERRUPTS`, names every handler itself).
//!
//! It also writes the component metadata the vehicle serves over MAVLink FTP
//! (docs/ground-link.md#parameter-metadata) from the parameter table itself (`shared`, with
//! its descriptions, is a build dependency): `comp_param.json`, `comp_general.json` and
//! `metadata.rs` (the files as `link::ftp::ReadOnlyFile`s, the general file's CRC-32).

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
    write_metadata(&out, qemu);
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

/// The parameter metadata and the general file pointing at it, generated from the table.
fn write_metadata(out: &std::path::Path, qemu: bool) {
    use shared::mission::params::metadata;
    let mut parameters = String::new();
    metadata::parameter_json(&mut parameters).expect("writing to a String");
    let model = if qemu {
        "QEMU mps2-an500"
    } else {
        "Pixhawk 6C"
    };
    let version = env::var("CARGO_PKG_VERSION").expect("set by cargo");
    let mut general = String::new();
    metadata::general_json(
        &mut general,
        model,
        &version,
        metadata::PARAMETER_URI,
        metadata::crc32(parameters.as_bytes()),
    )
    .expect("writing to a String");
    fs::write(out.join("comp_param.json"), &parameters).expect("OUT_DIR is writable");
    fs::write(out.join("comp_general.json"), &general).expect("OUT_DIR is writable");
    let code = format!(
        "/// The component metadata files, generated from the parameter table at build time.\n\
         pub static FILES: [link::ftp::ReadOnlyFile; 2] = [\n\
         link::ftp::ReadOnlyFile {{ path: {general_path:?}, \
         contents: include_bytes!(concat!(env!(\"OUT_DIR\"), \"/comp_general.json\")) }},\n\
         link::ftp::ReadOnlyFile {{ path: {param_path:?}, \
         contents: include_bytes!(concat!(env!(\"OUT_DIR\"), \"/comp_param.json\")) }},\n];\n\
         /// CRC-32 of the general metadata file (`COMPONENT_METADATA`'s `file_crc`).\n\
         pub const GENERAL_CRC: u32 = {crc:#010x};\n",
        general_path = metadata::GENERAL_PATH,
        param_path = metadata::PARAMETER_PATH,
        crc = metadata::crc32(general.as_bytes()),
    );
    fs::write(out.join("metadata.rs"), code).expect("OUT_DIR is writable");
}
