//! The payload description's upload over MAVLink FTP (docs/firmware.md#payload-upload):
//! every request answered (refused unsigned once signing is on, said once per sender in a
//! row), a file written whole decoded and checked with the host's checks and for this board's
//! outputs, handed to the job task and stored; the stored one is put in force at the start.

use embedded_storage_async::nor_flash::NorFlash;
use link::ftp::{FileEvent, FtpMessage};
use link::signing::Verdict;
use link::vehicle::Sender;
use shared::scenario_wire::{PayloadError, decode_and_check, decode_for_board};

use super::{Bulk, LinkService, Received, VehiclePorts, report};
use crate::autonomy::Severity;

impl<F: NorFlash> LinkService<F> {
    /// An FTP request: answered; a payload description written whole is checked.
    pub(super) async fn handle_ftp(
        &mut self,
        message: &FtpMessage,
        from: Sender,
        verdict: Verdict,
        io: &mut impl VehiclePorts,
    ) {
        if !verdict.trusted() {
            io.bulk(Bulk::Ftp {
                message: link::ftp::refusal(message),
                to: from,
            });
            // Said once per sender in a row: a ground station that retries its file reads
            // (MAVProxy's) would fill its own console with the same line.
            let sender = 1 + (u32::from(from.system) << 8 | u32::from(from.component));
            if core::mem::replace(&mut self.ftp_refused, sender) != sender {
                io.reply(report(
                    Severity::Warning,
                    format_args!("payload upload refused: {}", verdict.reason()),
                ));
            }
            return;
        }
        self.ftp_refused = 0;
        let (answer, event) = self.ftp.handle_with(message, self.files);
        io.bulk(Bulk::Ftp {
            message: answer,
            to: from,
        });
        if let FileEvent::Written { .. } = event {
            self.check_payload(true, io).await;
        }
    }

    /// Loads the stored payload description, if one is stored and passes the checks, as if
    /// it had just been uploaded.
    pub(super) async fn restore_payload(&mut self, io: &mut impl VehiclePorts) {
        let Some(store) = &mut self.store else {
            return;
        };
        let valid = |bytes: &[u8]| decode_and_check(bytes).is_ok();
        match store.load_payload(self.ftp.restore_buffer(), valid).await {
            Ok(Some(len)) => {
                self.ftp.restored(len);
                io.reply_waiting(report(
                    Severity::Info,
                    format_args!("payload description restored from storage"),
                ))
                .await;
                self.check_payload(false, io).await;
            }
            Ok(None) => {}
            Err(e) => {
                io.reply_waiting(report(
                    Severity::Error,
                    format_args!("payload description not read from storage: {e}"),
                ))
                .await;
            }
        }
    }

    /// Decodes and checks the payload description file with the host's checks; stores it
    /// (when `store`) and hands it to the job task to load (which then says it was accepted),
    /// or says which key is wrong.
    ///
    /// The decoded description (2.5 KB with its wire form) is never kept across a wait (the
    /// firmware's receive future is a static): [`Self::hand_over`] decodes it on the stack and
    /// offers it; if the job task has not taken the last one yet, this waits for room and
    /// decodes the same bytes again.
    async fn check_payload(&mut self, store: bool, io: &mut impl VehiclePorts) {
        let accepted = loop {
            match self.hand_over(io) {
                Ok(true) => break true,
                Ok(false) => io.payload_room().await,
                Err(e) => {
                    io.reply_waiting(report(
                        Severity::Error,
                        format_args!("payload refused: {e}"),
                    ))
                    .await;
                    break false;
                }
            }
        };
        // Stored after it went to the planner, so the description (1.4 KB) is not held across
        // the store's wait.
        if accepted
            && store
            && let Some(s) = &mut self.store
            && let Err(e) = s.save_payload(self.ftp.file()).await
        {
            io.reply_waiting(report(
                Severity::Error,
                format_args!("payload description in use but not stored: {e}"),
            ))
            .await;
        }
    }

    /// Decodes and checks the file; a description that passes goes to the job task if it has
    /// room (`true`), else it is dropped (`false`: [`Self::check_payload`] waits for room and
    /// comes again; this is the job task's only sender, so once is enough).
    fn hand_over(&self, io: &mut impl VehiclePorts) -> Result<bool, PayloadError> {
        // The board must drive every robot with the ESC protocol in force.
        let esc_protocol = self.params.values().config().hardware.esc_protocol;
        let (wire, scenario) = decode_for_board(self.ftp.file(), &io.drives(), esc_protocol)?;
        Ok(io.offer_payload(Received {
            name: wire.name,
            scenario,
        }))
    }
}
