//! The payload-description decoder and its checks (`shared::scenario_wire`, with
//! `shared::scenario`'s rules): any bytes, as a file uploaded to the vehicle. The first byte
//! is a mode: odd, the file's last four bytes are replaced by the CRC-32 of the rest, so that
//! mutated files get past the checksum to the fields and their checks. Never a panic;
//! `decode_and_check` decodes as `decode` does; what decodes encodes back to the same bytes
//! (or is refused by the encoder and by the checks alike); a checked scenario, encoded again,
//! passes the checks again, and the vehicle's planner takes it: loaded, one of each job the
//! mission asks for before the flight runs without a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use shared::estimation::Measurement;
use shared::mission::{JobRequest, JobResult, MissionConfig, MissionPlanner};
use shared::scenario::Scenario;
use shared::scenario_wire::{MAX_ENCODED_LEN, decode, decode_and_check, encode, encode_scenario};

const CRC32: crc::Crc<u32, crc::NoTable> =
    crc::Crc::<u32, crc::NoTable>::new(&crc::CRC_32_ISO_HDLC);

fuzz_target!(|input: &[u8]| {
    let Some((&mode, file)) = input.split_first() else {
        return;
    };
    let mut file = file.to_vec();
    if mode & 1 == 1 && file.len() >= 4 {
        let n = file.len() - 4;
        let crc = CRC32.checksum(&file[..n]);
        file[n..].copy_from_slice(&crc.to_le_bytes());
    }
    let data = &file[..];
    let decoded = decode(data);
    let checked = decode_and_check(data);
    match (&decoded, &checked) {
        (Err(_), Ok(_)) => panic!("decode refuses what decode_and_check takes"),
        (Ok(wire), Ok((wire2, _))) => assert_eq!(wire, wire2),
        _ => {}
    }
    let Ok(wire) = decoded else {
        return;
    };
    // What was read encodes back to the same bytes. (The encoder refuses early a robot count
    // past the table's, which the decoder reads as a byte for the checks to refuse by name.)
    let mut out = [0u8; MAX_ENCODED_LEN];
    match encode(&wire.name, &wire.input(), &mut out) {
        Ok(len) => assert_eq!(&out[..len], data, "decode then encode changes the bytes"),
        Err(e) => {
            assert!(
                checked.is_err(),
                "the checks accept what the encoder refuses: {e}"
            );
            return;
        }
    }
    let Ok((_, scenario)) = checked else {
        return;
    };
    // The checked scenario, encoded again, passes the same checks.
    let len = encode_scenario(&wire.name, &scenario, &mut out).expect("a checked scenario encodes");
    let (_, again) = decode_and_check(&out[..len]).expect("a checked scenario passes again");
    assert_eq!(again.robots.count(), scenario.robots.count());
    plan(&scenario);
});

/// What the vehicle's job task does with a checked description: the planner loaded with it,
/// then one of each job the mission asks for before the flight, from the robots' start.
fn plan(scenario: &Scenario) {
    let mut planner = Box::new(MissionPlanner::UNLOADED);
    if planner.load(scenario, MissionConfig::DEFAULT).is_err() {
        return;
    }
    let robots = scenario.robots.initial.clone();
    let pair = planner.run(&JobRequest::SelectPair {
        robots: robots.clone(),
    });
    if let JobResult::Pair(Ok(lift)) = pair {
        let thrust = scenario.robots.max_thrust * 0.5;
        for reading in [Measurement::Lifted { thrust }, Measurement::CouldNotLift] {
            planner.run(&JobRequest::Update {
                group: lift.group,
                reading,
            });
        }
    }
    planner.run(&JobRequest::DecideFormation {
        robots: robots.clone(),
    });
    planner.run(&JobRequest::BuildFlight { robots });
}
