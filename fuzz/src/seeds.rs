//! The seed corpora (`fuzz/seeds/TARGET/`, written by `cargo run --example seeds`): for
//! `link_input`, one valid frame of each message the vehicle handles (behind the default
//! header) and a few whole sessions (an upload then a start, in HIL and with the IMU driver,
//! signed and not); for `payload_wire`, each scenario of `tests/scenarios` encoded as the
//! vehicle receives it, and a few damaged copies. (`scenario_toml` starts from the scenario
//! files of `tests/scenarios` and `tests/broken-scenarios` themselves.)

use std::path::Path;

use link::MessageData;
use link::command::{CommandWire, MotorTestRequest, OperatorCommand, command_long};
use link::frame::{Encoder, Frame};
use link::ftp::{FtpMessage, Opcode, PAYLOAD_PATH, Progress, Server, Upload};
use link::hil::{ImuSample, MocapFix, PlantSample, mocap_message};
use link::msg::{
    ATT_POS_MOCAP_DATA, COMMAND_LONG_DATA, HEARTBEAT_DATA, MANUAL_CONTROL_DATA,
    MISSION_REQUEST_LIST_DATA, MavEstimatorType, MavFrame, MavParamType, ODOMETRY_DATA,
    PARAM_REQUEST_LIST_DATA, PARAM_REQUEST_READ_DATA, PARAM_SET_DATA, SETUP_SIGNING_DATA,
    TIMESYNC_DATA,
};
use link::signing::Signing;
use link::vehicle::crc_extra;
use shared::control::vector::{Quat, Vec3};
use shared::scenario_wire::{MAX_ENCODED_LEN, encode_scenario};

use crate::vehicle::{Options, SEED_KEY, SEED_KEY_TIMESTAMP, TICK_US};

/// The scenario files of `tests/scenarios`, by name.
pub const SCENARIOS: [(&str, &str); 6] = [
    ("L-sim1", include_str!("../../tests/scenarios/L-sim1.toml")),
    ("L-sim2", include_str!("../../tests/scenarios/L-sim2.toml")),
    (
        "rect-ex1",
        include_str!("../../tests/scenarios/rect-ex1.toml"),
    ),
    (
        "rect-ex2",
        include_str!("../../tests/scenarios/rect-ex2.toml"),
    ),
    (
        "rect-sim1",
        include_str!("../../tests/scenarios/rect-sim1.toml"),
    ),
    (
        "rect-sim2",
        include_str!("../../tests/scenarios/rect-sim2.toml"),
    ),
];

/// A scenario file read by the host's loader and encoded as the vehicle receives it.
pub fn encoded_scenario(toml: &str) -> Vec<u8> {
    let loaded =
        scenario_toml::parse(toml, Path::new("seed.toml")).expect("the test scenarios load");
    let mut out = vec![0u8; MAX_ENCODED_LEN];
    let len = encode_scenario(&loaded.name, &loaded.scenario, &mut out).expect("it encodes");
    out.truncate(len);
    out
}

/// A ground station's frames (system 255, component 190, as the HIL plant's), signed when a
/// key is given.
pub struct Ground {
    encoder: Encoder,
    signing: Option<Signing>,
    /// The bytes so far.
    pub bytes: Vec<u8>,
}

impl Ground {
    /// A ground station that signs with `key`, or does not sign.
    pub fn new(key: Option<[u8; 32]>) -> Self {
        let signing = key.map(|k| {
            let mut s = Signing::new();
            // A little ahead of the vehicle's stored timestamp: its frames are newer.
            s.set_key(k, SEED_KEY_TIMESTAMP + 1000, 0, 3);
            s
        });
        Self {
            encoder: Encoder::new(link::PLANT_SYSTEM_ID, link::PLANT_COMPONENT_ID),
            signing,
            bytes: Vec::new(),
        }
    }

    /// Appends `message`.
    pub fn send<M: MessageData>(&mut self, message: &M) -> &mut Self {
        self.send_extended(message, &[])
    }

    /// Appends `message` with the raw bytes of its extension fields.
    pub fn send_extended<M: MessageData>(&mut self, message: &M, ext: &[u8]) -> &mut Self {
        let mut f = Frame::default();
        self.encoder.encode_extended(message, ext, &mut f);
        if let (Some(s), Some(extra)) = (&mut self.signing, crc_extra(M::ID)) {
            s.sign(&mut f, extra, 0);
        }
        self.bytes.extend_from_slice(f.bytes());
        self
    }

    /// Appends an upload of `contents` as the payload description, each command answered by
    /// a server of the vehicle's (the vehicle answers the same way).
    pub fn upload(&mut self, contents: &[u8]) -> &mut Self {
        let mut server = Server::<MAX_ENCODED_LEN>::new();
        let mut up = Upload::new(PAYLOAD_PATH, contents);
        loop {
            let request = up.current();
            self.send(&request.to_message(link::VEHICLE_SYSTEM_ID, link::VEHICLE_COMPONENT_ID));
            let (answer, _) = server.handle(&request);
            match up.on_answer(&answer) {
                Ok(Progress::Done) => return self,
                Ok(_) => {}
                Err(e) => panic!("the seed upload fails: {e}"),
            }
        }
    }

    /// Appends `n` HIL_SENSOR samples at rest, each with a motion-capture fix at the origin,
    /// [`TICK_US`] apart from `start_us`.
    pub fn hil_steps(&mut self, start_us: u64, n: u64) -> &mut Self {
        for i in 0..n {
            let time_us = start_us + i * TICK_US;
            let imu = PlantSample {
                time_us,
                imu: ImuSample {
                    gyro: Vec3::new(0.0, 0.0, crate::rest_noise(time_us)),
                    accel: Vec3::new(0.0, 0.0, -shared::scenario::GRAVITY),
                },
            };
            self.send(&imu.to_message());
            let fix = MocapFix {
                stamp_us: time_us,
                position: Vec3::ZERO,
                attitude: Quat::IDENTITY,
            };
            self.send(&mocap_message(&fix));
        }
        self
    }
}

/// A seed: the header of `options` (with the checksums recomputed, so that mutations of its
/// frames reach the services) and the ground's bytes.
fn input(options: Options, ground: &Ground) -> Vec<u8> {
    let options = Options {
        fix_checksums: true,
        ..options
    };
    let mut out = options.header().to_vec();
    out.extend_from_slice(&ground.bytes);
    out
}

fn one<M: MessageData>(message: &M) -> Vec<u8> {
    input(Options::default(), Ground::new(None).send(message))
}

/// A joystick's `MANUAL_CONTROL` to the vehicle (x forward, y right, z throttle 0..1000 with
/// 500 centred, r yaw).
fn joystick(x: i16, y: i16, z: i16, r: i16) -> MANUAL_CONTROL_DATA {
    MANUAL_CONTROL_DATA {
        target: link::VEHICLE_SYSTEM_ID,
        x,
        y,
        z,
        r,
        ..MANUAL_CONTROL_DATA::default()
    }
}

fn param_name(name: &str) -> [u8; 16] {
    let mut n = [0u8; 16];
    n[..name.len()].copy_from_slice(name.as_bytes());
    n
}

fn ftp(seq: u16, opcode: Opcode, data: &[u8]) -> FtpMessage {
    let mut m = FtpMessage::command(seq, opcode);
    m.set_data(data);
    m
}

/// The `link_input` seeds, by file name.
pub fn link_inputs() -> Vec<(String, Vec<u8>)> {
    let to_us = |m: FtpMessage| m.to_message(link::VEHICLE_SYSTEM_ID, link::VEHICLE_COMPONENT_ID);
    let param = shared::mission::params::TABLE[0].name;
    let mut seeds: Vec<(&str, Vec<u8>)> = vec![
        ("heartbeat", one(&HEARTBEAT_DATA::default())),
        ("gcs-heartbeat", one(&link::vehicle::gcs_heartbeat())),
        ("battery-status", one(&link::vehicle::battery_status(13.1))),
        (
            "command-start",
            one(&OperatorCommand::Start.to_command_long()),
        ),
        (
            "command-abort",
            one(&OperatorCommand::Abort.to_command_long()),
        ),
        (
            "command-land",
            one(&OperatorCommand::LandNow.to_command_long()),
        ),
        (
            "command-confirm-rails",
            one(&OperatorCommand::ConfirmRails.to_command_long()),
        ),
        (
            "command-jog",
            one(&OperatorCommand::Jog {
                robot: 2,
                micrometres: 20_000,
            }
            .to_command_long()),
        ),
        (
            "command-calibrate-gyro",
            one(
                &OperatorCommand::Calibrate(link::command::CalibrationKind::Gyro).to_command_long(),
            ),
        ),
        (
            "command-motor-test",
            one(&OperatorCommand::MotorTest(MotorTestRequest {
                first: 1,
                count: 2,
                permille: 100,
                millis: 1_000,
            })
            .to_command_long()),
        ),
        (
            "command-kill",
            one(&OperatorCommand::Kill.to_command_long()),
        ),
        (
            "command-position",
            one(&OperatorCommand::Position.to_command_long()),
        ),
        ("manual-control", one(&joystick(300, 0, 500, 0))),
        (
            "command-arm",
            one(&command_long(
                link::msg::MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
                1.0,
                0.0,
            )),
        ),
        (
            "command-request-version",
            one(&command_long(
                link::msg::MavCmd::MAV_CMD_REQUEST_MESSAGE,
                148.0,
                0.0,
            )),
        ),
        (
            "command-request-sys-status",
            one(&command_long(
                link::msg::MavCmd::MAV_CMD_REQUEST_MESSAGE,
                1.0,
                0.0,
            )),
        ),
        (
            "command-set-interval",
            one(&command_long(
                link::msg::MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
                31.0,
                20_000.0,
            )),
        ),
        (
            "command-unknown",
            one(&COMMAND_LONG_DATA {
                target_system: 1,
                ..command_long(link::msg::MavCmd::MAV_CMD_DO_SET_MODE, 0.0, 0.0)
            }),
        ),
        (
            "param-list",
            one(&PARAM_REQUEST_LIST_DATA {
                target_system: 1,
                target_component: 1,
            }),
        ),
        (
            "param-read-index",
            one(&PARAM_REQUEST_READ_DATA {
                param_index: 3,
                target_system: 1,
                target_component: 1,
                param_id: param_name("").into(),
            }),
        ),
        (
            "param-read-name",
            one(&PARAM_REQUEST_READ_DATA {
                param_index: -1,
                target_system: 1,
                target_component: 1,
                param_id: param_name(param).into(),
            }),
        ),
        (
            "param-set",
            one(&PARAM_SET_DATA {
                param_value: shared::mission::params::TABLE[0].default_value(),
                target_system: 1,
                target_component: 1,
                param_id: param_name(param).into(),
                param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
            }),
        ),
        (
            "mission-list",
            one(&MISSION_REQUEST_LIST_DATA {
                target_system: 1,
                target_component: 1,
            }),
        ),
        ("timesync-request", one(&TIMESYNC_DATA { tc1: 0, ts1: 42 })),
        ("timesync-answer", one(&TIMESYNC_DATA { tc1: 5, ts1: 0 })),
        ("hil-sensor", one(&PlantSample::AT_REST.to_message())),
        (
            "att-pos-mocap",
            one(&ATT_POS_MOCAP_DATA {
                q: [1.0, 0.0, 0.0, 0.0],
                ..Default::default()
            }),
        ),
        (
            "odometry-mocap",
            input(
                Options::default(),
                Ground::new(None).send_extended(
                    &ODOMETRY_DATA {
                        time_usec: 7,
                        q: [1.0, 0.0, 0.0, 0.0],
                        frame_id: MavFrame::MAV_FRAME_LOCAL_NED,
                        ..Default::default()
                    },
                    &[0, MavEstimatorType::MAV_ESTIMATOR_TYPE_MOCAP as u8],
                ),
            ),
        ),
        (
            "setup-signing",
            input(
                Options {
                    key_setup_allowed: true,
                    ..Options::default()
                },
                Ground::new(None).send(&SETUP_SIGNING_DATA {
                    initial_timestamp: SEED_KEY_TIMESTAMP,
                    secret_key: SEED_KEY,
                    target_system: 1,
                    target_component: 1,
                }),
            ),
        ),
        ("ftp-reset", one(&to_us(ftp(0, Opcode::ResetSessions, &[])))),
        (
            "ftp-create",
            one(&to_us(ftp(0, Opcode::CreateFile, PAYLOAD_PATH.as_bytes()))),
        ),
        (
            "ftp-open",
            one(&to_us(ftp(0, Opcode::OpenFileWO, PAYLOAD_PATH.as_bytes()))),
        ),
        ("ftp-write", one(&to_us(ftp(0, Opcode::WriteFile, b"RTSC")))),
        (
            "ftp-terminate",
            one(&to_us(ftp(0, Opcode::TerminateSession, &[]))),
        ),
    ];
    let rect = encoded_scenario(SCENARIOS[4].1);
    // An upload and a start, then 0.1 s of lockstep HIL with motion capture.
    let mut g = Ground::new(None);
    g.upload(&rect)
        .send(&link::vehicle::gcs_heartbeat())
        .send(&OperatorCommand::ConfirmRails.to_command_long())
        .send(&OperatorCommand::Start.to_command_long())
        .hil_steps(TICK_US, 40);
    seeds.push(("session-upload-start-hil", input(Options::default(), &g)));
    // The same, signed, on a vehicle whose key is stored.
    let mut g = Ground::new(Some(SEED_KEY));
    g.upload(&rect)
        .send(&link::vehicle::gcs_heartbeat())
        .send(&OperatorCommand::ConfirmRails.to_command_long())
        .send(&OperatorCommand::Start.to_command_long())
        .hil_steps(TICK_US, 40)
        .send(&OperatorCommand::Abort.to_command_long());
    let signed = Options {
        key_stored: true,
        ..Options::default()
    };
    seeds.push(("session-signed-upload-start", input(signed, &g)));
    // A stored payload, the IMU driver with motion capture: start, then heartbeats (each
    // gives the driver 255 steps, 0.64 s) through the checks, the lifts and on.
    let driver = Options {
        payload_stored: true,
        imu_driver: true,
        mocap: true,
        ticks: 255,
        ..Options::default()
    };
    let mut g = Ground::new(None);
    g.send(&link::vehicle::gcs_heartbeat())
        .send(&OperatorCommand::ConfirmRails.to_command_long())
        .send(&OperatorCommand::Start.to_command_long());
    for _ in 0..80 {
        g.send(&link::vehicle::gcs_heartbeat());
    }
    seeds.push(("session-stored-payload-driver", input(driver, &g)));
    // An upload (its checksum recomputed at the end, so mutations of it reach the checks and
    // the mission), a start, then the IMU driver with motion capture for 20 s.
    let mut g = Ground::new(None);
    g.upload(&rect)
        .send(&link::vehicle::gcs_heartbeat())
        .send(&OperatorCommand::ConfirmRails.to_command_long())
        .send(&OperatorCommand::Start.to_command_long());
    for _ in 0..40 {
        g.send(&link::vehicle::gcs_heartbeat());
    }
    let upload = Options {
        imu_driver: true,
        mocap: true,
        ticks: 200,
        fix_payload_checksum: true,
        ..Options::default()
    };
    seeds.push(("session-upload-driver", input(upload, &g)));
    // A joystick that flies: its MANUAL_CONTROL through the start and the checks, Position
    // mode asked for on the ground (the sticks take over after the take-off), then silence.
    let mut g = Ground::new(None);
    g.send(&link::vehicle::gcs_heartbeat())
        .send(&joystick(0, 0, 500, 0))
        .send(&OperatorCommand::ConfirmRails.to_command_long())
        .send(&OperatorCommand::Position.to_command_long());
    for k in 0..40 {
        g.send(&link::vehicle::gcs_heartbeat()).send(&joystick(
            if k % 2 == 0 { 400 } else { 0 },
            0,
            500,
            0,
        ));
    }
    seeds.push((
        "session-joystick-position",
        input(
            Options {
                ticks: 40,
                ..driver
            },
            &g,
        ),
    ));
    // A parameter write and a kill while running.
    let mut g = Ground::new(None);
    g.send(&link::vehicle::gcs_heartbeat())
        .send(&OperatorCommand::ConfirmRails.to_command_long())
        .send(&OperatorCommand::Start.to_command_long())
        .send(&link::vehicle::gcs_heartbeat())
        .send(&PARAM_SET_DATA {
            param_value: 1.0,
            target_system: 1,
            target_component: 1,
            param_id: param_name(param).into(),
            param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
        })
        .send(&OperatorCommand::Kill.to_command_long())
        .send(&link::vehicle::gcs_heartbeat());
    seeds.push((
        "session-running-param-kill",
        input(
            Options {
                ticks: 20,
                stalled_robots: 0x04,
                faults_from: 200,
                ..driver
            },
            &g,
        ),
    ));
    // Checksums as they come: garbage, a corrupted frame, then good frames.
    let mut raw = Options::default().header().to_vec();
    raw.extend([0x00, 0x55, 0xFE, 0x01, 0x13]);
    let mut g = Ground::new(None);
    g.send(&link::vehicle::gcs_heartbeat());
    let mut bad = g.bytes.clone();
    let n = bad.len();
    bad[n - 1] ^= 0x20;
    raw.extend(bad);
    g.bytes.clear();
    g.send(&link::vehicle::gcs_heartbeat())
        .send(&OperatorCommand::ConfirmRails.to_command_long())
        .send(&OperatorCommand::Start.to_command_long());
    raw.extend(&g.bytes);
    seeds.push(("raw-garbage-and-frames", raw));
    seeds
        .into_iter()
        .map(|(name, bytes)| (name.to_string(), bytes))
        .collect()
}

/// The `payload_wire` seeds, by file name: a mode byte (1: the target recomputes the
/// checksum; 0: it does not) and the file.
pub fn payload_inputs() -> Vec<(String, Vec<u8>)> {
    let with_mode = |mode: u8, file: &[u8]| [&[mode], file].concat();
    let mut seeds = Vec::new();
    for (name, toml) in SCENARIOS {
        seeds.push((
            format!("{name}.rtsc"),
            with_mode(1, &encoded_scenario(toml)),
        ));
    }
    let rect = encoded_scenario(SCENARIOS[4].1);
    seeds.push((
        "truncated.rtsc".into(),
        with_mode(0, &rect[..rect.len() / 2]),
    ));
    let mut damaged = rect.clone();
    damaged[20] ^= 0x10;
    seeds.push(("bad-checksum.rtsc".into(), with_mode(0, &damaged)));
    seeds
}
