//! The receive service's behaviour, concern by concern, through [`QueuePorts`]: the start
//! with a blank or filled store, parameters, commands (every request branch), signing,
//! the map origin, missions, the payload upload and log requests.

// SET_GPS_GLOBAL_ORIGIN is deprecated in MAVLink, yet QGroundControl and MAVProxy still send
// it, and the vehicle answers it.
#![allow(deprecated)]

extern crate std;

use std::vec::Vec;

use crate::store::ParamStore;
use embassy_futures::block_on;
use link::MessageData;
use link::command::CommandWire;
use link::frame::{Encoder, Frame};
use link::mission::stored::{self, MAX_STORED_LEN};
use link::mission::wire::WireItem;
use link::msg::{
    COMMAND_LONG_DATA, COMPONENT_METADATA_DATA, CURRENT_MODE_DATA, LOG_REQUEST_LIST_DATA, MavCmd,
    MavParamType, MavResult, PARAM_SET_DATA, SET_GPS_GLOBAL_ORIGIN_DATA, SETUP_SIGNING_DATA,
};
use link::status::MissionState;
use shared::mission::params::{ParamValues, TABLE};
use test_support::flash::{CutFlash, PAGE};

use super::*;
use crate::autonomy::OperatorCommand;

const PARAM_RANGE: core::ops::Range<u32> = 0..(8 * PAGE) as u32;
const PAYLOAD_RANGE: core::ops::Range<u32> = (8 * PAGE) as u32..(12 * PAGE) as u32;
const MISSION_RANGE: core::ops::Range<u32> = (12 * PAGE) as u32..(14 * PAGE) as u32;

fn store(flash: CutFlash) -> ParamStore<CutFlash> {
    ParamStore::new(flash, PARAM_RANGE)
        .and_then(|s| s.with_payload(PAYLOAD_RANGE))
        .and_then(|s| s.with_mission(MISSION_RANGE))
        .expect("the store opens")
}

/// A started vehicle on `flash`, its start's replies taken.
struct Bench {
    service: LinkService<CutFlash>,
    io: QueuePorts,
    ground: Encoder,
    start: Vec<Outbound>,
}

impl Bench {
    fn on(flash: CutFlash) -> Self {
        let mut service = LinkService::new(&[]);
        let mut io = QueuePorts::new();
        block_on(service.start(Ok(store(flash)), &mut io));
        let start = io.outbox.iter().cloned().collect();
        io.outbox.clear();
        Self {
            service,
            io,
            ground: Encoder::new(255, 190),
            start,
        }
    }

    fn new() -> Self {
        Self::on(CutFlash::new(14))
    }

    fn send<M: MessageData>(&mut self, message: &M) {
        let mut frame = Frame::default();
        self.ground.encode(message, &mut frame);
        let bytes = frame.bytes().to_vec();
        block_on(self.service.receive(&bytes, &mut self.io));
    }

    /// The replies queued since the last call.
    fn replies(&mut self) -> Vec<Outbound> {
        let r = self.io.outbox.iter().cloned().collect();
        self.io.outbox.clear();
        r
    }

    /// The restart: the same flash, a new service.
    fn restart(mut self) -> Self {
        let flash = self
            .service
            .take_store()
            .and_then(|s| s.into_flash())
            .expect("the flash back");
        Self::on(flash)
    }
}

fn texts(replies: &[Outbound]) -> Vec<std::string::String> {
    let mut all = Vec::new();
    for r in replies {
        if let Outbound::Report(report) = r {
            all.extend(report.texts.iter().map(|t| t.text.as_str().into()));
        }
    }
    all
}

fn acks(replies: &[Outbound]) -> Vec<MavResult> {
    replies
        .iter()
        .filter_map(|r| match r {
            Outbound::Ack { result, .. } => Some(*result),
            _ => None,
        })
        .collect()
}

fn param_set(name: &str, value: f32) -> PARAM_SET_DATA {
    let mut id = [0u8; 16];
    id[..name.len()].copy_from_slice(name.as_bytes());
    PARAM_SET_DATA {
        param_value: value,
        target_system: 1,
        target_component: 1,
        param_id: id.into(),
        param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
    }
}

fn request_message(id: u32) -> COMMAND_LONG_DATA {
    COMMAND_LONG_DATA {
        command: MavCmd::MAV_CMD_REQUEST_MESSAGE,
        param1: id as f32,
        target_system: 1,
        target_component: 1,
        ..Default::default()
    }
}

/// A parameter of the table that is not part of the map origin, and a value it takes.
fn plain_param() -> (&'static str, f32) {
    let p = TABLE
        .iter()
        .find(|p| !p.name.starts_with("ORIGIN") && p.max > p.min)
        .expect("a plain parameter");
    (p.name, 0.5 * (p.min + p.max))
}

#[test]
fn a_blank_store_starts_with_the_defaults_and_says_so() {
    let b = Bench::new();
    let said = texts(&b.start);
    assert!(
        said.iter().any(|t| t.contains("restored from storage")),
        "{said:?}"
    );
    assert!(b.start.contains(&Outbound::Origin));
    assert_eq!(b.io.values, ParamValues::DEFAULT);
    assert!(
        b.io.config_changed,
        "the configuration is handed to the mission"
    );
}

#[test]
fn a_parameter_write_is_stored_answered_and_applied() {
    let (name, value) = plain_param();
    let mut b = Bench::new();
    b.send(&param_set(name, value));
    let replies = b.replies();
    assert!(
        replies
            .iter()
            .any(|r| matches!(r, Outbound::Params(bits) if !bits.is_empty())),
        "no PARAM_VALUE: {replies:?}"
    );
    assert!(
        b.io.reload,
        "the payload is loaded again with the new value"
    );
    let index = TABLE
        .iter()
        .position(|p| p.name == name)
        .expect("in the table");
    assert_eq!(
        b.io.values.get(index),
        Some(value),
        "the send task has the value"
    );
    let b = b.restart();
    assert_eq!(
        b.service.params().values().get(index),
        Some(value),
        "lost in a restart"
    );
}

#[test]
fn no_parameter_changes_while_the_mission_runs() {
    let (name, value) = plain_param();
    let mut b = Bench::new();
    b.io.mission_state = MissionState::Running;
    b.send(&param_set(name, value));
    assert_eq!(b.service.params().values(), &ParamValues::DEFAULT);
    let said = texts(&b.replies());
    assert!(said.iter().any(|t| t.contains("running")), "{said:?}");
}

#[test]
fn every_message_request_branch_is_answered() {
    let mut b = Bench::new();
    b.send(&request_message(CURRENT_MODE_DATA::ID));
    assert_eq!(
        b.replies(),
        [
            Outbound::Ack {
                command: link::command_wire::CommandId(MavCmd::MAV_CMD_REQUEST_MESSAGE as u16),
                result: MavResult::MAV_RESULT_ACCEPTED
            },
            Outbound::CurrentMode
        ]
    );
    b.send(&request_message(COMPONENT_METADATA_DATA::ID));
    assert!(b.replies().contains(&Outbound::ComponentMetadata));
    b.send(&request_message(link::msg::AUTOPILOT_VERSION_DATA::ID));
    assert!(b.replies().contains(&Outbound::Identity));
    b.send(&request_message(link::msg::HOME_POSITION_DATA::ID));
    assert!(b.replies().contains(&Outbound::Home));
    // A message nothing sends: refused, with the reason.
    b.send(&request_message(link::msg::COMMAND_ACK_DATA::ID));
    let replies = b.replies();
    assert_eq!(acks(&replies), [MavResult::MAV_RESULT_UNSUPPORTED]);
    assert!(texts(&replies)[0].contains("not sent on request"));
}

#[test]
fn operator_commands_queue_for_the_control_task_until_it_is_full() {
    let mut b = Bench::new();
    for _ in 0..queue_ports::COMMANDS_CAPACITY {
        b.send(&OperatorCommand::Abort.to_command_long());
    }
    assert_eq!(b.io.commands.len(), queue_ports::COMMANDS_CAPACITY);
    assert!(
        b.io.commands
            .iter()
            .all(|c| c.command == OperatorCommand::Abort)
    );
    assert!(b.replies().is_empty(), "the control task acknowledges them");
    b.send(&OperatorCommand::Abort.to_command_long());
    assert_eq!(
        acks(&b.replies()),
        [MavResult::MAV_RESULT_TEMPORARILY_REJECTED]
    );
}

#[test]
fn a_reboot_is_refused_while_armed_and_done_otherwise() {
    let reboot = COMMAND_LONG_DATA {
        command: MavCmd::MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN,
        param1: 1.0,
        target_system: 1,
        target_component: 1,
        ..Default::default()
    };
    let mut b = Bench::new();
    b.io.armed = true;
    b.send(&reboot);
    assert_eq!(acks(&b.replies()), [MavResult::MAV_RESULT_DENIED]);
    assert_eq!(b.io.reboots, 0);
    b.io.armed = false;
    b.send(&reboot);
    assert_eq!(acks(&b.replies()), [MavResult::MAV_RESULT_ACCEPTED]);
    assert_eq!(b.io.reboots, 1);
}

#[test]
fn a_signing_key_is_stored_restored_and_then_required() {
    let mut b = Bench::new();
    b.send(&SETUP_SIGNING_DATA {
        target_system: 1,
        target_component: 1,
        secret_key: [9; 32],
        initial_timestamp: 1_000,
    });
    assert!(texts(&b.replies())[0].starts_with("signing: on"));
    assert!(b.io.signing.enabled());
    let mut b = b.restart();
    assert!(
        texts(&b.start)
            .iter()
            .any(|t| t == "signing: on (key restored)")
    );
    assert!(
        b.io.signing.enabled(),
        "the key is in force after a restart"
    );
    // An unsigned write is refused.
    let (name, value) = plain_param();
    b.send(&param_set(name, value));
    assert_eq!(b.service.params().values(), &ParamValues::DEFAULT);
}

#[test]
fn a_signing_key_is_refused_where_the_board_takes_none() {
    let mut b = Bench::new();
    b.io.key_setup_allowed = false;
    b.send(&SETUP_SIGNING_DATA {
        target_system: 1,
        target_component: 1,
        secret_key: [9; 32],
        initial_timestamp: 1_000,
    });
    assert!(texts(&b.replies())[0].contains("over USB only"));
    assert!(!b.io.signing.enabled());
}

#[test]
fn an_origin_is_set_stored_and_refused_out_of_range() {
    let mut b = Bench::new();
    b.send(&SET_GPS_GLOBAL_ORIGIN_DATA {
        latitude: 356_812_000,
        longitude: 1_397_671_000,
        altitude: 40_000,
        target_system: 1,
    });
    let replies = b.replies();
    assert!(replies.contains(&Outbound::Origin), "{replies:?}");
    assert_eq!(b.service.params().origin().lat_e7, 356_812_000);
    let b2 = b.restart();
    assert_eq!(b2.service.params().origin().lat_e7, 356_812_000);
    let mut b = b2;
    b.send(&SET_GPS_GLOBAL_ORIGIN_DATA {
        latitude: 950_000_000,
        longitude: 0,
        altitude: 0,
        target_system: 1,
    });
    let said = texts(&b.replies());
    assert!(said[0].starts_with("origin not changed"), "{said:?}");
    assert_eq!(b.service.params().origin().lat_e7, 356_812_000);
}

#[test]
fn a_stored_mission_is_restored_and_handed_over_as_a_route() {
    let origin = link::geo::GeoOrigin::from_params(&ParamValues::DEFAULT);
    let item = |command: u16, north: f32, z: f32| {
        let p = origin.to_global([north, 0.0, 0.0]).expect("a point");
        WireItem {
            command,
            frame: 6,
            autocontinue: 1,
            x: p.lat_e7,
            y: p.lon_e7,
            z,
            ..Default::default()
        }
    };
    let items = [item(22, 0.0, 0.5), item(16, 0.3, 0.5), item(21, 0.3, 0.0)];
    let mut s = store(CutFlash::new(14));
    let mut bytes = [0u8; MAX_STORED_LEN];
    let len = stored::encode(&items, &mut bytes);
    block_on(s.save_mission(&bytes[..len])).expect("stored");
    let b = Bench::on(s.into_flash().expect("the flash"));
    let said = texts(&b.start);
    assert!(
        said.iter()
            .any(|t| t == "mission of 3 items restored from storage"),
        "{said:?}"
    );
    assert_eq!(b.io.mission_items, 3);
    assert!(matches!(
        b.io.routes.front(),
        Some(crate::autonomy::RouteChange::Set(_))
    ));
    assert_eq!(b.service.mission().items().len(), 3);
}

#[test]
fn an_unsigned_upload_is_refused_and_said_once_per_sender() {
    let mut b = Bench::new();
    b.io.signing.set_key([3; 32], 1, 0, LINK_ID);
    let write = link::ftp::FtpMessage::command(1, link::ftp::Opcode::CreateFile);
    let message = write.to_message(1, 1);
    b.send(&message);
    b.send(&message);
    assert_eq!(b.io.bulk.len(), 2, "every request answered");
    let said = texts(&b.replies());
    assert_eq!(said.len(), 1, "{said:?}");
    assert!(said[0].starts_with("payload upload refused"));
}

#[test]
fn a_board_without_logs_lists_none() {
    let mut b = Bench::new();
    b.send(&LOG_REQUEST_LIST_DATA {
        start: 0,
        end: 0xFFFF,
        target_system: 1,
        target_component: 1,
    });
    assert!(matches!(
        b.io.bulk.front(),
        Some(Bulk::Log(link::log_transfer::LogReply::Entry(e))) if e.num_logs == 0
    ));
}

#[test]
fn a_joystick_in_range_goes_to_the_control_task_and_one_out_of_range_does_not() {
    let stick = |z: i16| link::msg::MANUAL_CONTROL_DATA {
        target: link::VEHICLE_SYSTEM_ID,
        x: 1000,
        y: 0,
        z,
        r: 0,
        buttons: 0,
    };
    let mut b = Bench::new();
    b.send(&stick(-5));
    assert_eq!(b.io.manual, None, "a thrust below 0 is no input");
    b.send(&stick(500));
    let input = b.io.manual.expect("taken");
    assert_eq!((input.sticks.pitch, input.sticks.throttle), (1.0, 0.5));
    // Once signing is on, an unsigned joystick is not taken.
    b.io.manual = None;
    b.io.signing.set_key([3; 32], 1, 0, LINK_ID);
    b.send(&stick(500));
    assert_eq!(b.io.manual, None);
}
