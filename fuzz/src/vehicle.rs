//! The flight controller's MAVLink input handling as one synchronous host program: the
//! firmware's own receive service (`onboard::link_service::LinkService`, which the firmware's
//! link task calls) over [`QueuePorts`], with the firmware's control task (one step of
//! `onboard::autonomy` per IMU sample, the job's result at its deadline) and job task
//! (`onboard::payload_loading` and the planner) played behind it ([`crate::tasks`]), and a
//! ground side that reads back every frame the vehicle sends ([`crate::ground`]).
//!
//! A branch added to the service is fuzzed as it is: this harness calls the service, not a
//! copy of it. What is its own: the order the firmware's tasks take their turns (a frame's
//! handling, then the control steps it causes, a job run at once and taken at its deadline,
//! as in lockstep HIL), the board's IMU driver, and the invariants.
//!
//! [`Vehicle`] panics, with the reason, when one of these invariants breaks:
//! - a frame the vehicle ignores, or one it does not trust (signing on, unsigned or bad
//!   signature), changes nothing: parameters, the FTP file, queued commands, the telemetry
//!   rates, the signing state;
//! - a refused parameter write leaves the value in force; every value in force is one the
//!   table accepts; no value changes while the mission runs, nor a mission but by a
//!   set-current;
//! - the harness's parser and the service's find the same frames;
//! - every command taken is acknowledged;
//! - the rotors are armed only in the phases that spin them (lift, arming, flight), with
//!   thrust only in lift and flight, every thrust a finite fraction in `[0, 1]`, every rail
//!   setpoint finite; never armed when the heartbeat says idle, completed or aborted, but for
//!   a motor test (on the ground, the mission not running);
//! - every frame sent parses back whole, its checksum (and signature) verified;
//! - after the input, a restart finds in the store exactly the parameters, the signing key
//!   and the payload description in force (unless the store reported an error).

use embassy_futures::block_on;
use link::frame::{Encoder, Frame, Integrity, Parser};
use link::ftp::{FtpMessage, Opcode};
use link::hil::{JobDeadline, VehicleClock};
use link::mission::wire::MissionMessage;
use link::signing::{KEY_LEN, Signing, Verdict};
use link::status::MissionState;
use link::vehicle::{Inbound, crc_extra, dispatch};
use onboard::autonomy::{Autonomy, JobResult, Report, Severity};
use onboard::link_service::{LINK_ID, LinkService, Outbound, QueuePorts};
use onboard::payload_loading::{LoadedPayload, PayloadLoader};
use onboard::store::{ParamStore, StoreError};
use shared::mission::MissionPlanner;
use shared::mission::params::{COUNT as PARAM_COUNT, ParamValues, check};
use shared::scenario_wire::{MAX_ENCODED_LEN, decode_and_check};

use crate::flash::{MISSION_RANGE, MemFlash, PARAM_RANGE, PAYLOAD_RANGE};

pub use crate::options::Options;

/// The payload description's checksum (`shared::scenario_wire`'s).
const CRC32: crc::Crc<u32, crc::NoTable> =
    crc::Crc::<u32, crc::NoTable>::new(&crc::CRC_32_ISO_HDLC);
/// Largest payload description file the vehicle takes.
pub const FILE_CAPACITY: usize = MAX_ENCODED_LEN;
/// The signing key a seed's "key stored" option puts in the store before the start.
pub const SEED_KEY: [u8; KEY_LEN] = [7; KEY_LEN];
/// The signing timestamp stored with [`SEED_KEY`].
pub const SEED_KEY_TIMESTAMP: u64 = 1_000_000;
/// Board time one received byte takes (115,200 baud), us.
pub const BYTE_US: u64 = 87;
/// The control period of the board's IMU driver, us (400 Hz).
pub const TICK_US: u64 = 2_500;
/// Most steps the IMU driver takes in one run (50 s of the mission): bounds the time of one
/// fuzz input (about 0.1 s) without a plant to fly, the mission never gets further.
pub const MAX_DRIVER_STEPS: u64 = 20_000;

/// The vehicle: the receive service and what it hands to, the control task's state and the
/// job task's, and the ground side.
pub struct Vehicle {
    pub(crate) options: Options,
    pub(crate) service: Box<LinkService<MemFlash>>,
    pub(crate) io: QueuePorts,
    /// The harness's own parser, beside the service's: which frame comes, to check the
    /// invariants around its handling.
    mirror: Parser,
    pub(crate) next_beat_us: u64,
    pub(crate) frames: u32,
    pub(crate) driver_steps: u64,
    /// A store operation failed: a restart may legitimately find older values.
    store_failed: bool,
    /// What a restart must find in the store.
    stored_key: Option<[u8; KEY_LEN]>,
    stored_payload: Option<Vec<u8>>,
    /// The job task: the planner and the last description accepted.
    pub(crate) planner: Box<MissionPlanner>,
    pub(crate) loader: Box<PayloadLoader>,
    /// `PAYLOAD`: the newest description loaded into the planner, for the control task.
    pub(crate) payload: Option<LoadedPayload>,
    /// The control task.
    pub(crate) autonomy: Box<Autonomy>,
    pub(crate) clock: VehicleClock,
    pub(crate) deadline: JobDeadline,
    pub(crate) job_id: u32,
    pub(crate) job_result: Option<(u32, JobResult)>,
    /// The phase as the vehicle last reported it (`phase: NAME: reason`).
    pub(crate) phase: String,
    /// [`Self::steps`] when the phase was last reported.
    pub(crate) phase_since: u64,
    /// The send side.
    pub(crate) encoder: Encoder,
    pub(crate) frame: Frame,
    pub(crate) text_id: u16,
    pub(crate) ground: Parser,
    pub(crate) ground_signing: Signing,
    /// Frames sent (for the seed generator's checks).
    pub sent: u32,
    /// Control steps taken.
    pub steps: u64,
    /// The phases the mission went through, in order, with their reasons.
    pub phases: Vec<String>,
}

/// The description the "payload stored" option puts in the store: rect-sim1, encoded.
pub fn stored_payload() -> &'static [u8] {
    use std::sync::OnceLock;
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    BYTES.get_or_init(|| crate::seeds::encoded_scenario(crate::seeds::SCENARIOS[4].1))
}

impl Vehicle {
    /// The vehicle after its start with `options`: the store opened and read, the signing key,
    /// payload description and mission restored (the firmware's receive task before its loop).
    pub fn start(options: Options) -> Self {
        let mut flash = MemFlash::new();
        if options.payload_stored || options.key_stored {
            let mut store = open(flash).expect("the store opens on a blank flash");
            if options.payload_stored {
                block_on(store.save_payload(stored_payload())).expect("payload stored");
            }
            if options.key_stored {
                block_on(store.save_signing(&SEED_KEY, SEED_KEY_TIMESTAMP)).expect("key stored");
            }
            flash = store.into_flash().expect("the flash back");
        }
        let mut io = QueuePorts::new();
        io.key_setup_allowed = options.key_setup_allowed;
        let mut v = Self {
            options,
            service: Box::new(LinkService::new(&[])),
            io,
            mirror: Parser::new(crc_extra),
            next_beat_us: 0,
            frames: 0,
            driver_steps: 0,
            store_failed: false,
            stored_key: None,
            stored_payload: None,
            planner: Box::new(MissionPlanner::UNLOADED),
            loader: Box::new(PayloadLoader::new()),
            payload: None,
            autonomy: Box::new(Autonomy::new()),
            clock: VehicleClock::new(),
            deadline: JobDeadline::new(),
            job_id: 0,
            job_result: None,
            phase: "idle".into(),
            encoder: Encoder::new(link::VEHICLE_SYSTEM_ID, link::VEHICLE_COMPONENT_ID),
            frame: Frame::default(),
            text_id: 0,
            ground: Parser::new(crc_extra),
            ground_signing: Signing::new(),
            sent: 0,
            steps: 0,
            phase_since: 0,
            phases: Vec::new(),
        };
        v.send_outbound(&Outbound::Identity);
        block_on(v.service.start(open(flash), &mut v.io));
        if v.io.signing.enabled() {
            v.stored_key = Some(SEED_KEY);
            v.ground_key(SEED_KEY, SEED_KEY_TIMESTAMP);
        }
        if v.io.to_load.is_some() {
            v.stored_payload = Some(v.service.payload_file().to_vec());
        }
        v.other_tasks();
        v
    }

    /// Takes the received bytes `stream`, one at a time, as the link task does.
    pub fn receive(&mut self, stream: &[u8]) {
        for &byte in stream {
            self.io.now_us += BYTE_US;
            self.heartbeat_due();
            let before = self.io.parsed.frames;
            let Some((frame, integrity)) = self.mirror.push(byte) else {
                block_on(self.service.receive(&[byte], &mut self.io));
                assert_eq!(before, self.io.parsed.frames, "the parsers disagree");
                continue;
            };
            let frame = frame.clone();
            // The verdict the service will reach: its check on a copy of the signing state.
            let mut probe = self.io.signing;
            let verdict = probe.check(&frame, self.io.now_us);
            let inbound = dispatch(&frame, integrity);
            if integrity == Integrity::Unverified {
                assert!(
                    matches!(inbound, Inbound::Ignored { .. }),
                    "an unverified frame was dispatched: {inbound:?}"
                );
            }
            if self.options.fix_payload_checksum {
                self.fix_payload_checksum(&inbound, verdict);
            }
            // The signing state after the service's check of this frame, which a frame may change.
            let checked = Checked::before(self, &inbound, verdict, probe);
            block_on(self.service.receive(&[byte], &mut self.io));
            assert_eq!(before + 1, self.io.parsed.frames, "the parsers disagree");
            checked.after(self, &inbound);
            self.other_tasks();
            self.frames = self.frames.saturating_add(1);
            if self.options.imu_driver {
                for _ in 0..self.options.ticks {
                    if self.driver_steps < MAX_DRIVER_STEPS {
                        self.driver_step();
                    }
                }
            }
        }
    }

    /// With [`Options::fix_payload_checksum`]: before an upload's close reaches the service,
    /// its last four bytes are written as the CRC-32 of the rest, as a ground station with a
    /// well-formed file of those contents would have.
    fn fix_payload_checksum(&mut self, inbound: &Inbound, verdict: Verdict) {
        let Inbound::Ftp { message, from } = inbound else {
            return;
        };
        if message.opcode != Opcode::TerminateSession as u8 || !verdict.trusted() {
            return;
        }
        let file = self.service.payload_file();
        let Some(n) = file.len().checked_sub(4) else {
            return;
        };
        let crc = CRC32.checksum(&file[..n]);
        let mut write = FtpMessage::command(message.seq.wrapping_sub(1), Opcode::WriteFile);
        write.session = message.session;
        write.offset = n as u32;
        write.set_data(&crc.to_le_bytes());
        let fix = Inbound::Ftp {
            message: write,
            from: *from,
        };
        block_on(self.service.handle(fix, verdict, &mut self.io));
        self.other_tasks();
    }

    /// The ground station takes the vehicle's key at the same moment (its own link id).
    pub(crate) fn ground_key(&mut self, key: [u8; KEY_LEN], timestamp: u64) {
        self.ground_signing
            .set_key(key, timestamp, self.io.now_us, LINK_ID + 1);
    }

    /// The end of the input: the board restarts and must find in its store what was in force.
    pub fn restart_check(mut self) {
        let Some(store) = self.service.take_store() else {
            return;
        };
        if self.store_failed {
            return;
        }
        let flash = store.into_flash().expect("the flash back from the store");
        let mut store = open(flash).expect("the store opens again");
        let mut values = ParamValues::DEFAULT;
        let loaded = block_on(store.load(&mut values));
        assert_eq!(loaded.error, None, "the store fails after a restart");
        assert_eq!(
            &values,
            self.service.params().values(),
            "parameters lost in a restart"
        );
        let key = block_on(store.load_signing()).expect("the signing key reads back");
        assert_eq!(
            key.map(|(k, _)| k).filter(|k| *k != [0; KEY_LEN]),
            self.stored_key,
            "signing key lost in a restart"
        );
        let mut buffer = vec![0u8; FILE_CAPACITY];
        let valid = |bytes: &[u8]| decode_and_check(bytes).is_ok();
        let payload = block_on(store.load_payload(&mut buffer, valid))
            .expect("the payload description reads back");
        assert_eq!(
            payload.map(|len| buffer[..len].to_vec()),
            self.stored_payload,
            "payload description lost in a restart"
        );
    }

    /// What the vehicle's other tasks do with what the service queued: the control task steps
    /// on the plant's samples, the job task loads a description, the send task sends the
    /// replies (noting a store's failure said in them).
    pub(crate) fn other_tasks(&mut self) {
        // The control task: a step on each sample the plant sent.
        while let Some(sample) = self.io.sensors.pop_front() {
            self.control_step(sample.time_us, sample.imu, sample.hil);
        }
        // The receive task's poll after each read: an upload's timeout, a calibration's
        // offsets to store.
        block_on(self.service.poll(&mut self.io));
        if let Some(received) = self.io.to_load.take() {
            let running = self.io.mission_state == MissionState::Running;
            let (report, loaded) =
                self.loader
                    .load(&mut self.planner, received, self.io.config, running);
            if let Some(payload) = loaded {
                self.io.payload_robots = payload.scenario.robots.count();
                self.payload = Some(payload);
            }
            self.send_report(&report, 0);
        }
        if core::mem::take(&mut self.io.reload) {
            let running = self.io.mission_state == MissionState::Running;
            if let Some((report, loaded)) =
                self.loader
                    .reload(&mut self.planner, self.io.config, running)
            {
                if let Some(payload) = loaded {
                    self.payload = Some(payload);
                }
                self.send_report(&report, 0);
            }
        }
        while let Some(reply) = self.io.outbox.pop_front() {
            if let Outbound::Report(report) = &reply {
                self.note_store_failures(report);
            }
            self.send_outbound(&reply);
        }
        while let Some(message) = self.io.bulk.pop_front() {
            self.send_bulk(&message);
        }
        self.send_lists();
    }

    /// A store's failure, said in a text: a restart may then find older values.
    fn note_store_failures(&mut self, report: &Report) {
        let failed = report.texts.iter().any(|t| {
            t.severity == Severity::Error
                && (t.text.contains("not stored") || t.text.starts_with("params:"))
        });
        self.store_failed |= failed;
    }
}

/// What a frame may change, taken before its handling and checked after.
struct Checked {
    inert: bool,
    untrusted: bool,
    was_running: bool,
    values: ParamValues,
    file: Vec<u8>,
    commands: Vec<onboard::link_service::PendingCommand>,
    telemetry: link::telemetry::Schedule,
    signing: Signing,
    mission: Vec<link::mission::wire::WireItem>,
    offered: u32,
}

impl Checked {
    fn before(v: &Vehicle, inbound: &Inbound, verdict: Verdict, signing: Signing) -> Self {
        let inert = matches!(
            inbound,
            Inbound::Ignored { .. }
                | Inbound::Heartbeat(_)
                | Inbound::GcsHeartbeat(_)
                | Inbound::Battery { .. }
                | Inbound::EscStatus(_)
        );
        Self {
            inert,
            untrusted: !verdict.trusted(),
            was_running: v.io.mission_state == MissionState::Running,
            values: v.service.params().values().clone(),
            file: v.service.payload_file().to_vec(),
            commands: v.io.commands.iter().copied().collect(),
            telemetry: v.io.telemetry,
            signing,
            mission: v.service.mission().items().to_vec(),
            offered: v.io.offered,
        }
    }

    fn after(self, v: &mut Vehicle, inbound: &Inbound) {
        let values = v.service.params().values();
        let commands: Vec<_> = v.io.commands.iter().copied().collect();
        if self.inert {
            assert_eq!(&self.values, values, "an ignored frame changed a parameter");
            assert_eq!(
                self.file,
                v.service.payload_file(),
                "an ignored frame changed the FTP file"
            );
            assert_eq!(self.commands, commands, "an ignored frame queued a command");
            assert_eq!(
                self.telemetry, v.io.telemetry,
                "an ignored frame changed the telemetry rates"
            );
            assert_eq!(
                self.signing, v.io.signing,
                "an ignored frame changed the signing state"
            );
        }
        if self.untrusted || self.was_running {
            assert_eq!(
                &self.values, values,
                "a parameter changed (untrusted {}, running {})",
                self.untrusted, self.was_running
            );
            let set_current = matches!(
                inbound,
                Inbound::Mission {
                    message: MissionMessage::SetCurrent { .. },
                    ..
                }
            );
            if !set_current {
                assert_eq!(
                    self.mission,
                    v.service.mission().items(),
                    "a locked mission changed"
                );
            }
        }
        if self.untrusted {
            assert_eq!(
                self.file,
                v.service.payload_file(),
                "an untrusted upload wrote the file"
            );
            assert!(
                commands.len() <= self.commands.len(),
                "an untrusted command was queued"
            );
        }
        for i in 0..PARAM_COUNT {
            let value = values.get(i).expect("every index has a value");
            assert!(
                check(i, value).is_ok(),
                "parameter {i} = {value} is out of range"
            );
        }
        // What a restart must find: the key set, the description accepted from an upload.
        if let Inbound::SetupSigning { key, timestamp, .. } = inbound
            && v.options.key_setup_allowed
        {
            assert_eq!(
                v.io.signing.enabled(),
                *key != [0; KEY_LEN],
                "signing on with an all-zero key"
            );
            v.stored_key = (*key != [0; KEY_LEN]).then_some(*key);
            v.ground_key(*key, *timestamp);
        }
        if v.io.offered > self.offered {
            v.stored_payload = Some(v.service.payload_file().to_vec());
        }
    }
}

/// The store over `flash` with the Pixhawk 6C's ranges (the firmware's receive task).
fn open(flash: MemFlash) -> Result<ParamStore<MemFlash>, StoreError> {
    ParamStore::new(flash, PARAM_RANGE)
        .and_then(|s| s.with_payload(PAYLOAD_RANGE))
        .and_then(|s| s.with_mission(MISSION_RANGE))
}

/// Runs one `link_input` fuzz input: the header's options, then the byte stream.
pub fn run(data: &[u8]) -> Option<Vehicle> {
    let header: [u8; Options::HEADER_LEN] = data.get(..Options::HEADER_LEN)?.try_into().ok()?;
    let options = Options::from_header(header);
    let mut vehicle = Vehicle::start(options);
    if options.fix_checksums {
        let mut stream = data[Options::HEADER_LEN..].to_vec();
        fix_checksums(&mut stream);
        vehicle.receive(&stream);
    } else {
        vehicle.receive(&data[Options::HEADER_LEN..]);
    }
    Some(vehicle)
}

/// Recomputes the checksum of each frame of `stream` whose message the vehicle knows, where
/// the parser ([`link::frame::Parser`]) will find it: its state machine, followed over the
/// bytes (a start byte begins a frame; a MAVLink 2 header with flags other than "signed" is
/// dropped; a whole frame is taken, and the search goes on after it).
pub fn fix_checksums(stream: &mut [u8]) {
    use link::frame::{STX_V1, STX_V2};
    use link::signing::{IFLAG_SIGNED, SIGNATURE_LEN};
    let mut i = 0;
    while i < stream.len() {
        let stx = stream[i];
        if stx != STX_V1 && stx != STX_V2 {
            i += 1;
            continue;
        }
        let v1 = stx == STX_V1;
        let header = if v1 { 6 } else { 10 };
        if i + header > stream.len() {
            return;
        }
        let h = &stream[i..i + header];
        if !v1 && h[2] & !IFLAG_SIGNED != 0 {
            i += header;
            continue;
        }
        let crc_end = i + header + usize::from(h[1]);
        let id = if v1 {
            u32::from(h[5])
        } else {
            u32::from_le_bytes([h[7], h[8], h[9], 0])
        };
        let signature = if !v1 && h[2] & IFLAG_SIGNED != 0 {
            SIGNATURE_LEN
        } else {
            0
        };
        if crc_end + 2 + signature > stream.len() {
            return;
        }
        if let Some(extra) = crc_extra(id) {
            let crc = mavlink::calculate_crc(&stream[i + 1..crc_end], extra);
            stream[crc_end..crc_end + 2].copy_from_slice(&crc.to_le_bytes());
        }
        i = crc_end + 2 + signature;
    }
}
