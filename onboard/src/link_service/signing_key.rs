//! The link's signing key (docs/firmware.md#signing): restored from the store at the
//! start, set or cleared by `SETUP_SIGNING` on a link that may set it, stored before it is
//! said to be in force.

use crate::store::StoreError;
use embedded_storage_async::nor_flash::NorFlash;
use link::signing::KEY_LEN;

use super::{LINK_ID, LinkService, Outbound, VehiclePorts, report};
use crate::autonomy::{Report, Severity};

impl<F: NorFlash> LinkService<F> {
    /// Puts the stored signing key in force, if one is stored; says so.
    pub(super) async fn restore_signing(&mut self, io: &mut impl VehiclePorts) {
        let Some(store) = &mut self.store else {
            return;
        };
        match store.load_signing().await {
            Ok(Some((key, timestamp))) => {
                let now = io.now_us();
                io.signing(|s| s.set_key(key, timestamp, now, LINK_ID));
                io.reply_waiting(report(
                    Severity::Info,
                    format_args!("signing: on (key restored)"),
                ))
                .await;
            }
            Ok(None) => {}
            Err(e) => {
                io.reply_waiting(report(
                    Severity::Error,
                    format_args!("signing: stored key not read ({e}); signing off"),
                ))
                .await;
            }
        }
    }

    /// Sets (or with an all-zero key clears) the signing key, on a link that may; stores it
    /// before saying so.
    pub(super) async fn setup_signing(
        &mut self,
        key: [u8; KEY_LEN],
        timestamp: u64,
        io: &mut impl VehiclePorts,
    ) {
        if !io.key_setup_allowed() {
            io.reply(report(
                Severity::Warning,
                format_args!("signing: key refused: it is set over USB only"),
            ));
            return;
        }
        let stored = match &mut self.store {
            Some(store) => store.save_signing(&key, timestamp).await,
            None => Err(StoreError::Other),
        };
        let now = io.now_us();
        let on = io.signing(|s| {
            s.set_key(key, timestamp, now, LINK_ID);
            s.enabled()
        });
        let mut r = Report::default();
        if on {
            r.text(
                Severity::Notice,
                format_args!("signing: on; unsigned commands and parameter writes are refused"),
            );
        } else {
            r.text(Severity::Notice, format_args!("signing: off"));
        }
        if let Err(e) = stored {
            r.text(
                Severity::Error,
                format_args!("signing: key in force but not stored: {e}"),
            );
        }
        io.reply(Outbound::Report(r));
    }
}
