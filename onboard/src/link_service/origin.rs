//! The map origin over the link (docs/ground-link.md#the-map-origin): `SET_GPS_GLOBAL_ORIGIN`
//! and `MAV_CMD_DO_SET_GLOBAL_ORIGIN` set the origin's five parameters together, refused as a
//! `PARAM_SET` is (unsigned once signing is on, or while the mission runs) or when the origin
//! cannot place the vehicle.

use embedded_storage_async::nor_flash::NorFlash;
use link::command_wire::CommandId;
use link::geo::{GeoOrigin, OriginError};
use link::msg::MavResult;
use link::signing::Verdict;

use super::commands::refuse;
use super::messages::ParamBits;
use super::{LinkService, Outbound, VehiclePorts, change_refused, report};
use crate::autonomy::Severity;

impl<F: NorFlash> LinkService<F> {
    /// The origin asked for, checked ([`change_refused`], then the origin itself).
    fn checked_origin(
        &self,
        (lat_e7, lon_e7, alt_mm): (i32, i32, i32),
        verdict: Verdict,
        io: &impl VehiclePorts,
    ) -> Result<GeoOrigin, &'static str> {
        match change_refused(verdict, io) {
            Some(why) => Err(why),
            None => GeoOrigin::from_message(lat_e7, lon_e7, alt_mm).map_err(OriginError::as_str),
        }
    }

    /// `SET_GPS_GLOBAL_ORIGIN`: answered with the parameters' `PARAM_VALUE`s and
    /// `GPS_GLOBAL_ORIGIN`, or a text saying why not.
    pub(super) async fn set_origin(
        &mut self,
        origin: (i32, i32, i32),
        verdict: Verdict,
        io: &mut impl VehiclePorts,
    ) {
        match self.checked_origin(origin, verdict, io) {
            Ok(origin) => self.store_origin(&origin, io).await,
            Err(why) => io.reply(report(
                Severity::Warning,
                format_args!("origin not changed: {why}"),
            )),
        }
    }

    /// `MAV_CMD_DO_SET_GLOBAL_ORIGIN` (a `COMMAND_INT`): as `SET_GPS_GLOBAL_ORIGIN`,
    /// acknowledged first (a refusal `DENIED` with the reason).
    pub(super) async fn command_origin(
        &mut self,
        command: CommandId,
        origin: (i32, i32, i32),
        verdict: Verdict,
        io: &mut impl VehiclePorts,
    ) {
        match self.checked_origin(origin, verdict, io) {
            Ok(origin) => {
                let result = MavResult::MAV_RESULT_ACCEPTED;
                io.reply(Outbound::Ack { command, result });
                self.store_origin(&origin, io).await;
            }
            Err(why) => refuse(io, command, MavResult::MAV_RESULT_DENIED, why),
        }
    }

    /// Sets and stores a checked origin's parameters; sends their `PARAM_VALUE`s and
    /// `GPS_GLOBAL_ORIGIN`.
    async fn store_origin(&mut self, origin: &GeoOrigin, io: &mut impl VehiclePorts) {
        let Ok(changed) = self.params.set_origin(origin) else {
            return;
        };
        let mut answered = ParamBits::default();
        for &(index, value) in &changed {
            // Without a store (it did not open, said at the start) nothing more is said.
            if self.store.is_some() {
                self.save_param(index, value, io).await;
            }
            answered.insert(index);
        }
        // One entry for the five values: the queue keeps room for the origin after them (whose
        // announcement hands the send task the values in force).
        io.reply(Outbound::Params(answered));
        self.announce_origin(io);
    }

    /// Hands the map origin in force to the send task, which sends `GPS_GLOBAL_ORIGIN` and
    /// says when the global position cannot be given.
    pub(super) fn announce_origin(&self, io: &mut impl VehiclePorts) {
        io.publish(self.params.values());
        io.reply(Outbound::Origin);
    }
}
