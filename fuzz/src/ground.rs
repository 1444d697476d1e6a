//! The harness's send side and ground station: what the firmware's send task sends for each
//! reply, bulk message and parameter list the receive service queued, the heartbeat, a
//! control step's texts and values, each frame encoded, signed once signing is on, and read
//! back by a ground-side parser and signature check.

use link::MessageData;
use link::command::ack;
use link::frame::Integrity;
use link::ftp::component_metadata;
use link::geo::GeoOrigin;
use link::log_transfer::LogReply;
use link::modes::MODES;
use link::msg::{AUTOPILOT_VERSION_DATA, TIMESYNC_DATA};
use link::param::value_message;
use link::signing::Verdict;
use link::status::{chunks, heartbeat, named_float, named_int};
use link::telemetry::{Home, gps_global_origin};
use link::vehicle::crc_extra;
use onboard::autonomy::{Report, Severity, Value};
use onboard::link_service::{Bulk, Outbound, mav_severity};
use shared::mission::params::COUNT as PARAM_COUNT;

use crate::vehicle::Vehicle;

impl Vehicle {
    /// The heartbeat and a time-sync request, once a second of the board's clock.
    pub(crate) fn heartbeat_due(&mut self) {
        if self.io.now_us >= self.next_beat_us {
            let beat = heartbeat(
                self.io.mission_state,
                self.autonomy.mode(),
                self.io.armed,
                self.io.in_hil,
            );
            self.send(&beat);
            let request = self.io.timesync.request(ns(self.io.now_us));
            self.send(&request);
            self.next_beat_us = self.io.now_us + 1_000_000;
        }
    }

    /// One reply of the service's queue, as the firmware's send task sends it.
    pub(crate) fn send_outbound(&mut self, message: &Outbound) {
        let origin = GeoOrigin::from_params(&self.io.values);
        match message {
            Outbound::Report(report) => self.send_report(report, (self.io.now_us / 1000) as u32),
            Outbound::Ack { command, result } => self.send(&ack(*command, *result)),
            Outbound::Identity => {
                self.send(&AUTOPILOT_VERSION_DATA {
                    capabilities: link::status::capabilities(),
                    ..Default::default()
                });
                self.report_text(Severity::Info, "board: fuzz (firmware 0.1.0)");
            }
            Outbound::ComponentMetadata => {
                let uri = shared::mission::params::metadata::GENERAL_URI;
                let now_ms = (self.io.now_us / 1000) as u32;
                self.send(&component_metadata(now_ms, 0, uri));
            }
            Outbound::Params(indices) => {
                for index in (0..PARAM_COUNT).filter(|&i| indices.contains(i)) {
                    let m = value_message(&self.io.values, index).expect("an index in range");
                    self.send(&m);
                }
            }
            Outbound::TimeSync { tc1, ts1 } => self.send(&TIMESYNC_DATA {
                tc1: *tc1,
                ts1: *ts1,
            }),
            Outbound::AvailableModes(index) => {
                for (i, mode) in MODES.iter().enumerate() {
                    if *index == 0 || usize::from(*index) == i + 1 {
                        self.send(&mode.available());
                    }
                }
            }
            Outbound::CurrentMode => {
                let mode = self.autonomy.mode();
                self.send(&mode.current(mode));
            }
            Outbound::Origin => self.send(&gps_global_origin(&origin)),
            Outbound::Home => {
                if let Some(home) = Home::START.home_position(&origin) {
                    self.send(&home);
                }
            }
        }
    }

    /// One bulk transfer's message.
    pub(crate) fn send_bulk(&mut self, message: &Bulk) {
        match message {
            Bulk::Ftp { message, to } => self.send(&message.to_message(to.system, to.component)),
            Bulk::Mission { reply, to } => {
                reply.encode(*to, &mut self.encoder, &mut self.frame);
                self.flush();
            }
            Bulk::Log(LogReply::Entry(entry)) => self.send(entry),
            Bulk::Log(LogReply::Data(data)) => self.send(data),
        }
    }

    /// The parameter lists in flight, whole (the link always has room here).
    pub(crate) fn send_lists(&mut self) {
        while let Some(i) = self.io.lists.next(PARAM_COUNT) {
            let m = value_message(&self.io.values, i).expect("an index in range");
            self.send(&m);
        }
    }

    /// A report's texts and values.
    pub(crate) fn send_report(&mut self, report: &Report, time_ms: u32) {
        for line in &report.texts {
            let text = line.text.clone();
            self.report_text(line.severity, &text);
        }
        for v in &report.values {
            match v.value {
                Value::Float(x) => self.send(&named_float(v.name, x, time_ms)),
                Value::Int(x) => self.send(&named_int(v.name, x, time_ms)),
            }
        }
    }

    /// One text, in `STATUSTEXT` chunks.
    pub(crate) fn report_text(&mut self, severity: Severity, text: &str) {
        self.text_id = self.text_id.wrapping_add(1).max(1);
        for chunk in chunks(text, mav_severity(severity), self.text_id) {
            chunk.encode(&mut self.encoder, &mut self.frame);
            self.flush();
        }
    }

    /// One message.
    pub(crate) fn send<M: MessageData>(&mut self, message: &M) {
        self.encoder.encode(message, &mut self.frame);
        self.flush();
    }

    /// Signs the frame when signing is on, and checks that the ground reads it back.
    fn flush(&mut self) {
        if let Some(extra) = crc_extra(self.frame.message_id()) {
            self.io.signing.sign(&mut self.frame, extra, self.io.now_us);
        }
        self.sent += 1;
        let bytes = self.frame.bytes().to_vec();
        let mut got = None;
        for (i, &b) in bytes.iter().enumerate() {
            if let Some((frame, integrity)) = self.ground.push(b) {
                assert_eq!(i + 1, bytes.len(), "a sent frame parsed short");
                assert_eq!(
                    integrity,
                    Integrity::Verified,
                    "a sent frame does not verify"
                );
                got = Some(frame.clone());
            }
        }
        let frame = got.expect("a sent frame does not parse");
        assert_eq!(frame.bytes(), &bytes[..]);
        if self.io.signing.enabled() {
            let verdict = self.ground_signing.check(&frame, self.io.now_us);
            // At the end of its 48 bits the timestamp stays there: then equal timestamps are
            // replays, as they must be (a key set that close to the end leaves no room).
            let ended = self.io.signing.timestamp(self.io.now_us) == (1 << 48) - 1;
            if !(ended && verdict == Verdict::Replayed) {
                assert_eq!(verdict, Verdict::Valid, "a signed frame does not check");
            }
        }
    }
}

fn ns(us: u64) -> i64 {
    us.saturating_mul(1000) as i64
}
