//! MAVLink's mission protocol, the vehicle's side (docs/ground-link.md#missions): upload
//! (`MISSION_COUNT`, `MISSION_REQUEST_INT`, `MISSION_ITEM_INT`, `MISSION_ACK`), download,
//! clear and set-current, over the items of a route ([`shared::flight::route`]).
//!
//! - An upload is atomic: items are collected apart and take the place of the mission in
//!   force only when the last one has come and the whole route checks; anything refused, a
//!   cancelled or timed-out upload, keeps the old mission.
//! - Each item is checked as it comes ([`item::to_route_item`]); the first bad one ends the
//!   upload with a `MISSION_ACK` naming the problem's class, and [`Outcome::refusal`] says
//!   what is wrong in words (for a `STATUSTEXT`).
//! - The vehicle drives an upload: an item that does not come within [`ITEM_TIMEOUT_US`] is
//!   asked for again, [`MAX_RETRIES`] times, then the upload is cancelled
//!   (`MAV_MISSION_OPERATION_CANCELLED`). An item out of order is answered by asking again
//!   for the one expected.
//! - Only the mission list (`MAV_MISSION_TYPE_MISSION`) is kept: a download of the fence or
//!   rally points is empty, an upload of them refused as unsupported.
//!
//! Sans-IO: the caller passes each message with the time and the context (the map origin,
//! whether changes are allowed now) and sends the [`Outcome`]'s reply.

pub mod item;
pub mod stored;
pub mod wire;

use heapless::{String, Vec};
use shared::flight::route::{MAX_ROUTE_ITEMS, Route, RouteItem};

use crate::geo::GeoOrigin;
use crate::msg::MavMissionResult;
use item::{ItemProblem, command_name, to_route_item};
use wire::{MISSION_TYPE_MISSION, MissionMessage, MissionReply, WireItem};

/// Most items the vehicle keeps (a route's).
pub const MAX_ITEMS: usize = MAX_ROUTE_ITEMS;
/// Time for the ground's next item before the vehicle asks again, us (MAVLink's default).
pub const ITEM_TIMEOUT_US: u64 = 1_500_000;
/// Times an item is asked for again before the upload is cancelled.
pub const MAX_RETRIES: u8 = 5;
/// `MAV_MISSION_TYPE_ALL`.
const MISSION_TYPE_ALL: u8 = 255;

/// Longest refusal text.
pub const REFUSAL_LEN: usize = 160;
/// A refusal, in words.
pub type Refusal = String<REFUSAL_LEN>;

/// Who the protocol talks with: system and component.
pub type Peer = (u8, u8);

/// An upload under way.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Upload {
    from: Peer,
    count: u16,
    next: u16,
    deadline_us: u64,
    retries: u8,
}

/// What the vehicle may do now.
#[derive(Clone, Copy, Debug)]
pub struct Context<'a> {
    /// The map origin that places global positions.
    pub origin: &'a GeoOrigin,
    /// Why the mission may not be changed now (unsigned while signing is on, or the mission
    /// is running), or `None`.
    pub locked: Option<&'static str>,
}

/// What changed in the vehicle's mission.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MissionEvent {
    /// A new mission is in force ([`MissionService::route`] gives it to fly, and it is to be
    /// stored).
    Replaced,
    /// The mission was cleared.
    Cleared,
    /// Fly from this item.
    SetCurrent(u16),
}

/// What the vehicle does about one message (or a timeout).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Outcome {
    /// The reply to send, and to whom.
    pub reply: Option<(MissionReply, Peer)>,
    /// The mission changed.
    pub event: Option<MissionEvent>,
    /// A refusal or a cancelled upload, in words, for a `STATUSTEXT`.
    pub refusal: Option<Refusal>,
}

impl Outcome {
    fn reply(reply: MissionReply, to: Peer) -> Self {
        Self {
            reply: Some((reply, to)),
            ..Self::default()
        }
    }

    fn ack(result: MavMissionResult, mission_type: u8, to: Peer) -> Self {
        Self::reply(
            MissionReply::Ack {
                result,
                mission_type,
            },
            to,
        )
    }

    fn refused(
        result: MavMissionResult,
        mission_type: u8,
        to: Peer,
        why: core::fmt::Arguments<'_>,
    ) -> Self {
        let mut text = Refusal::new();
        let _ = core::fmt::write(&mut text, why);
        Self {
            refusal: Some(text),
            ..Self::ack(result, mission_type, to)
        }
    }
}

/// The vehicle's mission: the items in force and an upload under way.
#[derive(Clone, Debug, Default)]
pub struct MissionService {
    items: Vec<WireItem, MAX_ITEMS>,
    staging: Vec<WireItem, MAX_ITEMS>,
    upload: Option<Upload>,
}

impl MissionService {
    /// No mission.
    pub const fn new() -> Self {
        Self {
            items: Vec::new(),
            staging: Vec::new(),
            upload: None,
        }
    }

    /// The items in force.
    pub fn items(&self) -> &[WireItem] {
        &self.items
    }

    /// Puts `items` in force (a stored mission at start), if they make a route with
    /// `origin`; else says which item is wrong and keeps none.
    pub fn restore(
        &mut self,
        items: &[WireItem],
        origin: &GeoOrigin,
    ) -> Result<(), (usize, ItemProblem)> {
        self.items = Vec::from_slice(items).map_err(|_| {
            (
                MAX_ITEMS,
                ItemProblem::Route(shared::flight::RouteProblem::TooMany),
            )
        })?;
        if let Err(e) = self.route(origin) {
            self.items.clear();
            return Err(e);
        }
        Ok(())
    }

    /// The items in force as a route to fly with `origin` (checked again: the origin may
    /// have moved since the upload).
    pub fn route(&self, origin: &GeoOrigin) -> Result<Route, (usize, ItemProblem)> {
        route_of(&self.items, origin)
    }

    /// Whether an upload is under way.
    pub fn uploading(&self) -> bool {
        self.upload.is_some()
    }

    /// One message from `from` at `now_us`.
    pub fn handle(
        &mut self,
        message: &MissionMessage,
        from: Peer,
        now_us: u64,
        context: &Context<'_>,
    ) -> Outcome {
        match *message {
            MissionMessage::Count {
                count,
                mission_type,
            } => self.begin_upload(count, mission_type, from, now_us, context),
            MissionMessage::Item {
                seq,
                item,
                mission_type,
            } => self.take_item(seq, &item, mission_type, from, now_us, context),
            MissionMessage::RequestList { mission_type } => {
                let count = if mission_type == MISSION_TYPE_MISSION {
                    self.items.len() as u16
                } else {
                    0
                };
                Outcome::reply(
                    MissionReply::Count {
                        count,
                        mission_type,
                    },
                    from,
                )
            }
            MissionMessage::RequestItem { seq, mission_type } => {
                match self.items.get(usize::from(seq)) {
                    Some(item) if mission_type == MISSION_TYPE_MISSION => Outcome::reply(
                        MissionReply::Item {
                            seq,
                            item: *item,
                            current: seq == 0,
                        },
                        from,
                    ),
                    _ => Outcome::refused(
                        MavMissionResult::MAV_MISSION_INVALID_SEQUENCE,
                        mission_type,
                        from,
                        format_args!(
                            "mission: no item {seq} to send (the vehicle has {})",
                            self.items.len()
                        ),
                    ),
                }
            }
            MissionMessage::ClearAll { mission_type } => self.clear(mission_type, from, context),
            MissionMessage::SetCurrent { seq } => {
                if let Some(why) = context.locked.filter(|_| !context_allows_jump(context)) {
                    return refusal(format_args!("mission: current item not set: {why}"));
                }
                if usize::from(seq) < self.items.len() {
                    Outcome {
                        event: Some(MissionEvent::SetCurrent(seq)),
                        ..Outcome::default()
                    }
                } else {
                    refusal(format_args!(
                        "mission: no item {seq} to fly from (the vehicle has {})",
                        self.items.len()
                    ))
                }
            }
            // The end of a download, or the ground giving one up: nothing to do.
            MissionMessage::Ack { .. } => Outcome::default(),
        }
    }

    /// An upload's timeout: asks again for the item awaited, or cancels the upload.
    pub fn poll(&mut self, now_us: u64) -> Option<Outcome> {
        let upload = self.upload.as_mut()?;
        if now_us < upload.deadline_us {
            return None;
        }
        if upload.retries >= MAX_RETRIES {
            let (from, next, count) = (upload.from, upload.next, upload.count);
            self.upload = None;
            return Some(Outcome::refused(
                MavMissionResult::MAV_MISSION_OPERATION_CANCELLED,
                MISSION_TYPE_MISSION,
                from,
                format_args!(
                    "mission upload cancelled: item {next} of {count} never came; the old mission is kept"
                ),
            ));
        }
        upload.retries += 1;
        upload.deadline_us = now_us + ITEM_TIMEOUT_US;
        Some(Outcome::reply(
            MissionReply::Request {
                seq: upload.next,
                mission_type: MISSION_TYPE_MISSION,
            },
            upload.from,
        ))
    }

    /// When [`Self::poll`] next has something to do, us.
    pub fn next_deadline(&self) -> Option<u64> {
        self.upload.map(|u| u.deadline_us)
    }

    fn begin_upload(
        &mut self,
        count: u16,
        mission_type: u8,
        from: Peer,
        now_us: u64,
        context: &Context<'_>,
    ) -> Outcome {
        use MavMissionResult as R;
        if mission_type != MISSION_TYPE_MISSION {
            return Outcome::refused(
                R::MAV_MISSION_UNSUPPORTED,
                mission_type,
                from,
                format_args!("mission: the vehicle keeps no geofence or rally points"),
            );
        }
        if let Some(why) = context.locked {
            return Outcome::refused(
                R::MAV_MISSION_DENIED,
                mission_type,
                from,
                format_args!("mission upload refused: {why}"),
            );
        }
        if let Some(u) = self.upload
            && u.from != from
        {
            return Outcome::refused(
                R::MAV_MISSION_DENIED,
                mission_type,
                from,
                format_args!("mission upload refused: another ground station is uploading"),
            );
        }
        if usize::from(count) > MAX_ITEMS {
            self.upload = None;
            return Outcome::refused(
                R::MAV_MISSION_NO_SPACE,
                mission_type,
                from,
                format_args!(
                    "mission refused: {count} items; the vehicle keeps at most {MAX_ITEMS}"
                ),
            );
        }
        if count == 0 {
            self.upload = None;
            self.items.clear();
            return Outcome {
                event: Some(MissionEvent::Cleared),
                ..Outcome::ack(R::MAV_MISSION_ACCEPTED, mission_type, from)
            };
        }
        self.staging.clear();
        self.upload = Some(Upload {
            from,
            count,
            next: 0,
            deadline_us: now_us + ITEM_TIMEOUT_US,
            retries: 0,
        });
        Outcome::reply(
            MissionReply::Request {
                seq: 0,
                mission_type,
            },
            from,
        )
    }

    fn take_item(
        &mut self,
        seq: u16,
        item: &WireItem,
        mission_type: u8,
        from: Peer,
        now_us: u64,
        context: &Context<'_>,
    ) -> Outcome {
        use MavMissionResult as R;
        let Some(upload) = self.upload.as_mut().filter(|u| u.from == from) else {
            // An item outside an upload (a late duplicate): nothing to take.
            return Outcome::default();
        };
        if mission_type != MISSION_TYPE_MISSION {
            return Outcome::default();
        }
        if seq != upload.next {
            // Out of order, or a duplicate of the last: ask again for the one expected.
            upload.deadline_us = now_us + ITEM_TIMEOUT_US;
            return Outcome::reply(
                MissionReply::Request {
                    seq: upload.next,
                    mission_type,
                },
                from,
            );
        }
        let count = upload.count;
        if let Err(problem) = to_route_item(item, context.origin) {
            self.upload = None;
            return Outcome::refused(
                problem.result(),
                mission_type,
                from,
                format_args!(
                    "mission refused: item {seq} ({}): {problem}; the old mission is kept",
                    command_name(item.command)
                ),
            );
        }
        // The staging list holds `count` <= MAX_ITEMS items: room is certain.
        let _ = self.staging.push(*item);
        upload.next += 1;
        upload.retries = 0;
        upload.deadline_us = now_us + ITEM_TIMEOUT_US;
        if upload.next < count {
            return Outcome::reply(
                MissionReply::Request {
                    seq: upload.next,
                    mission_type,
                },
                from,
            );
        }
        self.upload = None;
        if let Err((i, problem)) = route_of(&self.staging, context.origin) {
            return Outcome::refused(
                problem.result(),
                mission_type,
                from,
                format_args!(
                    "mission refused: item {i} ({}): {problem}; the old mission is kept",
                    command_name(self.staging.get(i).map_or(0, |it| it.command))
                ),
            );
        }
        core::mem::swap(&mut self.items, &mut self.staging);
        Outcome {
            event: Some(MissionEvent::Replaced),
            ..Outcome::ack(R::MAV_MISSION_ACCEPTED, mission_type, from)
        }
    }

    fn clear(&mut self, mission_type: u8, from: Peer, context: &Context<'_>) -> Outcome {
        if mission_type != MISSION_TYPE_MISSION && mission_type != MISSION_TYPE_ALL {
            // Nothing of the kind is kept: cleared already.
            return Outcome::ack(MavMissionResult::MAV_MISSION_ACCEPTED, mission_type, from);
        }
        if let Some(why) = context.locked {
            return Outcome::refused(
                MavMissionResult::MAV_MISSION_DENIED,
                mission_type,
                from,
                format_args!("mission not cleared: {why}"),
            );
        }
        self.upload = None;
        self.items.clear();
        Outcome {
            event: Some(MissionEvent::Cleared),
            ..Outcome::ack(MavMissionResult::MAV_MISSION_ACCEPTED, mission_type, from)
        }
    }
}

/// Set-current is a jump along the mission in force, allowed while it runs; only a
/// signature's absence locks it.
fn context_allows_jump(context: &Context<'_>) -> bool {
    context.locked == Some(crate::mission::RUNNING)
}

/// The reason [`Context::locked`] gives while the mission runs.
pub const RUNNING: &str = "the mission is running";

fn refusal(why: core::fmt::Arguments<'_>) -> Outcome {
    let mut text = Refusal::new();
    let _ = core::fmt::write(&mut text, why);
    Outcome {
        refusal: Some(text),
        ..Outcome::default()
    }
}

/// `items` as a checked route with `origin`, or the first item that is wrong.
fn route_of(items: &[WireItem], origin: &GeoOrigin) -> Result<Route, (usize, ItemProblem)> {
    let mut route: Vec<RouteItem, MAX_ITEMS> = Vec::new();
    for (i, item) in items.iter().enumerate() {
        let r = to_route_item(item, origin).map_err(|p| (i, p))?;
        let _ = route.push(r);
    }
    Route::new(&route).map_err(|e| (e.item, ItemProblem::Route(e.problem)))
}

#[cfg(test)]
mod tests;
