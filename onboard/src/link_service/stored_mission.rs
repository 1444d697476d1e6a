//! Missions over the link (docs/ground-link.md#missions): uploads, downloads and set-current
//! answered by `link`'s mission service; a mission replaced or cleared is handed to the
//! autonomy as a route and stored, and the stored one is put in force at the start. Downloads
//! need no signature; changes do, and none while the mission runs but a set-current.

use crate::store::StoreError;
use embedded_storage_async::nor_flash::NorFlash;
use link::mission::stored::{self, MAX_STORED_LEN};
use link::mission::wire::MissionMessage;
use link::mission::{Context as MissionContext, MissionEvent, Outcome};
use link::signing::Verdict;
use link::status::MissionState;
use link::vehicle::Sender;

use super::{Bulk, LinkService, Outbound, VehiclePorts, report};
use crate::autonomy::{Report, RouteChange, Severity};

impl<F: NorFlash> LinkService<F> {
    /// Puts the stored mission in force, if one is stored and still makes a route with the
    /// map origin; says what it found.
    pub(super) async fn restore_mission(&mut self, io: &mut impl VehiclePorts) {
        let Some(store) = &mut self.store else {
            return;
        };
        let mut bytes = [0u8; MAX_STORED_LEN];
        let valid = |b: &[u8]| stored::decode(b).is_some();
        let items = match store.load_mission(&mut bytes, valid).await {
            Ok(Some(len)) => stored::decode(&bytes[..len]).unwrap_or_default(),
            Ok(None) => return,
            Err(e) => {
                io.reply_waiting(report(
                    Severity::Error,
                    format_args!("mission not read from storage: {e}"),
                ))
                .await;
                return;
            }
        };
        if items.is_empty() {
            return;
        }
        let origin = self.params.origin();
        match self.mission.restore(&items, &origin) {
            Ok(()) => {
                self.offer_route(io).await;
                io.reply_waiting(report(
                    Severity::Info,
                    format_args!("mission of {} items restored from storage", items.len()),
                ))
                .await;
            }
            Err((i, problem)) => {
                io.reply_waiting(report(
                    Severity::Warning,
                    format_args!("stored mission not flown: item {i}: {problem}"),
                ))
                .await;
            }
        }
    }

    /// Hands the mission in force to the autonomy as a route to fly (an empty one when it
    /// cannot be flown with the map origin: the payload description's target then).
    async fn offer_route(&mut self, io: &mut impl VehiclePorts) {
        let route = self
            .mission
            .route(&self.params.origin())
            .unwrap_or_default();
        let items = self.mission.items().len() as u16;
        io.route(RouteChange::Set(route), items).await;
    }

    /// A mission-protocol message: answered, and a mission replaced or cleared is handed to
    /// the autonomy and stored.
    pub(super) async fn handle_mission(
        &mut self,
        message: &MissionMessage,
        from: Sender,
        verdict: Verdict,
        io: &mut impl VehiclePorts,
    ) {
        let locked = if !verdict.trusted() {
            Some(verdict.reason())
        } else if io.mission_state() == MissionState::Running {
            Some(link::mission::RUNNING)
        } else {
            None
        };
        let origin = self.params.origin();
        let context = MissionContext {
            origin: &origin,
            locked,
        };
        let now = io.now_us();
        let outcome = self
            .mission
            .handle(message, (from.system, from.component), now, &context);
        self.deliver_mission(outcome, io).await;
    }

    /// Sends a mission outcome's reply and refusal; puts a new mission in force and stores it.
    pub(super) async fn deliver_mission(&mut self, outcome: Outcome, io: &mut impl VehiclePorts) {
        if let Some((reply, to)) = outcome.reply {
            io.bulk(Bulk::Mission { reply, to });
        }
        if let Some(text) = &outcome.refusal {
            io.reply(report(Severity::Warning, format_args!("{text}")));
        }
        match outcome.event {
            Some(MissionEvent::Replaced | MissionEvent::Cleared) => {
                self.offer_route(io).await;
                let count = self.mission.items().len();
                let saved = self.save_mission().await;
                let mut r = Report::default();
                if count == 0 {
                    r.text(
                        Severity::Info,
                        format_args!("mission cleared: the payload description's target is flown"),
                    );
                } else {
                    r.text(
                        Severity::Info,
                        format_args!("mission of {count} items accepted"),
                    );
                }
                if let Err(e) = saved {
                    r.text(
                        Severity::Error,
                        format_args!("mission in force but not stored: {e}"),
                    );
                }
                io.reply(Outbound::Report(r));
            }
            Some(MissionEvent::SetCurrent(seq)) => {
                let items = self.mission.items().len() as u16;
                io.route(RouteChange::Current(seq), items).await;
            }
            None => {}
        }
    }

    /// Stores the mission in force.
    async fn save_mission(&mut self) -> Result<(), StoreError> {
        let Some(store) = &mut self.store else {
            return Err(StoreError::Other);
        };
        let mut bytes = [0u8; MAX_STORED_LEN];
        let len = stored::encode(self.mission.items(), &mut bytes);
        store.save_mission(&bytes[..len]).await
    }
}
