//! The plant's conversation with the firmware: who it is, the payload
//! description over MAVLink FTP, the start command, and the lockstep steps, with everything
//! the firmware says along the way (texts, values, acknowledgements, heartbeats) logged.
//!
//! Every wait has a deadline and ends in an error saying what did not come. One wait is
//! longer: once the firmware has acknowledged a reboot (`MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN`,
//! from a ground station), a step that gets no reply within a second is sent again each
//! second, for at most [`REBOOT_TIME`] more: the firmware restarted meanwhile, and the first
//! sample its new boot takes starts its clock over (the plant's time runs on). The restart is
//! logged ([`FirmwareLog::restarts`]).

use std::time::{Duration, Instant};

use anyhow::{Result, anyhow, bail};
use link::MessageData;
use link::command::{CommandWire, OperatorCommand, command_long};
use link::frame::{Frame, Integrity};
use link::ftp::{FtpMessage, PAYLOAD_PATH, Progress, Upload};
use link::hil::{Actuators, MocapFix, PlantSample, Reply, ReplyMatcher, mocap_message};
use link::msg::{
    ACTUATOR_OUTPUT_STATUS_DATA, AUTOPILOT_VERSION_DATA, COMMAND_ACK_DATA,
    FILE_TRANSFER_PROTOCOL_DATA, HEARTBEAT_DATA, HIL_ACTUATOR_CONTROLS_DATA, MavCmd, MavResult,
    MavSeverity, NAMED_VALUE_FLOAT_DATA, NAMED_VALUE_INT_DATA, PARAM_VALUE_DATA,
};
use link::status::{BOARD_PREFIX, MissionState, Reassembler, StatusChunk};

use super::gcs::GcsBridge;
use super::transport::Link;

/// One text from the firmware.
#[derive(Clone, Debug, PartialEq)]
pub struct LoggedText {
    /// Lockstep steps done when it arrived.
    pub step: u64,
    /// Its severity.
    pub severity: MavSeverity,
    /// The text.
    pub text: String,
}

/// One named value from the firmware.
#[derive(Clone, Debug, PartialEq)]
pub struct LoggedValue {
    /// Lockstep steps done when it arrived.
    pub step: u64,
    /// Its name.
    pub name: String,
    /// Its value.
    pub value: f64,
}

/// What the firmware said.
#[derive(Clone, Debug, Default)]
pub struct FirmwareLog {
    /// The board it runs on (its "board: " text).
    pub board: Option<String>,
    /// Its texts, in order.
    pub texts: Vec<LoggedText>,
    /// Its named values, in order.
    pub values: Vec<LoggedValue>,
    /// Its command acknowledgements, in order.
    pub acks: Vec<(MavCmd, MavResult)>,
    /// The mission state of its last heartbeat.
    pub state: Option<MissionState>,
    /// Heartbeats received.
    pub heartbeats: u32,
    /// Each restart of the firmware after a reboot it acknowledged, in order.
    pub restarts: Vec<Restart>,
    /// The `ESC_STATUS` messages it sent (four ESCs each).
    pub esc_statuses: u32,
    /// Each ESC's RPM in its last `ESC_STATUS`, by motor.
    pub esc_rpm: [i32; link::hil::MAX_ROBOTS],
    /// The ESCs any of its `ESC_INFO`s flagged failed (bit `i` for motor `i`).
    pub esc_failed: u16,
    /// Its last `RC_CHANNELS`: the 16 channels (us), `chancount` and `rssi`
    /// (docs/hardware.md#rc-receivers).
    pub rc_channels: Option<([u16; 16], u8, u8)>,
    /// The RC receiver's frames, good and bad, from its last `SYS_STATUS` (`errors_count2`,
    /// `errors_count1`).
    pub rc_frames: (u16, u16),
}

/// A restart of the firmware (a reboot it acknowledged, then silence, then a reply to a
/// sample sent again).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Restart {
    /// Lockstep steps done when the firmware acknowledged the reboot.
    pub acknowledged_at_step: u64,
    /// Its texts before the reboot's acknowledgement ([`FirmwareLog::texts`]`[..texts_before]`):
    /// what it says after its new boot follows.
    pub texts_before: usize,
    /// Lockstep steps done when it replied again (the step it replied to is the first of its
    /// new boot).
    pub back_at_step: u64,
}

impl FirmwareLog {
    /// The last value named `name`.
    pub fn last_value(&self, name: &str) -> Option<f64> {
        self.values
            .iter()
            .rev()
            .find(|v| v.name == name)
            .map(|v| v.value)
    }

    /// The acknowledgement of `command`, if one came.
    pub fn ack_of(&self, command: MavCmd) -> Option<MavResult> {
        self.acks
            .iter()
            .rev()
            .find(|(c, _)| *c == command)
            .map(|(_, r)| *r)
    }
}

/// The firmware refused a payload description (`payload refused: REASON`): what a run that
/// ends there reports.
#[derive(Clone, Debug, PartialEq)]
pub struct PayloadRefused {
    /// The board the firmware reported.
    pub firmware: String,
    /// Why, as the firmware said it.
    pub reason: String,
    /// Everything it said until then.
    pub texts: Vec<LoggedText>,
}

impl std::fmt::Display for PayloadRefused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the firmware refused the payload description: {}",
            self.reason
        )
    }
}

impl std::error::Error for PayloadRefused {}

/// A session with the firmware over a [`Link`].
pub struct Session {
    link: Link,
    texts: Reassembler,
    log: FirmwareLog,
    matcher: ReplyMatcher,
    gcs: Option<GcsBridge>,
    steps: u64,
    on_text: Box<dyn FnMut(&LoggedText) + Send>,
    /// The firmware acknowledged a reboot (steps done then, texts then) and has not come back
    /// yet.
    rebooting: Option<(u64, usize)>,
}

/// How long a ground station is silent before a lingering session ends ([`Session::linger`]).
pub const GCS_SILENCE: Duration = Duration::from_secs(2);

/// Time between resends of a request that got no answer.
const RESEND: Duration = Duration::from_millis(1000);

/// Longest a firmware may take to come back after a reboot it acknowledged, beyond the step's
/// own timeout.
pub const REBOOT_TIME: Duration = Duration::from_secs(30);

impl Session {
    /// A session over `link`; `gcs` (optional) gets every non-HIL frame, and `on_text` sees
    /// each text as it arrives.
    pub fn new(
        link: Link,
        gcs: Option<GcsBridge>,
        on_text: Box<dyn FnMut(&LoggedText) + Send>,
    ) -> Self {
        Self {
            link,
            texts: Reassembler::new(),
            log: FirmwareLog::default(),
            matcher: ReplyMatcher::new(),
            gcs,
            steps: 0,
            on_text,
            rebooting: None,
        }
    }

    /// What the firmware said so far.
    pub fn log(&self) -> &FirmwareLog {
        &self.log
    }

    /// Bytes that crossed the link so far.
    pub fn byte_counts(&self) -> super::transport::ByteCounts {
        self.link.counts()
    }

    /// Keeps the link up with no lockstep (the firmware's own tasks run on, the ground
    /// station's frames pass both ways) for at most `most`, ending once the ground station
    /// has been silent for [`GCS_SILENCE`] (at once without one).
    pub fn linger(&mut self, most: Duration) -> Result<()> {
        let end = Instant::now() + most;
        while let Some(gcs) = &self.gcs {
            let now = Instant::now();
            if now >= end || gcs.silent_for() >= GCS_SILENCE {
                break;
            }
            self.next((now + Duration::from_millis(100)).min(end))?;
        }
        Ok(())
    }

    /// Reads the firmware's frames until every flight log it said it started (`flight log N
    /// started`) it has also said it ended (`flight log N written: ...`, or why it stopped or
    /// is incomplete), at most `most` (wall time); an error naming its last texts when it does
    /// not. A firmware that started no log is not waited for.
    pub fn wait_for_logs_closed(&mut self, most: Duration) -> Result<()> {
        let open = |log: &FirmwareLog| {
            let said = |what: fn(&str) -> bool| log.texts.iter().filter(|t| what(&t.text)).count();
            let started = said(|t| t.starts_with("flight log ") && t.ends_with(" started"));
            let ended = said(|t| {
                (t.starts_with("flight log ") && t.contains(" written: "))
                    || t.starts_with("flight log incomplete")
                    || t.starts_with("flight log stopped")
            });
            started > ended
        };
        let end = Instant::now() + most;
        while open(&self.log) {
            let now = Instant::now();
            if now >= end {
                let last: Vec<&str> = self
                    .log
                    .texts
                    .iter()
                    .rev()
                    .take(5)
                    .map(|t| t.text.as_str())
                    .collect();
                bail!(
                    "the firmware did not say its flight log was written within {} s of the \
                     mission's end (its last texts, newest first: {last:?})",
                    most.as_secs()
                );
            }
            self.next((now + Duration::from_millis(100)).min(end))?;
        }
        Ok(())
    }

    /// A bridged ground station's frames forwarded and dropped (`None` without one).
    pub fn gcs_counts(&self) -> Option<super::gcs::GcsCounts> {
        self.gcs.as_ref().map(GcsBridge::counts)
    }

    /// Lockstep steps done.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The next frame (after logging what it says), or `None` at `deadline`.
    fn next(&mut self, deadline: Instant) -> Result<Option<Frame>> {
        let Some((frame, integrity)) = self.link.receive(deadline)? else {
            return Ok(None);
        };
        // The lockstep replies stay here. ACTUATOR_OUTPUT_STATUS goes to the ground too: the
        // firmware streams it for the ground station, and the one of a step past 8 robots is
        // of no harm there.
        if let (Some(gcs), false) = (
            &self.gcs,
            frame.message_id() == HIL_ACTUATOR_CONTROLS_DATA::ID,
        ) {
            gcs.to_ground(frame.bytes());
        }
        if integrity == Integrity::Verified {
            self.note(&frame);
        }
        Ok(Some(frame))
    }

    fn note(&mut self, frame: &Frame) {
        if let Some(chunk) = StatusChunk::from_frame(frame)
            && let Some(text) = self.texts.push(&chunk)
        {
            let text = String::from_utf8_lossy(&text).into_owned();
            if let Some(board) = text.strip_prefix(BOARD_PREFIX) {
                let name = board.split_whitespace().next().unwrap_or(board);
                self.log.board = Some(name.to_string());
            }
            let logged = LoggedText {
                step: self.steps,
                severity: chunk.message.severity,
                text,
            };
            (self.on_text)(&logged);
            self.log.texts.push(logged);
        } else if let Some(v) = frame.decode::<NAMED_VALUE_FLOAT_DATA>() {
            self.value(v.name.to_str().unwrap_or("?"), f64::from(v.value));
        } else if let Some(v) = frame.decode::<NAMED_VALUE_INT_DATA>() {
            self.value(v.name.to_str().unwrap_or("?"), f64::from(v.value));
        } else if let Some(m) = frame.decode::<link::msg::ESC_STATUS_DATA>() {
            self.log.esc_statuses += 1;
            let first = usize::from(m.index);
            if let Some(slots) = self.log.esc_rpm.get_mut(first..first + 4) {
                slots.copy_from_slice(&m.rpm);
            }
        } else if let Some(m) = frame.decode::<link::msg::ESC_INFO_DATA>() {
            for (i, flags) in m.failure_flags.iter().enumerate() {
                if *flags != 0 {
                    self.log.esc_failed |=
                        1u16.checked_shl(u32::from(m.index) + i as u32).unwrap_or(0);
                }
            }
        } else if let Some(m) = frame.decode::<link::msg::RC_CHANNELS_DATA>() {
            let c = [
                m.chan1_raw,
                m.chan2_raw,
                m.chan3_raw,
                m.chan4_raw,
                m.chan5_raw,
                m.chan6_raw,
                m.chan7_raw,
                m.chan8_raw,
                m.chan9_raw,
                m.chan10_raw,
                m.chan11_raw,
                m.chan12_raw,
                m.chan13_raw,
                m.chan14_raw,
                m.chan15_raw,
                m.chan16_raw,
            ];
            self.log.rc_channels = Some((c, m.chancount, m.rssi));
        } else if let Some(m) = frame.decode::<link::msg::SYS_STATUS_DATA>() {
            self.log.rc_frames = (m.errors_count2, m.errors_count1);
        } else if let Some(a) = frame.decode::<COMMAND_ACK_DATA>() {
            if a.command == MavCmd::MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN
                && a.result == MavResult::MAV_RESULT_ACCEPTED
            {
                self.rebooting = Some((self.steps, self.log.texts.len()));
            }
            self.log.acks.push((a.command, a.result));
        } else if let Some(h) = frame.decode::<HEARTBEAT_DATA>()
            && frame.system_id() == link::VEHICLE_SYSTEM_ID
        {
            self.log.heartbeats += 1;
            self.log.state = MissionState::from_custom_mode(h.custom_mode);
        }
    }

    fn value(&mut self, name: &str, value: f64) {
        self.log.values.push(LoggedValue {
            step: self.steps,
            name: name.to_string(),
            value,
        });
    }

    /// Asks the firmware who it is until its board's name comes, within `timeout`.
    pub fn identify(&mut self, timeout: Duration) -> Result<String> {
        let end = Instant::now() + timeout;
        let request = command_long(
            MavCmd::MAV_CMD_REQUEST_MESSAGE,
            AUTOPILOT_VERSION_DATA::ID as f32,
            0.0,
        );
        while Instant::now() < end {
            if let Some(board) = &self.log.board {
                return Ok(board.clone());
            }
            self.link.send(&request)?;
            let resend = (Instant::now() + RESEND).min(end);
            while self.log.board.is_none() && self.next(resend)?.is_some() {}
        }
        match &self.log.board {
            Some(board) => Ok(board.clone()),
            None => bail!(
                "the firmware did not say which board it runs on within {} s ({} heartbeats seen): is it running and is the link right?",
                timeout.as_secs(),
                self.log.heartbeats
            ),
        }
    }

    /// Writes the payload description `file` over MAVLink FTP and waits for the firmware's
    /// verdict: `Ok` with its text when accepted, an error with its reason when refused.
    pub fn upload_payload(&mut self, file: &[u8], timeout: Duration) -> Result<String> {
        let end = Instant::now() + timeout;
        let mut upload = Upload::new(PAYLOAD_PATH, file);
        let texts_before = self.log.texts.len();
        'commands: loop {
            let request = upload.current();
            self.link
                .send(&request.to_message(link::VEHICLE_SYSTEM_ID, link::VEHICLE_COMPONENT_ID))?;
            let resend = (Instant::now() + RESEND).min(end);
            while let Some(frame) = self.next(resend)? {
                let Some(f) = frame.decode::<FILE_TRANSFER_PROTOCOL_DATA>() else {
                    continue;
                };
                let answer = FtpMessage::from_payload(&f.payload);
                match upload
                    .on_answer(&answer)
                    .map_err(|e| anyhow!("payload upload: {e}"))?
                {
                    Progress::Ignored => {}
                    Progress::Continue => continue 'commands,
                    Progress::Done => break 'commands,
                }
            }
            if Instant::now() >= end {
                bail!(
                    "payload upload: no FTP answer from the firmware within {} s",
                    timeout.as_secs()
                );
            }
        }
        self.payload_verdict(texts_before, end)
    }

    /// Waits until `end` for the firmware's verdict on a payload description among its texts
    /// from `texts_before` on (`payload NAME accepted: ...` or `payload refused: ...`): `Ok`
    /// with its text when accepted, an error with its reason when refused. A description
    /// restored from storage at boot gets the same verdict.
    pub fn payload_verdict(&mut self, texts_before: usize, end: Instant) -> Result<String> {
        let waited = end.saturating_duration_since(Instant::now());
        loop {
            if let Some(t) = self.log.texts[texts_before.min(self.log.texts.len())..]
                .iter()
                .find(|t| is_payload_verdict(&t.text))
            {
                if !t.text.contains(" accepted") {
                    let reason = t.text.split_once(": ").map_or(&*t.text, |(_, why)| why);
                    return Err(PayloadRefused {
                        firmware: self.log.board.clone().unwrap_or_default(),
                        reason: reason.to_string(),
                        texts: self.log.texts.clone(),
                    }
                    .into());
                }
                return Ok(t.text.clone());
            }
            if self.next(end)?.is_none() {
                bail!(
                    "the firmware did not say whether it accepted the payload description within {} s",
                    waited.as_secs()
                );
            }
        }
    }

    /// Sets the vehicle's parameter `name` to `value` and waits (at most `timeout`) for its
    /// `PARAM_VALUE` with that value in force: an error naming the parameter, with what the
    /// vehicle said, when it keeps another value or does not answer.
    pub fn set_param(&mut self, name: &str, value: f32, timeout: Duration) -> Result<()> {
        let end = Instant::now() + timeout;
        let texts_before = self.log.texts.len();
        let set = link::msg::PARAM_SET_DATA {
            param_value: value,
            target_system: link::VEHICLE_SYSTEM_ID,
            target_component: link::VEHICLE_COMPONENT_ID,
            param_id: name.into(),
            param_type: link::msg::MavParamType::MAV_PARAM_TYPE_REAL32,
        };
        while Instant::now() < end {
            self.link.send(&set)?;
            let resend = (Instant::now() + RESEND).min(end);
            while let Some(frame) = self.next(resend)? {
                let Some(m) = frame.decode::<PARAM_VALUE_DATA>() else {
                    continue;
                };
                if m.param_id.to_str().unwrap_or("") != name {
                    continue;
                }
                if m.param_value == value {
                    return Ok(());
                }
                let why = self.log.texts[texts_before..]
                    .last()
                    .map(|t| format!(": {}", t.text))
                    .unwrap_or_default();
                bail!(
                    "the firmware kept {name} = {} when set to {value}{why}",
                    m.param_value
                );
            }
        }
        bail!(
            "the firmware did not answer PARAM_SET {name} within {} s",
            timeout.as_secs()
        )
    }

    /// Sends a ground station's joystick (`MANUAL_CONTROL` x, y, z, r).
    pub fn send_manual_control(&mut self, [x, y, z, r]: [i16; 4]) -> Result<()> {
        self.link.send(&link::msg::MANUAL_CONTROL_DATA {
            target: link::VEHICLE_SYSTEM_ID,
            x,
            y,
            z,
            r,
            ..Default::default()
        })
    }

    /// Sends the simulated ground station's heartbeat (`MAV_TYPE_GCS`, once a second).
    pub fn send_gcs_heartbeat(&mut self) -> Result<()> {
        self.link.send(&link::vehicle::gcs_heartbeat())
    }

    /// Sends the simulated pack's voltage (`BATTERY_STATUS`).
    pub fn send_battery(&mut self, volts: f32) -> Result<()> {
        self.link.send(&link::vehicle::battery_status(volts))
    }

    /// Sends each rotor's RPM (`ESC_STATUS`, four ESCs a message, `robots` of them) stamped
    /// with the step's time `time_us`, before the step's `HIL_SENSOR`: the plant's stand-in
    /// for the ESCs' bidirectional DShot (docs/firmware.md#esc-telemetry).
    pub fn send_esc_rpm(&mut self, time_us: u64, rpm: &[f32], robots: usize) -> Result<()> {
        let per = link::esc::ESCS_PER_MESSAGE;
        for (group, chunk) in rpm[..robots.min(rpm.len())].chunks(per).enumerate() {
            let mut values = [0i32; 4];
            for (v, &r) in values.iter_mut().zip(chunk) {
                // The RPM rounded; `as` saturates.
                *v = r.round() as i32;
            }
            self.link.send(&link::msg::ESC_STATUS_DATA {
                time_usec: time_us,
                rpm: values,
                index: (group * per) as u8,
                ..Default::default()
            })?;
        }
        Ok(())
    }

    /// Cuts (or mends) the bridge from the real ground station, if there is one.
    pub fn cut_ground(&mut self, cut: bool) {
        if let Some(gcs) = &self.gcs {
            gcs.cut(cut);
        }
    }

    /// Sends an operator command (acknowledged with the next step's reply).
    pub fn send_command(&mut self, command: OperatorCommand) -> Result<()> {
        self.link.send(&command.to_command_long())
    }

    /// One lockstep step: sends the motion-capture fixes due and the IMU sample, and waits (at
    /// most `timeout`) for the `HIL_ACTUATOR_CONTROLS` stamped with the sample's time.
    pub fn step(
        &mut self,
        imu: &PlantSample,
        fixes: &[MocapFix],
        robots: usize,
        timeout: Duration,
    ) -> Result<Actuators> {
        // One write: one Ethernet frame for the step's input.
        for fix in fixes {
            self.link.batch(&mocap_message(fix));
        }
        self.link.batch(&imu.to_message());
        self.link.send_batch()?;
        self.matcher.sent(imu.time_us);
        let sent = Instant::now();
        let mut resend_at = sent + RESEND;
        let mut resent = false;
        loop {
            // After a reboot the firmware acknowledged, a second with no reply means it is
            // restarting (its telemetry may have come meanwhile): the sample goes again each
            // second until its new boot takes one.
            let rebooting = self.rebooting.is_some();
            let allowed = if rebooting {
                timeout + REBOOT_TIME
            } else {
                timeout
            };
            let end = sent + allowed;
            let frame = self.next(if rebooting { resend_at.min(end) } else { end })?;
            let now = Instant::now();
            if rebooting && now >= resend_at && now < end {
                for fix in fixes {
                    self.link.batch(&mocap_message(fix));
                }
                self.link.batch(&imu.to_message());
                self.link.send_batch()?;
                resent = true;
                resend_at = now + RESEND;
            }
            let Some(frame) = frame else {
                if now < end {
                    continue;
                }
                let after_reboot = if rebooting {
                    " after the reboot it acknowledged: it did not come back"
                } else {
                    ": the firmware stalled or the link is down"
                };
                bail!(
                    "lockstep: no HIL_ACTUATOR_CONTROLS for the step at t = {:.4} s (step {}) within {:.1} s{after_reboot}{}",
                    imu.time_us as f64 * 1e-6,
                    self.steps,
                    sent.elapsed().as_secs_f64(),
                    self.host_drops_said()
                );
            };
            if let Some(status) = frame.decode::<ACTUATOR_OUTPUT_STATUS_DATA>() {
                // Only the step's own status carries the rail channels (bits from MAX_ROBOTS
                // in `active`); the one streamed for the ground station, of the same time,
                // has the robots' ESC commands alone.
                if status.active >> link::hil::MAX_ROBOTS != 0 {
                    self.matcher.on_status(&status);
                }
            } else if let Some(controls) = frame.decode::<HIL_ACTUATOR_CONTROLS_DATA>()
                && let Reply::Commands(commands) = self
                    .matcher
                    .on_controls(&controls, robots)
                    .map_err(|e| anyhow!("lockstep: {e}"))?
            {
                if resent && let Some((acknowledged_at_step, texts_before)) = self.rebooting.take()
                {
                    self.log.restarts.push(Restart {
                        acknowledged_at_step,
                        texts_before,
                        back_at_step: self.steps,
                    });
                }
                self.steps += 1;
                return Ok(commands);
            }
        }
    }

    /// What this machine dropped of the firmware's datagrams, for a lockstep error: a reply
    /// the firmware sent and the host lost is not the firmware's stall.
    fn host_drops_said(&self) -> String {
        match self.link.host_drops() {
            Some(n) if n > 0 => format!(
                " (this machine dropped {n} of the firmware's datagrams, its socket's buffer \
                 full: the reply may be among them)"
            ),
            _ => String::new(),
        }
    }
}

/// Whether `text` is the firmware's verdict on a payload description: `payload NAME
/// accepted: ...`, `payload refused: ...` or `payload upload refused: ...` (not `payload
/// description restored from storage` and the like, said before a verdict).
fn is_payload_verdict(text: &str) -> bool {
    text.starts_with("payload refused")
        || text.starts_with("payload upload refused")
        || (text.starts_with("payload ") && text.contains(" accepted"))
}

/// The pack's voltage as the firmware's control step reads it after `BATTERY_STATUS` carried
/// it (`link::vehicle::battery_status`: whole millivolts, cut; `battery_volts` back to volts;
/// the link service's millivolts, cut again; volts in the step): what the in-process vehicle
/// is given, so that `mission` and `hil` agree to the bit.
pub fn carried_volts(volts: f32) -> f32 {
    use link::vehicle::{millivolts_of, pack_millivolts, volts_of};
    let received = volts_of(u32::from(pack_millivolts(volts)));
    volts_of(millivolts_of(received))
}
