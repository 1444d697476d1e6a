//! `host-sim hil`: the mission with the firmware in the loop (docs/formats.md#hil): the plant side
//! of PX4's simulator MAVLink API, in lockstep. The firmware runs under QEMU (`--qemu ELF`, started
//! here), on a board over a serial device (`--serial DEV`), or behind any TCP socket (`--connect
//! tcp:HOST:PORT`).
//!
//! Prints what the firmware says as it says it; `--json` prints one object with the keys of
//! `mission` plus `firmware` (the board it reported) and `ticks` (lockstep exchanges). Exit
//! codes as `mission` (docs/commands.md#exit-codes): 1 when the firmware refuses the payload or the
//! start or the lockstep breaks, 3 when the mission aborts, 4 when it ends undelivered, 5 when
//! the payload drops.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Result, bail};
use clap::{ArgGroup, Args};
use link::status::MissionState;
use serde_json::json;

use crate::cli::{Outcome, check_map_error, check_range, triple};
use crate::hil::gcs::GcsBridge;
use crate::hil::qemu::{Guest, Qemu, QemuLink};
use crate::hil::run::{HilOutcome, HilSetup, run_with_rc as run_hil};
use crate::hil::session::{LoggedText, PayloadRefused};
use crate::hil::transport::{Endpoint, Link};
use crate::inject::{Fault, Injection};
use crate::mission_run::MISSION_TIME_LIMIT;
use crate::pilot_script::{PilotScript, PilotSource};
use crate::plant::sensors::MAX_GIVEN_GYRO_BIAS;
use crate::report::print_json;
use crate::say;
use crate::scenario_file;

/// Arguments of `hil`.
#[derive(Debug, Args)]
#[command(group(ArgGroup::new("firmware").required(true).args(["qemu", "serial", "connect"])))]
pub struct HilArgs {
    /// Scenario file (TOML, see docs/formats.md).
    #[arg(long, value_name = "FILE")]
    pub scenario: PathBuf,
    /// Run this firmware image under qemu-system-arm (mps2-an500), e.g.
    /// target/thumbv7em-none-eabihf/release/firmware-qemu.
    #[arg(long, value_name = "ELF")]
    pub qemu: Option<PathBuf>,
    /// With --qemu: keep the firmware's parameter flash in this directory (file
    /// firmware-params.bin), so parameters set in one run are there in the next, and its
    /// flight logs (log-000.ulg, log-001.ulg, ...: one per mission, ULog). Without it every
    /// run starts from the defaults and keeps no log.
    #[arg(long, value_name = "DIR", requires = "qemu")]
    pub storage: Option<PathBuf>,
    /// With --qemu: the board's link to the plant: `ethernet` (its LAN9118, frames as UDP
    /// datagrams on this machine: fast) or `uart` (its CMSDK UART over a TCP socket, one byte
    /// per pass of QEMU's main loop: the serial path a board's TELEM1 takes).
    #[arg(
        long,
        value_name = "LINK",
        default_value = "ethernet",
        requires = "qemu"
    )]
    pub qemu_link: QemuLink,
    /// With --qemu: the board drives at most N robots (1 to 16; default all 16), as a Pixhawk
    /// 6C drives 8: a payload description with more is refused (docs/hardware.md).
    #[arg(long, value_name = "N", requires = "qemu")]
    pub max_robots: Option<u32>,
    /// The firmware on a board (or QEMU's -serial pty) over this serial device.
    #[arg(long, value_name = "DEV")]
    pub serial: Option<String>,
    /// Baud rate of --serial (the Pixhawk's TELEM1 runs at 921600; USB ignores it).
    #[arg(long, value_name = "N", default_value_t = 921_600, requires = "serial")]
    pub baud: u32,
    /// The firmware behind a TCP socket: tcp:HOST:PORT.
    #[arg(long, value_name = "tcp:HOST:PORT", value_parser = Endpoint::parse_tcp)]
    pub connect: Option<Endpoint>,
    /// Seed of the sensors' noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print one JSON object on stdout and nothing else.
    #[arg(long)]
    pub json: bool,
    /// Bridge all non-HIL MAVLink traffic to a ground station: udp:HOST:PORT.
    #[arg(long, value_name = "udp:HOST:PORT", value_parser = GcsBridge::parse)]
    pub gcs: Option<std::net::SocketAddr>,
    /// Pace the lockstep to X times real time (default: as fast as it goes).
    #[arg(long, value_name = "X")]
    pub speed: Option<f64>,
    /// Stop after this many simulated seconds even if the mission goes on.
    #[arg(long, value_name = "S")]
    pub duration: Option<f64>,
    /// Seconds the plant waits for each lockstep reply before it gives up.
    #[arg(long, value_name = "S", default_value_t = 10.0)]
    pub reply_timeout: f64,
    /// The rotors' command-to-thrust map over-reads by this factor.
    #[arg(long, value_name = "S", default_value_t = 1.0)]
    pub map_error: f64,
    /// After the mission, keep the firmware and the ground station's link (--gcs) up for up to
    /// S seconds of wall time, ending once the ground station has been silent for 2 s: time to
    /// read parameters or download the log. At most 600.
    #[arg(long, requires = "gcs", value_name = "S")]
    pub linger: Option<f64>,
    /// Leave the mission start to the ground station (--gcs): upload the payload, then step
    /// the idle vehicle until it starts (parameters may be changed meanwhile).
    #[arg(long, requires = "gcs")]
    pub ground_start: bool,
    /// Leave the rail positions unconfirmed: the plant does not send MAV_CMD_USER_1 (31010)
    /// after the upload, so the firmware refuses a start until a ground station confirms them.
    #[arg(long)]
    pub unconfirmed_rails: bool,
    /// The simulated gyro's constant bias, rad/s about the body's x, y and z, each at most 0.5
    /// either way (default: drawn from the seed, about 0.01 per axis): what a gyro calibration
    /// should find.
    #[arg(long, value_name = "X,Y,Z", value_parser = triple, allow_hyphen_values = true)]
    pub gyro_bias: Option<[f64; 3]>,
    /// Sign what the plant sends (the payload upload, commands) with this MAVLink 2 signing
    /// key, 64 hexadecimal digits: for a vehicle whose signing is on.
    #[arg(long, value_name = "HEX", value_parser = parse_signing_key)]
    pub signing_key: Option<[u8; link::signing::KEY_LEN]>,
    /// Failure injection: motion capture stops this many seconds after take-off.
    #[arg(long, value_name = "S")]
    pub mocap_lost_after: Option<f64>,
    /// Failure injection in the plant, as `mission --inject` (KIND@SECONDS after take-off):
    /// `rotor-out:J@T`, `load-shift:DX,DY@T`, `mocap-loss@T`, `imu-stuck@T` and
    /// `imu-noise:X@T` (in the HIL_SENSOR samples), `gcs-loss[@T]` (the plant's heartbeat stops
    /// and nothing from --gcs passes), `battery:V[@T]` (the pack's voltage the plant sends as
    /// BATTERY_STATUS drops to V volts); not `stepper-stall` (the link carries no stall report).
    #[arg(long, value_name = "KIND@SECONDS", value_parser = Injection::parse)]
    pub inject: Vec<Injection>,
    /// The plant sends each rotor's RPM to the firmware (`ESC_STATUS`, before each step's
    /// `HIL_SENSOR`), as ESCs with bidirectional DShot report it: the rotor monitor then reads
    /// the RPM as well as the vehicle's response (docs/firmware.md#esc-telemetry).
    #[arg(long)]
    pub esc_telemetry: bool,
    /// A stick script (TOML, docs/hil.md): a person at the sticks. `source = "rc"` frames go
    /// into the board's RC receiver UART as CRSF (with --qemu: QEMU's second serial port),
    /// `source = "joystick"` frames as MANUAL_CONTROL over the link; the parameters that map
    /// its switches are set on the vehicle first.
    #[arg(long, value_name = "FILE")]
    pub rc: Option<PathBuf>,
}

/// A MAVLink 2 signing key from 64 hexadecimal digits.
fn parse_signing_key(text: &str) -> std::result::Result<[u8; link::signing::KEY_LEN], String> {
    let digits = text.trim();
    if digits.len() != 2 * link::signing::KEY_LEN {
        return Err(format!(
            "a signing key is {} hexadecimal digits, this has {}",
            2 * link::signing::KEY_LEN,
            digits.len()
        ));
    }
    let mut key = [0u8; link::signing::KEY_LEN];
    for (i, byte) in key.iter_mut().enumerate() {
        let pair = digits.get(2 * i..2 * i + 2).unwrap_or("");
        *byte = u8::from_str_radix(pair, 16).map_err(|_| {
            format!(
                "not a hexadecimal digit pair at position {}: {pair:?}",
                2 * i
            )
        })?;
    }
    Ok(key)
}

/// Runs the command.
pub fn run(args: &HilArgs) -> Result<Outcome> {
    // Every flag is checked before the firmware is started.
    let map_error = check_map_error(args.map_error)?;
    let positive = |flag: &str, v: Option<f64>, high: f64| {
        v.map(|v| check_range(flag, v, (0.0, true), high, ""))
            .transpose()
    };
    let speed = positive("--speed", args.speed, 1000.0)?;
    let duration = positive("--duration", args.duration, f64::from(MISSION_TIME_LIMIT))?;
    let linger = positive("--linger", args.linger, 600.0)?;
    let mocap_lost_after = args
        .mocap_lost_after
        .map(|s| {
            check_range(
                "--mocap-lost-after",
                s,
                (0.0, false),
                f64::from(MISSION_TIME_LIMIT),
                "s",
            )
        })
        .transpose()?;
    let gyro_bias = args
        .gyro_bias
        .map(|bias| -> Result<[f32; 3]> {
            let max = f64::from(MAX_GIVEN_GYRO_BIAS);
            let axis = |v: f64| check_range("--gyro-bias", v, (-max, false), max, "rad/s");
            Ok([axis(bias[0])?, axis(bias[1])?, axis(bias[2])?])
        })
        .transpose()?;
    let reply_timeout = check_range(
        "--reply-timeout",
        args.reply_timeout,
        (0.0, true),
        3600.0,
        "s",
    )?;
    if let Some(i) = args
        .inject
        .iter()
        .find(|i| matches!(i.fault, Fault::StepperStall(_)))
    {
        bail!(
            "--inject {i}: the HIL link carries no stall report (StallGuard is the board's own driver); use mission"
        );
    }
    let max_robots = args
        .max_robots
        .map(|n| {
            let most = shared::scenario::MAX_ROBOTS as u32;
            if (1..=most).contains(&n) {
                Ok(n as u8)
            } else {
                Err(anyhow::anyhow!("--max-robots {n}: 1 to {most}"))
            }
        })
        .transpose()?;
    let pilot = args.rc.as_deref().map(PilotScript::load).transpose()?;
    let rc_uart = pilot.as_ref().is_some_and(|p| p.source == PilotSource::Rc);
    if rc_uart && args.qemu.is_none() {
        bail!(
            "--rc with source = \"rc\" needs --qemu: the plant writes CRSF into the emulated board's receiver UART (a board's receiver is its own radio's)"
        );
    }
    let loaded = scenario_file::load(&args.scenario)?;
    crate::inject::check_robots(&args.inject, &loaded)?;
    let setup = HilSetup {
        injections: args.inject.clone(),
        seed: args.seed,
        speed: speed.map(f64::from),
        duration_s: duration.map(f64::from),
        reply_timeout: Duration::from_secs_f64(f64::from(reply_timeout)),
        gcs: args.gcs,
        map_error,
        mocap_lost_after_takeoff: mocap_lost_after,
        ground_start: args.ground_start,
        linger: linger.map(|s| Duration::from_secs_f64(f64::from(s))),
        confirm_rails: !args.unconfirmed_rails,
        gyro_bias,
        esc_telemetry: args.esc_telemetry,
        keeps_logs: args.qemu.is_some() && args.storage.is_some(),
        pilot,
        // The ground station's commands come from `--gcs` (a bridged ground station).
        commands: Vec::new(),
    };
    let json = args.json;
    let on_text: Box<dyn FnMut(&LoggedText) + Send> = Box::new(move |t: &LoggedText| {
        if !json {
            // A progress line that cannot be written is not worth stopping the flight for; a
            // reader that went away ends the process in `say`.
            let _ = say!("  step {:6}  firmware: {}", t.step, t.text);
        }
    });
    let mut rc = None;
    let (_qemu, mut link) = if let Some(elf) = &args.qemu {
        let guest = Guest {
            storage: args.storage.as_deref(),
            max_robots,
            rc: rc_uart,
        };
        let (mut qemu, link) = Qemu::start_guest(elf, &guest, args.qemu_link)?;
        rc = qemu.take_rc();
        (Some(qemu), link)
    } else if let Some(path) = &args.serial {
        let endpoint = Endpoint::Serial {
            path: path.clone(),
            baud: args.baud,
        };
        (None, Link::open(&endpoint)?)
    } else if let Some(endpoint) = &args.connect {
        (None, Link::open(endpoint)?)
    } else {
        bail!("give the firmware: --qemu ELF, --serial DEV or --connect tcp:HOST:PORT");
    };
    if let Some(key) = args.signing_key {
        link.sign_with(key);
    }
    if !json {
        say!("hil on {}", loaded.name)?;
    }
    let outcome = match run_hil(&loaded, link, rc, &setup, on_text) {
        Ok(outcome) => outcome,
        Err(e) => {
            // A refused description is an answer of the vehicle's: the report says it too.
            if let (true, Some(refused)) = (json, e.downcast_ref::<PayloadRefused>()) {
                print_json(refused_json(&loaded.name, refused))?;
            }
            return Err(e);
        }
    };
    if json {
        let mut report = to_json(&loaded.name, &outcome);
        let transport = match (&args.qemu, &args.serial) {
            (Some(_), _) => args.qemu_link.name(),
            (None, Some(_)) => "serial",
            (None, None) => "tcp",
        };
        report["transport"] = json!(transport);
        print_json(report)?;
    } else {
        print_summary(&outcome)?;
    }
    Ok(Outcome::of_run(
        outcome.dropped,
        outcome.aborted.is_some() || outcome.state == MissionState::Aborted,
        outcome.delivered,
    ))
}

/// The JSON report: the keys of `mission`, plus `firmware` and `ticks`.
pub fn to_json(scenario: &str, o: &HilOutcome) -> serde_json::Value {
    let worst = o.worst_tick();
    json!({
        "scenario": scenario,
        "firmware": o.firmware,
        "ticks": o.ticks,
        "estimate": o.estimate,
        "measurements": o.measurements,
        "positions": o.positions,
        "delivered": o.delivered,
        "aborted": o.aborted,
        "lifts": o.lifts.iter().map(|(g, r, m)| json!({"pair": g, "reading": r, "model": m})).collect::<Vec<_>>(),
        "dropped": o.dropped,
        "final_position_error_m": o.final_position_error_m,
        "phases": o.phases.iter().map(|(name, d)| json!({"name": name, "duration_s": d})).collect::<Vec<_>>(),
        "mission_state": o.state.name(),
        "start_ack": o.start_ack.map(|r| format!("{r:?}")),
        "simulated_s": o.simulated_s,
        "wall_s": o.wall_s,
        "ticks_per_s": o.ticks as f64 / o.wall_s.max(1e-9),
        "real_time_factor": o.real_time_factor(),
        "link_bytes": {
            "to_firmware": o.link_bytes.to_firmware,
            "from_firmware": o.link_bytes.from_firmware,
            "to_firmware_per_tick": o.link_bytes.to_firmware as f64 / o.ticks.max(1) as f64,
            "from_firmware_per_tick": o.link_bytes.from_firmware as f64 / o.ticks.max(1) as f64,
        },
        // A bridged ground station's frames: forwarded, and dropped by the radio link.
        "gcs_link": o.gcs_link.map(|c| json!({"baud": crate::hil::gcs::GCS_BAUD, "forwarded_frames": c.forwarded, "dropped_frames": c.dropped})),
        "worst_tick": worst.map(|(name, v)| json!({"name": name, "value": v})),
        "busy_per_step": o.busy_per_step().map(|(name, mean, worst)| json!({"name": name, "mean": mean, "worst_second": worst})),
        // The last value of each name the firmware sent (NAMED_VALUE_FLOAT/INT).
        "values": o.log.values.iter().map(|v| (v.name.clone(), json!(v.value))).collect::<serde_json::Map<String, serde_json::Value>>(),
        "statustexts": o.log.texts.iter().map(|t| json!({"step": t.step, "text": t.text})).collect::<Vec<_>>(),
        // Each restart after a reboot the firmware acknowledged: the step it acknowledged at
        // and the step its new boot first answered.
        "restarts": o.log.restarts.iter().map(|r| json!({"acknowledged_at_step": r.acknowledged_at_step, "back_at_step": r.back_at_step})).collect::<Vec<_>>(),
    })
}

/// The JSON report of a run whose payload description the firmware refused: the keys of
/// `mission` (nothing flown), `firmware`, `ticks` (0) and `payload_refused` (the reason).
fn refused_json(scenario: &str, refused: &PayloadRefused) -> serde_json::Value {
    json!({
        "scenario": scenario,
        "firmware": refused.firmware,
        "ticks": 0,
        "payload_refused": refused.reason,
        "estimate": null,
        "measurements": 0,
        "positions": [],
        "delivered": false,
        "aborted": null,
        "lifts": [],
        "dropped": false,
        "final_position_error_m": null,
        "phases": [],
        "mission_state": MissionState::Idle.name(),
        "statustexts": refused.texts.iter().map(|t| json!({"step": t.step, "text": t.text})).collect::<Vec<_>>(),
    })
}

fn print_summary(o: &HilOutcome) -> Result<()> {
    say!(
        "{} ticks in lockstep with the firmware on {}: {:.2} s simulated in {:.2} s ({:.0} ticks/s, {:.2}x real time)",
        o.ticks,
        o.firmware,
        o.simulated_s,
        o.wall_s,
        o.ticks as f64 / o.wall_s.max(1e-9),
        o.real_time_factor()
    )?;
    say!(
        "link: {:.0} bytes to the firmware and {:.0} from it per tick",
        o.link_bytes.to_firmware as f64 / o.ticks.max(1) as f64,
        o.link_bytes.from_firmware as f64 / o.ticks.max(1) as f64
    )?;
    if let Some((name, v)) = o.worst_tick() {
        let unit = if name == "tick_insn" {
            "instructions"
        } else {
            "cycles"
        };
        say!("worst control step: {v:.0} {unit}")?;
    }
    if let Some((name, mean, worst)) = o.busy_per_step() {
        let unit = if name == "busy_insn" {
            "instructions"
        } else {
            "cycles"
        };
        say!(
            "processor busy per control step (the step, the link, the jobs): {mean:.0} {unit} on average, {worst:.0} in the busiest second"
        )?;
    }
    for r in &o.log.restarts {
        say!(
            "the firmware rebooted: acknowledged at step {}, back at step {}",
            r.acknowledged_at_step,
            r.back_at_step
        )?;
    }
    if let Some(e) = o.estimate {
        say!(
            "estimate: COM ({:.3}, {:.3}) m, mass {:.2} kg after {} lifts",
            e[0],
            e[1],
            e[2],
            o.measurements
        )?;
    }
    say!(
        "{}: final position error {:.3} m{}",
        if o.delivered {
            "delivered"
        } else if o.dropped {
            "DROPPED"
        } else {
            "NOT delivered"
        },
        o.final_position_error_m,
        o.aborted
            .as_deref()
            .map(|a| format!("; aborted: {a}"))
            .unwrap_or_default()
    )
}
