//! Parameters over the link (docs/firmware.md#parameters): the store read at the start,
//! reads and writes answered, a changed value stored before its `PARAM_VALUE` goes out (so a
//! ground station that saw the answer may cut the power), a calibration's offsets set as
//! their parameters.

use crate::store::{ParamStore, StoreError};
use embedded_storage_async::nor_flash::NorFlash;
use link::geo::GeoOrigin;
use link::param::{ParamRequest, ParamService, Values};
use link::signing::Verdict;
use link::vehicle::Sender;
use shared::mission::bringup::CalibrationKind;
use shared::mission::params::{COUNT as PARAM_COUNT, NAME_LEN, ParamValues, TABLE, is_origin};

use super::messages::ParamBits;
use super::ports::send_values;
use super::{LinkService, Outbound, VehiclePorts, change_refused, report};
use crate::autonomy::{Report, Severity};

// Every parameter's index is a bit of `Outbound::Params`.
const _: () = assert!(PARAM_COUNT <= ParamBits::CAPACITY);

impl<F: NorFlash> LinkService<F> {
    /// Reads the stored values and puts them in force; says what it found.
    pub(super) async fn open_params(
        &mut self,
        store: Result<ParamStore<F>, StoreError>,
        io: &mut impl VehiclePorts,
    ) {
        let mut values = ParamValues::DEFAULT;
        match store {
            Ok(mut store) => {
                let loaded = store.load(&mut values).await;
                self.store = Some(store);
                let mut r = Report::default();
                r.text(
                    Severity::Info,
                    format_args!(
                        "params: {} of {PARAM_COUNT} restored from storage",
                        loaded.restored
                    ),
                );
                if loaded.refused > 0 {
                    r.text(
                        Severity::Warning,
                        format_args!(
                            "params: {} stored values out of today's ranges, defaults used",
                            loaded.refused
                        ),
                    );
                }
                if let Some(e) = loaded.error {
                    r.text(Severity::Error, format_args!("params: {e}"));
                }
                if GeoOrigin::from_params(&values) == GeoOrigin::from_params(&ParamValues::DEFAULT)
                {
                    r.text(
                        Severity::Notice,
                        format_args!("origin: not set; the map shows PX4's simulation home"),
                    );
                }
                if !io.store_persistent() {
                    r.text(
                        Severity::Warning,
                        format_args!("params: kept in RAM on this board, lost at power-off"),
                    );
                }
                io.reply_waiting(Outbound::Report(r)).await;
            }
            Err(e) => {
                io.reply_waiting(report(Severity::Error, format_args!("params: {e}")))
                    .await;
            }
        }
        self.params = ParamService::new(values);
        io.apply_config(self.params.values().config());
        // Waited for, as the texts above: the send task may not have begun.
        io.publish(self.params.values());
        io.reply_waiting(Outbound::Origin).await;
    }

    /// Answers a parameter request, puts a changed value in force and stores it.
    pub(super) async fn handle_param(
        &mut self,
        request: ParamRequest,
        from: Sender,
        verdict: Verdict,
        io: &mut impl VehiclePorts,
    ) {
        let refuse_changes = change_refused(verdict, io);
        self.params.drive_robots(io.payload_robots(), io.drives());
        let answer = self.params.handle(&request, refuse_changes);
        if let Some((index, value)) = answer.changed {
            self.save_param(index, value, io).await;
            if is_origin(index) {
                self.announce_origin(io);
            } else {
                // In force now for the loaded payload (the mission is not running) and the next.
                io.apply_config(self.params.values().config());
                io.reload();
            }
        }
        send_values(io, self.params.values(), answer.values, Some(from));
        if let Some(text) = &answer.text {
            io.reply(report(Severity::Warning, format_args!("{text}")));
        }
    }

    /// Sets a calibration's offsets as their parameters (`CAL_GYRO0_*OFF` or `CAL_ACC0_*OFF`),
    /// stores them and sends their `PARAM_VALUE`s (the mission has them in force already).
    pub(super) async fn store_calibration(
        &mut self,
        kind: CalibrationKind,
        offsets: [f32; 3],
        io: &mut impl VehiclePorts,
    ) {
        let names = match kind {
            CalibrationKind::Gyro => ["CAL_GYRO0_XOFF", "CAL_GYRO0_YOFF", "CAL_GYRO0_ZOFF"],
            CalibrationKind::Level => ["CAL_ACC0_XOFF", "CAL_ACC0_YOFF", "CAL_ACC0_ZOFF"],
        };
        let mut answered = ParamBits::default();
        for (name, value) in names.into_iter().zip(offsets) {
            let mut id = [0u8; NAME_LEN];
            id[..name.len()].copy_from_slice(name.as_bytes());
            let answer = self
                .params
                .handle(&ParamRequest::Set { name: id, value }, None);
            if let Some((index, value)) = answer.changed {
                self.save_param(index, value, io).await;
            }
            if let Values::One(index) = answer.values {
                answered.insert(index);
            }
        }
        // The three values as one entry of the queue.
        io.publish(self.params.values());
        io.reply(Outbound::Params(answered));
        io.record_config(self.params.values().config());
    }

    /// Stores parameter `index` as `value`, already in force; says so when it cannot be
    /// stored.
    pub(super) async fn save_param(
        &mut self,
        index: usize,
        value: f32,
        io: &mut impl VehiclePorts,
    ) {
        let stored = match &mut self.store {
            Some(store) => store.save(index, value).await,
            None => Err(StoreError::Other),
        };
        if let Err(e) = stored {
            io.reply(report(
                Severity::Error,
                format_args!("param {} in force but not stored: {e}", TABLE[index].name),
            ));
        }
    }
}
