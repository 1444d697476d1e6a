//! Hardware in the loop under QEMU (issue 11, sections 2 to 4): the firmware's ARM image
//! (`cargo fw-qemu`) on `qemu-system-arm -M mps2-an500`, the plant in lockstep over MAVLink.
//!
//! These tests need `qemu-system-arm` and the image at
//! `target/thumbv7em-none-eabihf/release/firmware-qemu` (or `FIRMWARE_QEMU_ELF`). Without
//! them each test says it was skipped and why, and passes; with `HIL_REQUIRED=1` (CI) it
//! fails instead. One QEMU runs at a time.
//!
//! The firmware's autonomy is still the placeholder behind its seam (`firmware/src/app/
//! autonomy.rs`: zero thrust, one synthetic job, done two seconds after the start); the checks
//! on its job and phases follow it and change when the mission is integrated.

use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use host_sim::hil::qemu::{self, Qemu};
use host_sim::hil::run::{HilSetup, run};
use host_sim::hil::session::{LoggedText, Session};
use host_sim::hil::transport::Link;
use host_sim::scenario_file;
use link::hil::ImuSample;
use link::msg::{MavCmd, MavResult};
use link::status::MissionState;
use shared::scenario_wire::{MAX_ENCODED_LEN, encode};

/// One QEMU at a time: the machines that run this have two cores.
static ONE_QEMU: Mutex<()> = Mutex::new(());

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn firmware_image() -> PathBuf {
    if let Some(p) = std::env::var_os("FIRMWARE_QEMU_ELF") {
        return PathBuf::from(p);
    }
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace().join("target"));
    target.join("thumbv7em-none-eabihf/release/firmware-qemu")
}

/// The firmware image if the test can run; otherwise says why it is skipped (or, with
/// `HIL_REQUIRED=1`, fails).
fn image_or_skip(test: &str) -> Option<PathBuf> {
    let elf = firmware_image();
    let reason = if !qemu::available() {
        "qemu-system-arm is not installed (Debian: apt-get install qemu-system-arm)".to_string()
    } else if !elf.is_file() {
        format!(
            "the firmware image {} is not built (cargo fw-qemu)",
            elf.display()
        )
    } else {
        return Some(elf);
    };
    if std::env::var("HIL_REQUIRED").is_ok_and(|v| v == "1") {
        panic!("{test}: HIL_REQUIRED=1 but {reason}");
    }
    // Straight to stderr: the test harness hides what `eprintln!` prints in a passing test.
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "{test}: SKIPPED: {reason}");
    None
}

/// Prints a measurement where it is seen even when the test passes (the harness hides what
/// `println!` prints then).
fn report(line: std::fmt::Arguments<'_>) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "{line}");
}

fn rect_ex1() -> scenario_file::LoadedScenario {
    scenario_file::load(&workspace().join("tests/scenarios/rect-ex1.toml")).expect("rect-ex1")
}

fn print_text() -> Box<dyn FnMut(&LoggedText) + Send> {
    Box::new(|t: &LoggedText| println!("  step {:5}  firmware: {}", t.step, t.text))
}

fn qemu_session(elf: &Path) -> (Qemu, Session) {
    let (qemu, stream) = Qemu::launch(elf).expect("QEMU starts");
    let link = Link::over_tcp(stream).expect("link");
    (qemu, Session::new(link, None, print_text()))
}

/// The placeholder job's checksum, computed here as the firmware does (xorshift32 from its
/// seed, folded), to check the job ran to its end in thread mode.
fn placeholder_checksum(iterations: u32) -> u32 {
    let mut x = 0x1234_5678u32;
    let mut folded = 0;
    for _ in 0..iterations {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        folded ^= x;
    }
    folded
}

#[test]
fn the_qemu_firmware_runs_its_mission_in_lockstep() {
    let Some(elf) = image_or_skip("the_qemu_firmware_runs_its_mission_in_lockstep") else {
        return;
    };
    let _one = ONE_QEMU.lock().unwrap_or_else(|e| e.into_inner());
    let loaded = rect_ex1();
    let (qemu, stream) = Qemu::launch(&elf).expect("QEMU starts");
    let link = Link::over_tcp(stream).expect("link");
    let outcome = run(&loaded, link, &HilSetup::default(), print_text())
        .unwrap_or_else(|e| panic!("hil run failed: {e:#}\nQEMU said: {}", qemu.output()));

    report(format_args!(
        "hil: lockstep: {} ticks, {:.2} s simulated in {:.2} s wall ({:.0} ticks/s)",
        outcome.ticks,
        outcome.simulated_s,
        outcome.wall_s,
        outcome.ticks as f64 / outcome.wall_s
    ));
    assert_eq!(outcome.firmware, "qemu-mps2-an500");
    assert_eq!(outcome.start_ack, Some(MavResult::MAV_RESULT_ACCEPTED));
    assert_eq!(outcome.state, MissionState::Completed);
    // The placeholder completes 2 s after its start: 800 steps at 400 Hz, and the clock is
    // the plant's.
    assert!(
        (801..=803).contains(&outcome.ticks),
        "{} ticks",
        outcome.ticks
    );
    assert!((outcome.simulated_s - outcome.ticks as f64 / 400.0).abs() < 0.003);
    let said = |prefix: &str| outcome.log.texts.iter().any(|t| t.text.starts_with(prefix));
    assert!(said("payload rect-ex1 accepted: 8 robots"));
    assert!(said("phase: running"));
    assert!(said("phase: completed"));
    assert_eq!(
        outcome
            .phases
            .iter()
            .map(|(n, _)| n.as_str())
            .collect::<Vec<_>>(),
        ["running", "completed"]
    );
    // The job ran whole in thread mode and its result was taken exactly at its deadline.
    let value = |name: &str| outcome.log.last_value(name).expect(name);
    assert_eq!(
        value("job_sum") as i64 as u32,
        placeholder_checksum(6_000_000)
    );
    // The placeholder's job (~48 million instructions) outlasts its one-step deadline: the
    // control task held that step's reply until the job was done, and took the result at
    // exactly that step.
    assert_eq!(value("job_step") - value("job_req"), 1.0);
    assert!(value("job_holds") >= 1.0);
    // The robots stay where the scenario puts them.
    let initial = &loaded.scenario.robots.initial;
    assert_eq!(outcome.positions, initial.to_vec());
    let (name, worst) = outcome
        .worst_tick()
        .expect("the firmware reports its worst tick");
    assert_eq!(name, "tick_insn");
    assert!(worst > 0.0);
    report(format_args!(
        "hil: worst control tick under QEMU -icount (NAMED_VALUE_INT {name}): {worst:.0} instructions (job holds: {})",
        outcome.log.last_value("job_holds").unwrap_or(0.0)
    ));
}

#[test]
fn a_bad_payload_is_refused_naming_its_key_and_the_start_denied() {
    let Some(elf) = image_or_skip("a_bad_payload_is_refused_naming_its_key_and_the_start_denied")
    else {
        return;
    };
    let _one = ONE_QEMU.lock().unwrap_or_else(|e| e.into_inner());
    let (qemu, mut session) = qemu_session(&elf);
    assert_eq!(
        session.identify(Duration::from_secs(20)).expect("board"),
        "qemu-mps2-an500"
    );
    // A value the host's checks refuse, sent past them.
    let mut bad = shared::paper::rect_sim1();
    bad.estimation.resolution[1] = 0.0;
    let mut file = [0u8; MAX_ENCODED_LEN];
    let n = encode("bad-resolution", &bad, &mut file).expect("encodes");
    let refusal = session
        .upload_payload(&file[..n], Duration::from_secs(20))
        .expect_err("refused");
    let refusal = format!("{refusal:#}");
    println!("{refusal}");
    assert!(refusal.contains("estimation.resolution"), "{refusal}");
    // The same file damaged on the way.
    let good = shared::paper::rect_sim1();
    let n = encode("rect-sim1", &good, &mut file).expect("encodes");
    file[20] ^= 0x10;
    let damaged = session
        .upload_payload(&file[..n], Duration::from_secs(20))
        .expect_err("refused");
    assert!(format!("{damaged:#}").contains("damaged"), "{damaged:#}");
    // Without a payload description the start is denied, and the firmware says why.
    session.send_start().expect("sent");
    let at_rest = ImuSample {
        time_us: 0,
        gyro: [0.0; 3],
        accel: [0.0, 0.0, -9.81],
    };
    session
        .step(&at_rest, &[], 8, Duration::from_secs(10))
        .unwrap_or_else(|e| panic!("{e:#}: {}", qemu.output()));
    assert_eq!(
        session.log().ack_of(MavCmd::MAV_CMD_MISSION_START),
        Some(MavResult::MAV_RESULT_DENIED)
    );
    assert!(
        session
            .log()
            .texts
            .iter()
            .any(|t| t.text == "start refused: no payload description loaded")
    );
}

#[test]
fn a_stalled_firmware_is_a_clear_lockstep_error() {
    let Some(elf) = image_or_skip("a_stalled_firmware_is_a_clear_lockstep_error") else {
        return;
    };
    let _one = ONE_QEMU.lock().unwrap_or_else(|e| e.into_inner());
    let (qemu, mut session) = qemu_session(&elf);
    session.identify(Duration::from_secs(20)).expect("board");
    let mut sample = ImuSample {
        time_us: 0,
        gyro: [0.0; 3],
        accel: [0.0, 0.0, -9.81],
    };
    for _ in 0..20 {
        session
            .step(&sample, &[], 8, Duration::from_secs(10))
            .expect("steps while the firmware runs");
        sample.time_us += 2500;
    }
    // Freeze the emulator: the firmware neither runs nor answers.
    let pid = qemu.pid() as libc::pid_t;
    // SAFETY: signals to our own child process.
    unsafe { libc::kill(pid, libc::SIGSTOP) };
    let started = Instant::now();
    let err = session
        .step(&sample, &[], 8, Duration::from_millis(1500))
        .expect_err("no reply from a stopped firmware");
    // SAFETY: as above.
    unsafe { libc::kill(pid, libc::SIGCONT) };
    let message = format!("{err:#}");
    println!("{message}");
    assert!(
        message.contains("lockstep: no HIL_ACTUATOR_CONTROLS"),
        "{message}"
    );
    assert!(message.contains("step 20"), "{message}");
    assert!(started.elapsed() >= Duration::from_millis(1500));
    assert!(started.elapsed() < Duration::from_secs(5));
}

#[test]
fn the_serial_path_runs_through_a_pty() {
    let Some(elf) = image_or_skip("the_serial_path_runs_through_a_pty") else {
        return;
    };
    let _one = ONE_QEMU.lock().unwrap_or_else(|e| e.into_inner());
    let (_qemu, pty) = Qemu::launch_pty(&elf).expect("QEMU starts on a pty");
    let link = Link::over_serial(&pty, 921_600).expect("the pty opens as a serial device");
    let setup = HilSetup {
        duration_s: Some(0.5),
        ..HilSetup::default()
    };
    let outcome = run(&rect_ex1(), link, &setup, print_text()).expect("hil over the pty");
    assert_eq!(outcome.firmware, "qemu-mps2-an500");
    assert_eq!(outcome.ticks, 200);
    assert_eq!(outcome.state, MissionState::Running);
    println!(
        "over {}: {} ticks in {:.2} s wall",
        pty.display(),
        outcome.ticks,
        outcome.wall_s
    );
}

#[test]
fn a_ground_station_sees_and_commands_the_vehicle_through_the_bridge() {
    let Some(elf) =
        image_or_skip("a_ground_station_sees_and_commands_the_vehicle_through_the_bridge")
    else {
        return;
    };
    let _one = ONE_QEMU.lock().unwrap_or_else(|e| e.into_inner());
    use link::MessageData;
    use link::frame::{Encoder, Frame, Parser};
    use link::msg::{AUTOPILOT_VERSION_DATA, HEARTBEAT_DATA, HIL_ACTUATOR_CONTROLS_DATA};
    // A ground station on a local UDP port: once the vehicle speaks, it asks who it is.
    let ground = std::net::UdpSocket::bind("127.0.0.1:0").expect("udp");
    ground
        .set_read_timeout(Some(Duration::from_millis(200)))
        .expect("timeout");
    let addr = ground.local_addr().expect("address");
    // What it saw: every message id, and whether an AUTOPILOT_VERSION came after its request.
    let station = std::thread::spawn(move || {
        let mut parser = Parser::new(link::vehicle::crc_extra);
        let mut seen = Vec::new();
        let mut asked = false;
        let mut answered = false;
        let mut buf = [0u8; 2048];
        let end = Instant::now() + Duration::from_secs(60);
        while Instant::now() < end && !(answered && seen.contains(&HEARTBEAT_DATA::ID)) {
            let Ok((n, vehicle)) = ground.recv_from(&mut buf) else {
                continue;
            };
            for &b in &buf[..n] {
                if let Some((f, _)) = parser.push(b) {
                    seen.push(f.message_id());
                    answered |= asked && f.message_id() == AUTOPILOT_VERSION_DATA::ID;
                }
            }
            if !asked {
                asked = true;
                let mut enc = Encoder::new(255, 190);
                let mut f = Frame::default();
                let ask = link::command::command_long(
                    MavCmd::MAV_CMD_REQUEST_MESSAGE,
                    AUTOPILOT_VERSION_DATA::ID as f32,
                    0.0,
                );
                enc.encode(&ask, &mut f);
                let _ = ground.send_to(f.bytes(), vehicle);
            }
        }
        (seen, answered)
    });
    let (_qemu, stream) = Qemu::launch(&elf).expect("QEMU starts");
    let link = Link::over_tcp(stream).expect("link");
    let setup = HilSetup {
        duration_s: Some(2.5),
        gcs: Some(addr),
        ..HilSetup::default()
    };
    run(&rect_ex1(), link, &setup, print_text()).expect("hil with a ground station");
    let (seen, answered) = station.join().expect("ground station");
    assert!(
        seen.contains(&HEARTBEAT_DATA::ID),
        "no heartbeat reached the ground station"
    );
    assert!(
        answered,
        "the ground station's request did not reach the vehicle and back"
    );
    assert!(
        !seen.contains(&HIL_ACTUATOR_CONTROLS_DATA::ID),
        "HIL traffic leaked to the ground station"
    );
}

#[test]
fn the_hil_command_prints_the_mission_keys_as_json() {
    let Some(elf) = image_or_skip("the_hil_command_prints_the_mission_keys_as_json") else {
        return;
    };
    let _one = ONE_QEMU.lock().unwrap_or_else(|e| e.into_inner());
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .arg("hil")
        .arg("--scenario")
        .arg(workspace().join("tests/scenarios/rect-ex1.toml"))
        .arg("--qemu")
        .arg(&elf)
        .args(["--seed", "3", "--json"])
        .output()
        .expect("host-sim runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "host-sim hil failed: {stderr}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    for key in [
        "estimate",
        "measurements",
        "positions",
        "delivered",
        "dropped",
        "final_position_error_m",
        "phases",
        "firmware",
        "ticks",
    ] {
        assert!(v.get(key).is_some(), "key {key} missing from {v}");
    }
    assert_eq!(v["firmware"], "qemu-mps2-an500");
    assert!(v["ticks"].as_u64().is_some_and(|t| t > 800));
}

#[test]
fn a_link_where_no_firmware_answers_is_a_clear_error() {
    // Runs everywhere: a socket that accepts and never speaks.
    let listener = TcpListener::bind("127.0.0.1:0").expect("listen");
    let addr = listener.local_addr().expect("address");
    let silent = std::thread::spawn(move || listener.accept().map(|(s, _)| s));
    let link =
        Link::open(&host_sim::hil::transport::Endpoint::Tcp(addr.to_string())).expect("connects");
    let mut session = Session::new(link, None, print_text());
    let err = session
        .identify(Duration::from_millis(600))
        .expect_err("nobody answers");
    assert!(
        format!("{err:#}").contains("did not say which board it runs on"),
        "{err:#}"
    );
    drop(silent.join());
}
