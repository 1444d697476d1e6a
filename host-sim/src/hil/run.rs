//! The plant loop of `hil`: the physics plant and its sensors (the same `plant` the `mission`
//! command flies), stepped in lockstep with the firmware (issue 11, section 3).
//!
//! Each control step (400 Hz): the motion-capture fixes due (100 Hz, with their latency) and
//! the IMU sample go out; the plant then waits for the firmware's actuator commands stamped
//! with that sample's time, applies them (rotor thrust = fraction x the robots' maximum; each
//! robot moved to its commanded rail position) and advances its physics by one step (five
//! 2 kHz steps). Nothing advances without the firmware's reply, so a run is the same however
//! fast QEMU or the link is. `--speed X` only slows the loop down to X times real time.
//!
//! The run ends when the firmware's heartbeat says its mission is over, when the payload tips
//! past 45 degrees, or at the time limit.

use std::time::{Duration, Instant};

use anyhow::{Result, bail};
use link::hil::{ImuSample, MocapFix};
use link::msg::{MavCmd, MavResult};
use link::status::{MissionState, PHASE_PREFIX};
use shared::control::vector::Vec3;
use shared::geometry::Vec2;
use shared::scenario_wire::{MAX_ENCODED_LEN, encode_scenario};

use super::gcs::GcsBridge;
use super::session::{FirmwareLog, LoggedText, Session};
use super::transport::Link;
use crate::harness::{CONTROL_HZ, DROP_TILT_DEG};
use crate::plant::sensors::Sensors;
use crate::plant::{PHYSICS_DT, Plant, PlantConfig};
use crate::scenario_file::LoadedScenario;

/// Longest run, simulated seconds (as the `mission` command's limit).
pub const TIME_LIMIT_S: f64 = 900.0;

/// One run's set-up.
#[derive(Clone, Debug)]
pub struct HilSetup {
    /// Seed of the sensors' noise.
    pub seed: u64,
    /// Pace the lockstep to this many times real time (`None`: as fast as it goes).
    pub speed: Option<f64>,
    /// Stop after this much simulated time even if the mission goes on, s.
    pub duration_s: Option<f64>,
    /// How long the plant waits for each reply before giving up.
    pub reply_timeout: Duration,
    /// Bridge non-HIL traffic to this ground station.
    pub gcs: Option<std::net::SocketAddr>,
}

impl Default for HilSetup {
    fn default() -> Self {
        Self {
            seed: 1,
            speed: None,
            duration_s: None,
            reply_timeout: Duration::from_secs(10),
            gcs: None,
        }
    }
}

/// What a run did.
#[derive(Clone, Debug)]
pub struct HilOutcome {
    /// The board the firmware reported.
    pub firmware: String,
    /// Lockstep exchanges (control steps).
    pub ticks: u64,
    /// Simulated time, s.
    pub simulated_s: f64,
    /// Wall-clock time of the lockstep, s.
    pub wall_s: f64,
    /// The firmware's mission state at the end.
    pub state: MissionState,
    /// The acknowledgement of the start command.
    pub start_ack: Option<MavResult>,
    /// Roll or pitch passed 45 degrees.
    pub dropped: bool,
    /// Distance of the payload from the flight target's landing point at the end, m (from the
    /// start point when the scenario has no flight target).
    pub final_position_error_m: f64,
    /// The robots' last commanded rail positions, m.
    pub positions: Vec<f32>,
    /// Each phase the firmware reported (`phase: NAME: ...`) and how long it lasted, s.
    pub phases: Vec<(String, f64)>,
    /// Everything the firmware said.
    pub log: FirmwareLog,
}

impl HilOutcome {
    /// The worst control-step cost the firmware reported: its name (`tick_insn` under QEMU,
    /// instructions; `tick_cyc` on a board, cycles) and value.
    pub fn worst_tick(&self) -> Option<(&'static str, f64)> {
        ["tick_insn", "tick_cyc"]
            .into_iter()
            .find_map(|name| self.log.last_value(name).map(|v| (name, v)))
    }
}

/// Runs `scenario` against the firmware on `link`; `on_text` sees each text with the simulated
/// time it arrived at.
pub fn run(
    scenario: &LoadedScenario,
    link: Link,
    setup: &HilSetup,
    on_text: Box<dyn FnMut(&LoggedText) + Send>,
) -> Result<HilOutcome> {
    let s = &scenario.scenario;
    let Some(truth) = s.truth else {
        bail!("[truth]: hil needs the scenario's truth to simulate the payload");
    };
    let gcs = match setup.gcs {
        Some(addr) => Some(GcsBridge::start(addr, link.writer())?),
        None => None,
    };
    let mut session = Session::new(link, gcs, on_text);
    let firmware = session.identify(Duration::from_secs(20))?;

    let mut file = [0u8; MAX_ENCODED_LEN];
    let len = encode_scenario(&scenario.name, s, &mut file).map_err(|e| {
        anyhow::anyhow!(
            "{}: cannot encode for the firmware: {e}",
            scenario.path.display()
        )
    })?;
    session.upload_payload(&file[..len], Duration::from_secs(20))?;

    let rail = &s.payload.rail;
    let robots = s.robots.count();
    let points =
        |positions: &[f32]| -> Vec<Vec2> { positions.iter().map(|&p| rail.point_at(p)).collect() };
    let mut plant = Plant::new(PlantConfig {
        footprint: s.payload.footprint.to_vec(),
        com: truth.com,
        mass: truth.mass,
        robot_mass: s.robots.mass,
        rotor_points: points(&s.robots.initial),
        spin: s.robots.spin.to_vec(),
        torque_per_thrust: s.robots.torque_per_thrust,
        max_thrust: s.robots.max_thrust,
        map_error: 1.0,
        disturbance_peak: 0.0,
        disturbance_phase: [0.4 + setup.seed as f32 % 3.0, 1.9],
    });
    let mut sensors = Sensors::new(setup.seed);
    let dt = 1.0 / CONTROL_HZ as f32;
    let physics_per_tick = (dt / PHYSICS_DT).round() as usize;
    let limit = setup.duration_s.unwrap_or(TIME_LIMIT_S).min(TIME_LIMIT_S);
    let mut positions = s.robots.initial.to_vec();
    let mut commands = vec![0.0f32; robots];
    let mut dropped = false;
    let mut was_running = false;
    let start_point = plant.state().position;
    let wall = Instant::now();

    session.send_start()?;
    loop {
        let t = f64::from(plant.time());
        if t >= limit {
            break;
        }
        let truth_now = plant.state();
        let imu = sensors.imu(&truth_now, dt);
        let now_us = plant.time_us();
        let fixes: Vec<MocapFix> = sensors
            .mocap(&truth_now, now_us)
            .into_iter()
            .map(|f| MocapFix {
                stamp_us: f.stamp_us,
                position: [f.position.x, f.position.y, f.position.z],
                attitude: [f.attitude.w, f.attitude.x, f.attitude.y, f.attitude.z],
            })
            .collect();
        let sample = ImuSample {
            time_us: now_us,
            gyro: [imu.gyro.x, imu.gyro.y, imu.gyro.z],
            accel: [imu.accel.x, imu.accel.y, imu.accel.z],
        };
        let reply = session.step(&sample, &fixes, robots, setup.reply_timeout)?;
        if session.steps() == 1 {
            match session.log().ack_of(MavCmd::MAV_CMD_MISSION_START) {
                Some(MavResult::MAV_RESULT_ACCEPTED) => {}
                Some(result) => {
                    let why = last_error(session.log()).unwrap_or_default();
                    bail!("the firmware refused the mission start ({result:?}){why}");
                }
                None => bail!(
                    "the firmware did not acknowledge MAV_CMD_MISSION_START with its first step"
                ),
            }
        }
        for (j, c) in commands.iter_mut().enumerate() {
            let fraction = if reply.armed { reply.thrust[j] } else { 0.0 };
            *c = fraction.clamp(0.0, 1.0) * s.robots.max_thrust;
        }
        let wanted: Vec<f32> = reply.rail[..robots].iter().map(|&p| rail.wrap(p)).collect();
        if wanted != positions {
            positions = wanted;
            plant.set_rotor_points(&points(&positions));
        }
        let euler = truth_now.attitude.to_euler();
        if euler.x.abs().to_degrees() > DROP_TILT_DEG || euler.y.abs().to_degrees() > DROP_TILT_DEG
        {
            dropped = true;
            break;
        }
        match session.log().state {
            Some(MissionState::Running) => was_running = true,
            Some(state) if state.is_over() => break,
            _ => {}
        }
        if was_running && session.log().state == Some(MissionState::Idle) {
            bail!("the firmware's mission went back to idle while running (did it restart?)");
        }
        for _ in 0..physics_per_tick {
            plant.step(&commands);
        }
        if let Some(speed) = setup.speed.filter(|s| *s > 0.0) {
            let due = Duration::from_secs_f64(f64::from(plant.time()) / speed);
            if let Some(wait) = due.checked_sub(wall.elapsed()) {
                std::thread::sleep(wait);
            }
        }
    }
    let wall_s = wall.elapsed().as_secs_f64();
    let simulated_s = f64::from(plant.time());
    let landing = match s.flight {
        Some(f) => Vec3::new(f.target[0], f.target[1], start_point.z),
        None => start_point,
    };
    let final_position_error_m = f64::from((plant.state().position - landing).norm());
    let log = session.log().clone();
    let phases = phases(&log, session.steps(), dt);
    Ok(HilOutcome {
        firmware,
        ticks: session.steps(),
        simulated_s,
        wall_s,
        state: log.state.unwrap_or(MissionState::Idle),
        start_ack: log.ack_of(MavCmd::MAV_CMD_MISSION_START),
        dropped,
        final_position_error_m,
        positions,
        phases,
        log,
    })
}

/// The firmware's last error text, as `": TEXT"`.
fn last_error(log: &FirmwareLog) -> Option<String> {
    log.texts
        .iter()
        .rev()
        .find(|t| (t.severity as u8) <= 3)
        .map(|t| format!(": {}", t.text))
}

/// Phases from the firmware's `phase: NAME: ...` texts, with durations from the steps at which
/// they arrived.
fn phases(log: &FirmwareLog, steps: u64, dt: f32) -> Vec<(String, f64)> {
    let marks: Vec<(String, u64)> = log
        .texts
        .iter()
        .filter_map(|t| {
            let rest = t.text.strip_prefix(PHASE_PREFIX)?;
            let name = rest.split(':').next().unwrap_or(rest).trim().to_string();
            Some((name, t.step))
        })
        .collect();
    marks
        .iter()
        .enumerate()
        .map(|(i, (name, at))| {
            let end = marks.get(i + 1).map_or(steps, |(_, next)| *next);
            (name.clone(), end.saturating_sub(*at) as f64 * f64::from(dt))
        })
        .collect()
}
