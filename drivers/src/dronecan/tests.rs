//! The DroneCAN encodings against frames made by pydronecan 1.0.27, the reference
//! implementation (`drivers/tools/dronecan_vectors.py` prints these constants), and the
//! receiving side against lost, repeated and corrupted frames.

use super::bus_load::{BusLoad, wire_bits};
use super::esc::{
    EscStatus, RAW_COMMAND_ID, RAW_COMMAND_SIGNATURE, STATUS_BYTES, STATUS_ID, STATUS_SIGNATURE,
    decode_raw_command, encode_raw_command, raw_command,
};
use super::node_status::{Health, Mode, NODE_STATUS_ID, NODE_STATUS_SIGNATURE, NodeStatus};
use super::transfer::{
    CanFrame, FrameError, MAX_PAYLOAD, MessageId, Reassembler, frame_count, frames,
};

/// RAW_COMMAND_FOUR, from pydronecan 1.0.27.
const RAW_COMMAND_FOUR: &[(u32, &[u8])] = &[(
    0x05040601,
    &[0x00, 0x01, 0x90, 0x0f, 0xf7, 0xc0, 0x20, 0xc5],
)];
/// RAW_COMMAND_SIXTEEN, from pydronecan 1.0.27.
const RAW_COMMAND_SIXTEEN: &[(u32, &[u8])] = &[
    (
        0x05040601,
        &[0x11, 0x87, 0x00, 0x00, 0x8c, 0x24, 0x61, 0x9e],
    ),
    (
        0x05040601,
        &[0x1a, 0x46, 0x8c, 0x22, 0xbc, 0xad, 0x23, 0x3e],
    ),
    (
        0x05040601,
        &[0x3d, 0x4e, 0x18, 0x44, 0xed, 0x35, 0xe5, 0x1e],
    ),
    (
        0x05040601,
        &[0x60, 0x57, 0xa4, 0x67, 0x1d, 0xbe, 0xa7, 0x3e],
    ),
    (0x05040601, &[0x43, 0x40, 0x5e]),
];
/// ESC_STATUS, from pydronecan 1.0.27.
const ESC_STATUS: &[(u32, &[u8])] = &[
    (
        0x10040a17,
        &[0x22, 0x0d, 0x03, 0x00, 0x00, 0x00, 0x9a, 0x9f],
    ),
    (
        0x10040a17,
        &[0x4b, 0x80, 0x44, 0xb0, 0x5c, 0x78, 0xec, 0x3f],
    ),
    (0x10040a17, &[0xd5, 0x2c, 0x5f]),
];
/// NODE_STATUS, from pydronecan 1.0.27.
const NODE_STATUS: &[(u32, &[u8])] = &[(
    0x10015507,
    &[0x40, 0xe2, 0x01, 0x00, 0x42, 0xef, 0xbe, 0xc0],
)];

fn sixteen_commands() -> [i16; 16] {
    core::array::from_fn(|i| ((i * 547) % 8192) as i16)
}

fn esc_status() -> EscStatus {
    EscStatus {
        error_count: 3,
        voltage: 15.2,
        current: 4.5,
        temperature: 300.0,
        rpm: -5000,
        power_rating_pct: 42,
        esc_index: 11,
    }
}

fn node_status() -> NodeStatus {
    NodeStatus {
        uptime_sec: 123_456,
        health: Health::Warning,
        mode: Mode::Operational,
        sub_mode: 2,
        vendor_specific_status_code: 0xBEEF,
    }
}

/// The frames of `payload` sent as `id`, checked byte for byte against `expected`.
fn assert_frames(
    id: MessageId,
    signature: u64,
    tid: u8,
    payload: &[u8],
    expected: &[(u32, &[u8])],
) {
    let made: std::vec::Vec<CanFrame> = frames(id, signature, tid, payload).collect();
    assert_eq!(made.len(), expected.len(), "frames");
    assert_eq!(made.len(), frame_count(payload.len()));
    for (k, (frame, (want_id, want))) in made.iter().zip(expected).enumerate() {
        assert_eq!(frame.id, *want_id, "frame {k}'s identifier");
        assert_eq!(frame.bytes(), *want, "frame {k}'s data");
    }
}

fn can_frames(vector: &[(u32, &[u8])]) -> std::vec::Vec<CanFrame> {
    vector
        .iter()
        .map(|&(id, bytes)| {
            let mut data = [0u8; 8];
            data[..bytes.len()].copy_from_slice(bytes);
            CanFrame {
                id,
                data,
                len: bytes.len() as u8,
            }
        })
        .collect()
}

fn receive(vector: &[CanFrame], signature: u64) -> Result<std::vec::Vec<u8>, FrameError> {
    let mut rx = Reassembler::<4>::new();
    let mut whole = None;
    for (k, frame) in vector.iter().enumerate() {
        let got = rx.accept(frame, signature, k as u64 * 100)?;
        assert_eq!(
            got.is_some(),
            k + 1 == vector.len(),
            "whole only at the last frame"
        );
        whole = got;
    }
    Ok(whole.expect("a transfer").payload().to_vec())
}

#[test]
fn raw_commands_for_four_and_sixteen_escs_are_pydronecans_frames() {
    let id = |priority| MessageId {
        priority,
        data_type: RAW_COMMAND_ID,
        source: 1,
    };
    let mut buffer = [0u8; MAX_PAYLOAD];
    let len = encode_raw_command(&[0, 100, 8191, -8192], &mut buffer).expect("fits");
    assert_frames(
        id(5),
        RAW_COMMAND_SIGNATURE,
        5,
        &buffer[..len],
        RAW_COMMAND_FOUR,
    );
    let len = encode_raw_command(&sixteen_commands(), &mut buffer).expect("fits");
    assert_eq!(len, 28, "16 x 14 bits");
    assert_frames(
        id(5),
        RAW_COMMAND_SIGNATURE,
        30,
        &buffer[..len],
        RAW_COMMAND_SIXTEEN,
    );
    let payload = receive(&can_frames(RAW_COMMAND_SIXTEEN), RAW_COMMAND_SIGNATURE).expect("whole");
    let mut commands = [0i16; 20];
    assert_eq!(decode_raw_command(&payload, &mut commands), 16);
    assert_eq!(commands[..16], sixteen_commands());
}

#[test]
fn esc_status_and_node_status_are_pydronecans_frames_both_ways() {
    let mut buffer = [0u8; MAX_PAYLOAD];
    let len = esc_status().encode(&mut buffer).expect("fits");
    let id = MessageId {
        priority: 16,
        data_type: STATUS_ID,
        source: 23,
    };
    assert_frames(id, STATUS_SIGNATURE, 31, &buffer[..len], ESC_STATUS);
    let payload = receive(&can_frames(ESC_STATUS), STATUS_SIGNATURE).expect("whole");
    let status = EscStatus::decode(&payload).expect("a status");
    assert_eq!(status.rpm, -5000);
    assert_eq!(status.esc_index, 11);
    assert_eq!(status.power_rating_pct, 42);
    assert_eq!(status.error_count, 3);
    assert!((status.voltage - 15.2).abs() < 0.01, "{}", status.voltage);
    assert_eq!((status.current, status.temperature), (4.5, 300.0));

    let len = node_status().encode(&mut buffer).expect("fits");
    let id = MessageId {
        priority: 16,
        data_type: NODE_STATUS_ID,
        source: 7,
    };
    assert_frames(id, NODE_STATUS_SIGNATURE, 0, &buffer[..len], NODE_STATUS);
    let payload = receive(&can_frames(NODE_STATUS), NODE_STATUS_SIGNATURE).expect("whole");
    assert_eq!(NodeStatus::decode(&payload), Some(node_status()));
}

#[test]
fn a_lost_repeated_or_corrupted_frame_never_makes_a_transfer() {
    let good = can_frames(ESC_STATUS);
    let lost = [good[0], good[2]];
    assert_eq!(receive(&lost, STATUS_SIGNATURE), Err(FrameError::Toggle));
    let repeated = [good[0], good[1], good[1], good[2]];
    assert_eq!(
        receive(&repeated, STATUS_SIGNATURE),
        Err(FrameError::Toggle)
    );
    let mut flipped = good.clone();
    flipped[1].data[3] ^= 0x10;
    assert_eq!(receive(&flipped, STATUS_SIGNATURE), Err(FrameError::Crc));
    assert_eq!(
        receive(&good, RAW_COMMAND_SIGNATURE),
        Err(FrameError::Crc),
        "another data type's signature"
    );
    assert_eq!(
        receive(&good[1..], STATUS_SIGNATURE),
        Err(FrameError::NoStart)
    );
    let mut other = good.clone();
    other[2].data[2] = (other[2].data[2] & !0x1f) | 3;
    assert_eq!(
        receive(&other, STATUS_SIGNATURE),
        Err(FrameError::TransferId)
    );
    let mut service = good[0];
    service.id |= 0x80;
    let mut rx = Reassembler::<1>::new();
    assert_eq!(
        rx.accept(&service, STATUS_SIGNATURE, 0),
        Err(FrameError::NotAMessage)
    );
    let empty = CanFrame {
        id: good[0].id,
        data: [0; 8],
        len: 0,
    };
    assert_eq!(
        rx.accept(&empty, STATUS_SIGNATURE, 0),
        Err(FrameError::Empty)
    );
    // A new start replaces the transfer in progress: the good one after a broken start.
    let again: std::vec::Vec<CanFrame> =
        [good[0]].into_iter().chain(good.iter().copied()).collect();
    assert!(receive(&again[1..], STATUS_SIGNATURE).is_ok());
    let mut rx = Reassembler::<1>::new();
    assert_eq!(rx.accept(&again[0], STATUS_SIGNATURE, 0), Ok(None));
    assert_eq!(
        rx.accept(&again[1], STATUS_SIGNATURE, 1),
        Ok(None),
        "restarted"
    );
    assert_eq!(rx.accept(&again[2], STATUS_SIGNATURE, 2), Ok(None));
    assert!(
        rx.accept(&again[3], STATUS_SIGNATURE, 3)
            .is_ok_and(|t| t.is_some())
    );
}

#[test]
fn transfers_from_two_escs_interleaved_both_arrive() {
    let mut rx = Reassembler::<4>::new();
    let mut buffer = [[0u8; MAX_PAYLOAD]; 2];
    let mut sent = std::vec::Vec::new();
    for (k, b) in buffer.iter_mut().enumerate() {
        let status = EscStatus {
            esc_index: k as u8,
            rpm: 1000 * (k as i32 + 1),
            ..esc_status()
        };
        let len = status.encode(b).expect("fits");
        let id = MessageId {
            priority: 16,
            data_type: STATUS_ID,
            source: 20 + k as u8,
        };
        sent.push(frames(id, STATUS_SIGNATURE, 9, &b[..len]).collect::<std::vec::Vec<_>>());
    }
    let mut got = std::vec::Vec::new();
    for i in 0..3 {
        for esc in &sent {
            if let Some(t) = rx
                .accept(&esc[i], STATUS_SIGNATURE, i as u64)
                .expect("in order")
            {
                got.push(EscStatus::decode(t.payload()).expect("a status"));
            }
        }
    }
    assert_eq!(
        got.iter().map(|s| s.rpm).collect::<std::vec::Vec<_>>(),
        [1000, 2000]
    );
}

#[test]
fn raw_commands_scale_and_clamp_a_rotors_command_fraction() {
    assert_eq!(raw_command(0.0), 0);
    assert_eq!(raw_command(-0.3), 0);
    assert_eq!(raw_command(f32::NAN), 0);
    assert_eq!(raw_command(0.5), 4096);
    assert_eq!(raw_command(1.0), 8191);
    assert_eq!(raw_command(7.0), 8191);
    let mut buffer = [0u8; MAX_PAYLOAD];
    assert!(
        encode_raw_command(&[0; 21], &mut buffer).is_err(),
        "21 ESCs"
    );
}

#[test]
fn a_frames_wire_length_counts_its_stuff_bits() {
    // Unstuffed, an extended frame is 67 + 8 n bits (SOF to interframe space); stuffing adds
    // at most one bit in four of the 54 + 8 n bits it covers (after the first five).
    for vector in [RAW_COMMAND_SIXTEEN, ESC_STATUS, NODE_STATUS] {
        for frame in can_frames(vector) {
            let n = u32::from(frame.len);
            let bits = wire_bits(&frame);
            assert!(bits > 67 + 8 * n, "{bits} bits: some stuffing");
            assert!(bits <= 67 + 8 * n + (54 + 8 * n - 1) / 4, "{bits} bits");
        }
    }
    let zeros = CanFrame {
        id: 0,
        data: [0; 8],
        len: 8,
    };
    let mut load = BusLoad::default();
    load.add(&zeros, 1000);
    assert_eq!(load.frames, 1000);
    assert!((load.share(1.0) - wire_bits(&zeros) as f32 / 1000.0).abs() < 1e-6);
}

#[test]
fn slots_the_size_of_a_status_take_a_status_and_refuse_a_longer_transfer_without_a_panic() {
    let status = EscStatus {
        error_count: 3,
        voltage: 15.5,
        current: 4.0,
        temperature: 300.0,
        rpm: 5_000,
        power_rating_pct: 50,
        esc_index: 2,
    };
    let mut frames = std::vec::Vec::new();
    status.send(12, 0, |f| frames.push(f));
    let mut rx = Reassembler::<1, STATUS_BYTES>::new();
    let whole = frames
        .iter()
        .map(|f| rx.accept(f, STATUS_SIGNATURE, 0).expect("taken"))
        .last()
        .flatten()
        .expect("whole");
    assert_eq!(EscStatus::decode(whole.payload()), Some(status));
    // Sixteen commands, 28 bytes, do not fit: refused as too long, the slot freed.
    let mut payload = [0u8; MAX_PAYLOAD];
    let len = encode_raw_command(&[100; 16], &mut payload).expect("fits");
    let id = MessageId {
        priority: 5,
        data_type: RAW_COMMAND_ID,
        source: 1,
    };
    let results: std::vec::Vec<_> = frames_of(id, &payload[..len])
        .iter()
        .map(|f| rx.accept(f, RAW_COMMAND_SIGNATURE, 0))
        .collect();
    assert!(results.contains(&Err(FrameError::TooLong)), "{results:?}");
    assert!(results.iter().all(|r| !matches!(r, Ok(Some(_)))));
}

fn frames_of(id: MessageId, payload: &[u8]) -> std::vec::Vec<CanFrame> {
    frames(id, RAW_COMMAND_SIGNATURE, 0, payload).collect()
}
