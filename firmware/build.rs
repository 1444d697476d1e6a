//! Hands the linker the memory map of the board being built, with cortex-m-rt's and (Pixhawk)
//! defmt's linker scripts: the repository's `memory.x` holds both boards' regions, and
//! `board-memory.x` (written here) makes the built board's cortex-m-rt's FLASH and RAM:
//! - `pixhawk6c`: the Pixhawk 6C application map behind the bootloader;
//! - `qemu`: mps2-an500's, and an empty `device.x` (this crate's vector table,
//!   `board::qemu::__INTERRUPTS`, names every handler itself).
//!
//! It also writes the component metadata the vehicle serves over MAVLink FTP
//! (docs/ground-link.md#parameter-metadata) from the parameter table itself (`shared`, with
//! its descriptions, is a build dependency): `comp_param.json.xz` (the parameter file,
//! xz-compressed: 3 KB of flash instead of 15), `comp_general.json` and `metadata.rs` (the
//! files as `link::ftp::ReadOnlyFile`s, the general file's CRC-32).

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
    let compressed = xz(parameters.as_bytes());
    let mut general = String::new();
    // The CRC of the file as served (compressed): what a ground station caches it by.
    metadata::general_json(
        &mut general,
        model,
        &version,
        metadata::PARAMETER_URI,
        metadata::crc32(&compressed),
    )
    .expect("writing to a String");
    fs::write(out.join("comp_param.json"), &parameters).expect("OUT_DIR is writable");
    fs::write(out.join("comp_param.json.xz"), &compressed).expect("OUT_DIR is writable");
    fs::write(out.join("comp_general.json"), &general).expect("OUT_DIR is writable");
    let code = format!(
        "/// The component metadata files, generated from the parameter table at build time.\n\
         pub static FILES: [link::ftp::ReadOnlyFile; 2] = [\n\
         link::ftp::ReadOnlyFile {{ path: {general_path:?}, \
         contents: include_bytes!(concat!(env!(\"OUT_DIR\"), \"/comp_general.json\")) }},\n\
         link::ftp::ReadOnlyFile {{ path: {param_path:?}, \
         contents: include_bytes!(concat!(env!(\"OUT_DIR\"), \"/comp_param.json.xz\")) }},\n];\n\
         /// CRC-32 of the general metadata file (`COMPONENT_METADATA`'s `file_crc`).\n\
         pub const GENERAL_CRC: u32 = {crc:#010x};\n",
        general_path = metadata::GENERAL_PATH,
        param_path = metadata::PARAMETER_PATH,
        crc = metadata::crc32(general.as_bytes()),
    );
    fs::write(out.join("metadata.rs"), code).expect("OUT_DIR is writable");
}

/// `json` as an `.xz` file (the MAVLink component metadata protocol's compression, which
/// ground stations must read): one LZMA2 block, a CRC-32 check (XZ Embedded, QGroundControl's
/// decoder, always has it; CRC-64 is optional there) and a 64 KiB dictionary, more than the
/// file needs and little for a decoder to allocate. Read back before it is used.
fn xz(json: &[u8]) -> Vec<u8> {
    use lzma_rust2::{CheckType, XzOptions, XzReader, XzWriter};
    use std::io::{Read, Write};
    let mut options = XzOptions::with_preset(9);
    options.lzma_options.dict_size = 64 << 10;
    options.set_check_sum_type(CheckType::Crc32);
    let mut writer = XzWriter::new(Vec::new(), options).expect("valid options");
    writer.write_all(json).expect("writing to a Vec");
    let compressed = writer.finish().expect("writing to a Vec");
    // The stream header's flags: the check is CRC-32.
    assert_eq!(compressed[6..8], [0x00, 0x01]);
    let mut back = Vec::new();
    XzReader::new(compressed.as_slice(), false)
        .read_to_end(&mut back)
        .expect("the stream just written");
    assert!(back == json, "the xz stream decompresses to the file");
    compressed
}
