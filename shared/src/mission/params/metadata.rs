//! The parameter table as MAVLink component metadata (docs/ground-link.md#parameter-metadata):
//! the parameter file (`COMP_METADATA_TYPE_PARAMETER`, the schema QGroundControl reads:
//! `version` 1 and one object per parameter with its type, description, unit, default and
//! range) and the general file (`COMP_METADATA_TYPE_GENERAL`) that points at it with its
//! CRC-32. Written from `TABLE` (with the `docs` feature) by the firmware's build script, so the files the vehicle
//! serves over MAVLink FTP always say what the table says.

#[cfg(feature = "docs")]
use super::{ParamSpec, TABLE};
#[cfg(feature = "docs")]
use core::fmt::{self, Write};

/// Where the vehicle serves the general metadata file over MAVLink FTP.
pub const GENERAL_PATH: &str = "/comp_general.json";
/// `COMPONENT_METADATA`'s `uri`: the general file on this component (`mftp://` and the path).
pub const GENERAL_URI: &str = "mftp:///comp_general.json";
/// Where the vehicle serves the parameter metadata file over MAVLink FTP: the JSON of
/// [`parameter_json`] compressed with xz (the protocol's compression; ground stations
/// decompress a file whose name ends in `.xz`).
pub const PARAMETER_PATH: &str = "/comp_param.json.xz";
/// The parameter file's URI, as the general file gives it.
pub const PARAMETER_URI: &str = "mftp:///comp_param.json.xz";

/// CRC-32 of a metadata file as the general file and `COMPONENT_METADATA` carry it (zlib's
/// CRC-32, ISO-HDLC). The same CRC guards the payload description file
/// ([`crate::scenario_wire`]) and the stored mission: one function, never inlined, so the
/// flight controller links the loop once rather than at each caller.
#[inline(never)]
pub fn crc32(bytes: &[u8]) -> u32 {
    const CRC32: crc::Crc<u32, crc::NoTable> =
        crc::Crc::<u32, crc::NoTable>::new(&crc::CRC_32_ISO_HDLC);
    CRC32.checksum(bytes)
}

#[cfg(feature = "docs")]
/// Writes `s` as a JSON string (quoted, escaped).
fn json_str(out: &mut impl Write, s: &str) -> fmt::Result {
    out.write_char('"')?;
    for c in s.chars() {
        match c {
            '"' => out.write_str("\\\"")?,
            '\\' => out.write_str("\\\\")?,
            c if (c as u32) < 0x20 => write!(out, "\\u{:04x}", c as u32)?,
            c => out.write_char(c)?,
        }
    }
    out.write_char('"')
}

#[cfg(feature = "docs")]
/// Writes `,"key":value` for a finite `value` (JSON has no NaN or infinity: nothing then).
fn json_number(out: &mut impl Write, key: &str, value: f32) -> fmt::Result {
    if value.is_finite() {
        // f32's Display is the shortest exact decimal, never an exponent: valid JSON.
        write!(out, ",\"{key}\":{value}")?;
    }
    Ok(())
}

#[cfg(feature = "docs")]
/// The group a parameter belongs to: its name up to the first `_` (`LIFT_RAMP`: `LIFT`).
pub fn group(name: &str) -> &str {
    name.split('_').next().unwrap_or(name)
}

#[cfg(feature = "docs")]
fn parameter(out: &mut impl Write, p: &ParamSpec) -> fmt::Result {
    out.write_str("{\"name\":")?;
    json_str(out, p.name)?;
    // On the wire every parameter is a MAV_PARAM_TYPE_REAL32 (link::param).
    out.write_str(",\"type\":\"Float\",\"shortDesc\":")?;
    json_str(out, p.doc)?;
    if p.unit != "-" {
        out.write_str(",\"units\":")?;
        json_str(out, p.unit)?;
    }
    json_number(out, "default", p.default_value())?;
    json_number(out, "min", p.min)?;
    json_number(out, "max", p.max)?;
    if p.integer {
        out.write_str(",\"decimalPlaces\":0,\"increment\":1")?;
    }
    out.write_str(",\"group\":")?;
    json_str(out, group(p.name))?;
    out.write_str("}")
}

#[cfg(feature = "docs")]
/// The parameter metadata file (`COMP_METADATA_TYPE_PARAMETER`): every parameter of
/// [`TABLE`], in table order, one per line.
pub fn parameter_json(out: &mut impl Write) -> fmt::Result {
    out.write_str("{\"version\":1,\"parameters\":[\n")?;
    for (i, p) in TABLE.iter().enumerate() {
        if i > 0 {
            out.write_str(",\n")?;
        }
        parameter(out, p)?;
    }
    out.write_str("\n]}\n")
}

#[cfg(feature = "docs")]
/// The general metadata file (`COMP_METADATA_TYPE_GENERAL`): the vendor and model, and the
/// parameter file at `parameter_uri` with its CRC-32 `parameter_crc`.
pub fn general_json(
    out: &mut impl Write,
    model: &str,
    firmware_version: &str,
    parameter_uri: &str,
    parameter_crc: u32,
) -> fmt::Result {
    out.write_str("{\"version\":1,\"vendorName\":\"rail-riding rotor transport\",\"modelName\":")?;
    json_str(out, model)?;
    out.write_str(",\"firmwareVersion\":")?;
    json_str(out, firmware_version)?;
    out.write_str(",\"metadataTypes\":[{\"type\":1,\"uri\":")?;
    json_str(out, parameter_uri)?;
    writeln!(out, ",\"fileCrc\":{parameter_crc}}}]}}")
}
