//! The parameter metadata (docs/ground-link.md#parameter-metadata): the files the firmware's
//! build script writes from the parameter table parse as JSON, name every parameter with its
//! type, default and range, and the general file points at the parameter file (served
//! xz-compressed) with the CRC-32 of the file as served; both come back whole through the
//! vehicle's FTP server, and the parameter file decompresses to the JSON.

use link::ftp::{ErrorCode, FtpMessage, Opcode, ReadOnlyFile, Server};
use serde_json::Value;
use shared::mission::params::{TABLE, metadata};

/// The files as the build script makes them (for the Pixhawk): the general file, the
/// parameter file's JSON and the parameter file as served, compressed. (The build script's
/// encoder compresses; this one, lzma-rs's, only stores the bytes in an xz stream, which is
/// all these tests need.)
fn files() -> (String, String, Vec<u8>) {
    let mut parameters = String::new();
    metadata::parameter_json(&mut parameters).expect("writing to a String");
    let mut compressed = Vec::new();
    lzma_rs::xz_compress(&mut parameters.as_bytes(), &mut compressed).expect("writing to a Vec");
    let mut general = String::new();
    metadata::general_json(
        &mut general,
        "Pixhawk 6C",
        "0.1.0",
        metadata::PARAMETER_URI,
        metadata::crc32(&compressed),
    )
    .expect("writing to a String");
    (general, parameters, compressed)
}

/// Whether the JSON number reads back as exactly `b` (the shortest decimal of an f32 does).
fn close(a: &Value, b: f32) -> bool {
    a.as_f64().is_some_and(|a| a as f32 == b)
}

#[test]
fn the_parameter_file_lists_every_parameter_as_the_table_has_it() {
    let (_, parameters, _) = files();
    let json: Value = serde_json::from_str(&parameters).expect("valid JSON");
    assert_eq!(json["version"], 1, "QGroundControl reads version 1 only");
    let list = json["parameters"].as_array().expect("a parameters array");
    assert_eq!(list.len(), TABLE.len());
    for (p, m) in TABLE.iter().zip(list) {
        assert_eq!(m["name"], p.name);
        assert_eq!(
            m["type"], "Float",
            "{}: MAV_PARAM_TYPE_REAL32 on the wire",
            p.name
        );
        assert_eq!(m["shortDesc"], p.doc, "{}", p.name);
        assert!(
            close(&m["default"], p.default_value()),
            "{}: {}",
            p.name,
            m["default"]
        );
        assert!(close(&m["min"], p.min), "{}: {}", p.name, m["min"]);
        assert!(close(&m["max"], p.max), "{}: {}", p.name, m["max"]);
        assert_eq!(m["group"], metadata::group(p.name));
        assert_eq!(
            m["rebootRequired"],
            Value::Null,
            "{}: nothing needs a reboot",
            p.name
        );
        if p.unit == "-" {
            assert_eq!(m["units"], Value::Null);
        } else {
            assert_eq!(m["units"], p.unit);
        }
        assert_eq!(m["decimalPlaces"] == 0, p.integer, "{}", p.name);
        // Only the schema's keys (its additionalProperties is false).
        for key in m.as_object().expect("an object").keys() {
            assert!(
                [
                    "name",
                    "type",
                    "shortDesc",
                    "units",
                    "default",
                    "min",
                    "max",
                    "decimalPlaces",
                    "increment",
                    "group"
                ]
                .contains(&key.as_str()),
                "{key}"
            );
        }
    }
}

#[test]
fn the_general_file_points_at_the_parameter_file_with_its_crc() {
    let (general, _, compressed) = files();
    let json: Value = serde_json::from_str(&general).expect("valid JSON");
    assert_eq!(json["version"], 1);
    let types = json["metadataTypes"].as_array().expect("metadataTypes");
    assert_eq!(types.len(), 1);
    assert_eq!(types[0]["type"], 1, "COMP_METADATA_TYPE_PARAMETER");
    assert_eq!(types[0]["uri"], metadata::PARAMETER_URI);
    assert_eq!(
        types[0]["fileCrc"].as_u64(),
        Some(u64::from(metadata::crc32(&compressed))),
        "the CRC of the file as served"
    );
    // zlib's CRC-32 (what QGroundControl and PX4 compute).
    assert_eq!(metadata::crc32(b"123456789"), 0xcbf4_3926);
    assert_eq!(
        metadata::GENERAL_URI.strip_prefix("mftp://"),
        Some(metadata::GENERAL_PATH)
    );
    assert_eq!(
        metadata::PARAMETER_URI.strip_prefix("mftp://"),
        Some(metadata::PARAMETER_PATH)
    );
    // Ground stations decompress by the name (QGroundControl and MAVSDK: one ending in
    // `.xz`); the general file stays plain JSON.
    assert!(metadata::PARAMETER_URI.ends_with(".json.xz"));
    assert!(metadata::GENERAL_URI.ends_with(".json"));
}

/// Reads `path` through `server` as QGroundControl does: `OpenFileRO`, `BurstReadFile`s from
/// the next offset until `EOF`, `TerminateSession`.
fn download(server: &mut Server<16>, files: &[ReadOnlyFile], path: &str) -> Vec<u8> {
    let mut seq = 100;
    let mut send = |m: FtpMessage| {
        let mut m = m;
        m.seq = seq;
        seq += 2;
        let request = FtpMessage::from_payload(&m.to_payload());
        FtpMessage::from_payload(&server.handle_with(&request, files).0.to_payload())
    };
    let mut open = FtpMessage::command(0, Opcode::OpenFileRO);
    open.set_data(path.as_bytes());
    let opened = send(open);
    assert_eq!(opened.opcode, Opcode::Ack as u8, "{path}");
    let len = u32::from_le_bytes(opened.data().try_into().expect("4 bytes")) as usize;
    let mut got = Vec::new();
    loop {
        let mut read = FtpMessage::command(0, Opcode::BurstReadFile);
        read.session = opened.session;
        read.offset = got.len() as u32;
        let answer = send(read);
        if answer.nak_code() == Some(ErrorCode::Eof) {
            break;
        }
        assert_eq!(answer.opcode, Opcode::Ack as u8);
        got.extend_from_slice(answer.data());
    }
    let mut terminate = FtpMessage::command(0, Opcode::TerminateSession);
    terminate.session = opened.session;
    assert_eq!(send(terminate).opcode, Opcode::Ack as u8);
    assert_eq!(got.len(), len);
    got
}

#[test]
fn both_files_come_whole_through_the_ftp_server() {
    let (general, json, compressed) = files();
    let general: &'static str = general.leak();
    let parameters: &'static [u8] = compressed.leak();
    let files = [
        ReadOnlyFile {
            path: metadata::GENERAL_PATH,
            contents: general.as_bytes(),
        },
        ReadOnlyFile {
            path: metadata::PARAMETER_PATH,
            contents: parameters,
        },
    ];
    let mut server = Server::<16>::new();
    assert_eq!(
        download(&mut server, &files, metadata::GENERAL_PATH),
        general.as_bytes()
    );
    let served = download(&mut server, &files, metadata::PARAMETER_PATH);
    assert_eq!(served, parameters);
    let mut decompressed = Vec::new();
    lzma_rs::xz_decompress(&mut served.as_slice(), &mut decompressed).expect("an xz stream");
    assert_eq!(decompressed, json.as_bytes());
    println!(
        "general file {} bytes, parameter file {} bytes",
        general.len(),
        parameters.len()
    );
}
