//! The mission service's upload, download, clear and timeouts.

use super::item::{NAV_LAND, NAV_TAKEOFF, NAV_WAYPOINT};
use super::*;

const GROUND: Peer = (255, 190);
const OTHER: Peer = (254, 1);
const ORIGIN: GeoOrigin = GeoOrigin {
    lat_e7: 356_812_000,
    lon_e7: 1_397_671_000,
    alt_m: 40.0,
};
const FREE: Context<'static> = Context {
    origin: &ORIGIN,
    locked: None,
};

fn item(command: u16, north: f32, east: f32, height: f32) -> WireItem {
    let p = ORIGIN.to_global([north, east, 0.0]).expect("a point");
    WireItem {
        command,
        frame: 6,
        autocontinue: 1,
        x: p.lat_e7,
        y: p.lon_e7,
        z: height,
        ..Default::default()
    }
}

fn plan() -> [WireItem; 3] {
    [
        item(NAV_TAKEOFF, 0.0, 0.0, 0.5),
        item(NAV_WAYPOINT, 0.3, 1.98, 0.5),
        item(NAV_LAND, 0.3, 1.98, 0.0),
    ]
}

fn count(n: u16) -> MissionMessage {
    MissionMessage::Count {
        count: n,
        mission_type: 0,
    }
}

fn send(seq: u16, it: &WireItem) -> MissionMessage {
    MissionMessage::Item {
        seq,
        item: *it,
        mission_type: 0,
    }
}

fn request(seq: u16) -> Option<(MissionReply, Peer)> {
    Some((
        MissionReply::Request {
            seq,
            mission_type: 0,
        },
        GROUND,
    ))
}

fn ack(result: MavMissionResult) -> Option<(MissionReply, Peer)> {
    Some((
        MissionReply::Ack {
            result,
            mission_type: 0,
        },
        GROUND,
    ))
}

/// Uploads `items` in order; the last outcome.
fn upload(s: &mut MissionService, items: &[WireItem]) -> Outcome {
    let mut out = s.handle(&count(items.len() as u16), GROUND, 0, &FREE);
    for (i, it) in items.iter().enumerate() {
        assert_eq!(out.reply, request(i as u16), "asked for item {i}");
        out = s.handle(&send(i as u16, it), GROUND, 0, &FREE);
    }
    out
}

#[test]
fn an_upload_asks_for_each_item_and_puts_the_mission_in_force() {
    let mut s = MissionService::new();
    let out = upload(&mut s, &plan());
    assert_eq!(out.reply, ack(MavMissionResult::MAV_MISSION_ACCEPTED));
    assert_eq!(out.event, Some(MissionEvent::Replaced));
    assert_eq!(s.items(), &plan());
    let route = s.route(&ORIGIN).expect("a route");
    assert_eq!(route.len(), 3);
    // And it downloads back the same.
    let listed = s.handle(
        &MissionMessage::RequestList { mission_type: 0 },
        GROUND,
        0,
        &FREE,
    );
    assert_eq!(
        listed.reply,
        Some((
            MissionReply::Count {
                count: 3,
                mission_type: 0
            },
            GROUND
        ))
    );
    for (i, it) in plan().iter().enumerate() {
        let got = s.handle(
            &MissionMessage::RequestItem {
                seq: i as u16,
                mission_type: 0,
            },
            GROUND,
            0,
            &FREE,
        );
        let Some((MissionReply::Item { item, .. }, _)) = got.reply else {
            panic!("item {i} not sent");
        };
        assert_eq!(item.to_bytes(), it.to_bytes());
    }
    let past = s.handle(
        &MissionMessage::RequestItem {
            seq: 3,
            mission_type: 0,
        },
        GROUND,
        0,
        &FREE,
    );
    assert_eq!(
        past.reply,
        ack(MavMissionResult::MAV_MISSION_INVALID_SEQUENCE)
    );
}

#[test]
fn an_item_out_of_order_is_asked_for_again_and_the_upload_goes_on() {
    let mut s = MissionService::new();
    let items = plan();
    s.handle(&count(3), GROUND, 0, &FREE);
    assert_eq!(
        s.handle(&send(0, &items[0]), GROUND, 0, &FREE).reply,
        request(1)
    );
    // Item 2 before item 1, and item 0 again: item 1 is asked for each time.
    assert_eq!(
        s.handle(&send(2, &items[2]), GROUND, 0, &FREE).reply,
        request(1)
    );
    assert_eq!(
        s.handle(&send(0, &items[0]), GROUND, 0, &FREE).reply,
        request(1)
    );
    assert_eq!(
        s.handle(&send(1, &items[1]), GROUND, 0, &FREE).reply,
        request(2)
    );
    let out = s.handle(&send(2, &items[2]), GROUND, 0, &FREE);
    assert_eq!(out.event, Some(MissionEvent::Replaced));
    assert_eq!(s.items(), &items);
}

#[test]
fn a_silent_ground_is_asked_again_then_the_upload_is_cancelled_and_the_old_kept() {
    let mut s = MissionService::new();
    upload(&mut s, &plan());
    let mut out = s.handle(&count(2), GROUND, 0, &FREE);
    assert_eq!(out.reply, request(0));
    out = s.handle(&send(0, &plan()[0]), GROUND, 0, &FREE);
    assert_eq!(out.reply, request(1));
    assert_eq!(s.poll(ITEM_TIMEOUT_US - 1), None, "not before the timeout");
    let mut now = 0;
    for retry in 0..MAX_RETRIES {
        now += ITEM_TIMEOUT_US;
        let again = s.poll(now).expect("asked again");
        assert_eq!(again.reply, request(1), "retry {retry}");
    }
    now += ITEM_TIMEOUT_US;
    let cancelled = s.poll(now).expect("cancelled");
    assert_eq!(
        cancelled.reply,
        ack(MavMissionResult::MAV_MISSION_OPERATION_CANCELLED)
    );
    assert!(cancelled.refusal.expect("a reason").contains("item 1 of 2"));
    assert!(!s.uploading());
    assert_eq!(s.items(), &plan(), "the old mission is kept");
}

#[test]
fn bad_items_end_the_upload_with_the_reason_and_keep_the_old_mission() {
    let nan = WireItem {
        z: f32::NAN,
        ..item(NAV_WAYPOINT, 0.0, 0.0, 0.5)
    };
    let unsupported_frame = WireItem {
        frame: 1,
        ..item(NAV_WAYPOINT, 0.0, 0.0, 0.5)
    };
    let far = item(NAV_WAYPOINT, 5000.0, 0.0, 0.5);
    let after_land = [
        item(NAV_TAKEOFF, 0.0, 0.0, 0.5),
        item(NAV_LAND, 0.0, 0.0, 0.0),
        item(NAV_WAYPOINT, 0.0, 0.0, 0.5),
    ];
    let cases: [(&[WireItem], MavMissionResult, &str); 4] = [
        (
            &[nan],
            MavMissionResult::MAV_MISSION_INVALID,
            "not a number",
        ),
        (
            &[unsupported_frame],
            MavMissionResult::MAV_MISSION_UNSUPPORTED_FRAME,
            "frame 1",
        ),
        (
            &[far],
            MavMissionResult::MAV_MISSION_INVALID_PARAM5_X,
            "from the origin",
        ),
        (
            &after_land,
            MavMissionResult::MAV_MISSION_INVALID,
            "follow NAV_LAND",
        ),
    ];
    for (items, result, says) in cases {
        let mut s = MissionService::new();
        upload(&mut s, &plan());
        let out = upload(&mut s, items);
        assert_eq!(out.reply, ack(result), "{items:?}");
        let text = out.refusal.expect("a reason");
        assert!(
            text.contains(says) && text.contains("old mission is kept"),
            "{text}"
        );
        assert_eq!(out.event, None);
        assert_eq!(s.items(), &plan(), "the old mission is kept");
    }
}

#[test]
fn a_mission_over_capacity_is_refused_at_its_count() {
    let mut s = MissionService::new();
    let out = s.handle(&count(1000), GROUND, 0, &FREE);
    assert_eq!(out.reply, ack(MavMissionResult::MAV_MISSION_NO_SPACE));
    assert!(out.refusal.expect("a reason").contains("at most 16"));
    assert!(!s.uploading());
}

#[test]
fn a_locked_mission_is_neither_replaced_nor_cleared() {
    let mut s = MissionService::new();
    upload(&mut s, &plan());
    let running = Context {
        origin: &ORIGIN,
        locked: Some(RUNNING),
    };
    let clear = s.handle(
        &MissionMessage::ClearAll { mission_type: 0 },
        GROUND,
        0,
        &running,
    );
    assert_eq!(clear.reply, ack(MavMissionResult::MAV_MISSION_DENIED));
    assert!(clear.refusal.expect("a reason").contains("running"));
    let up = s.handle(&count(1), GROUND, 0, &running);
    assert_eq!(up.reply, ack(MavMissionResult::MAV_MISSION_DENIED));
    assert_eq!(s.items(), &plan());
    // Set-current is a jump along it: allowed while it runs.
    let jump = s.handle(&MissionMessage::SetCurrent { seq: 1 }, GROUND, 0, &running);
    assert_eq!(jump.event, Some(MissionEvent::SetCurrent(1)));
    let beyond = s.handle(&MissionMessage::SetCurrent { seq: 9 }, GROUND, 0, &running);
    assert_eq!(beyond.event, None);
    assert!(beyond.refusal.is_some());
    // Unlocked, a clear empties it.
    let clear = s.handle(
        &MissionMessage::ClearAll { mission_type: 0 },
        GROUND,
        0,
        &FREE,
    );
    assert_eq!(clear.event, Some(MissionEvent::Cleared));
    assert!(s.items().is_empty());
}

#[test]
fn another_ground_station_cannot_cut_into_an_upload() {
    let mut s = MissionService::new();
    s.handle(&count(3), GROUND, 0, &FREE);
    let other = s.handle(&count(1), OTHER, 0, &FREE);
    assert!(matches!(
        other.reply,
        Some((
            MissionReply::Ack {
                result: MavMissionResult::MAV_MISSION_DENIED,
                ..
            },
            OTHER
        ))
    ));
    // Its items are not taken.
    assert_eq!(
        s.handle(&send(0, &plan()[0]), OTHER, 0, &FREE),
        Outcome::default()
    );
    assert_eq!(
        s.handle(&send(0, &plan()[0]), GROUND, 0, &FREE).reply,
        request(1)
    );
}

#[test]
fn fence_and_rally_lists_are_empty_and_not_uploaded() {
    let mut s = MissionService::new();
    let listed = s.handle(
        &MissionMessage::RequestList { mission_type: 1 },
        GROUND,
        0,
        &FREE,
    );
    assert_eq!(
        listed.reply,
        Some((
            MissionReply::Count {
                count: 0,
                mission_type: 1
            },
            GROUND
        ))
    );
    let up = s.handle(
        &MissionMessage::Count {
            count: 2,
            mission_type: 2,
        },
        GROUND,
        0,
        &FREE,
    );
    assert!(matches!(
        up.reply,
        Some((
            MissionReply::Ack {
                result: MavMissionResult::MAV_MISSION_UNSUPPORTED,
                mission_type: 2
            },
            _
        ))
    ));
}
