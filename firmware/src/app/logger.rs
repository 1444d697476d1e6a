//! The flight log's two ends (docs/formats.md#flight-logs): the ring the control step writes
//! the mission's log into ([`LOG_RING`], through [`RingEnd`]), never waiting, and the logger
//! task in thread mode, below everything else, that reads it out into the board's log storage
//! (`link::flight_log::keeper`: a numbered log per mission, written in blocks). What the
//! keeper reports (a log opened or closed, the storage failing) goes to the ground as a
//! `STATUSTEXT`; the flight never waits on the storage.

use core::sync::atomic::{AtomicBool, Ordering};

use embassy_sync::pipe::Pipe;
use link::flight_log::file::{LogInfo, SYS_NAME};
use link::flight_log::keeper::{KeeperEvent, LogKeeper};
use link::flight_log::session::STEP_BYTES;
use link::flight_log::stream::{LogRing, LogSpace, Splitter};
use static_cell::StaticCell;

use super::autonomy::{Report, Severity};
use super::comms::Outbound;
use super::{Cs, MISSION_CONFIG, OUTBOX};
use crate::board::{Board, Selected};

/// The ring between the control step and the logger task.
pub static LOG_RING: Pipe<Cs, { <Selected as Board>::LOG_RING_BYTES }> = Pipe::new();

/// Whether the board keeps flight logs this run (the logger task runs): until then the ring
/// has no room and the control step records nothing.
pub static LOGGING: AtomicBool = AtomicBool::new(false);

/// Bytes of the control step's space on a board that keeps logs (none on one that does not).
const STEP_SPACE: usize = if <Selected as Board>::LOG_RING_BYTES > 0 {
    STEP_BYTES
} else {
    0
};

/// The control step's end of [`LOG_RING`]: the step's messages are built in its space, kept
/// between steps (nothing cleared), and go into the ring in one write when the step ends.
pub struct RingEnd {
    space: &'static mut [u8; STEP_SPACE],
    len: usize,
    /// The ring's free bytes when the step began (only the logger changes it, upwards).
    room: Option<usize>,
}

impl RingEnd {
    /// The control step's end; taken once, by the control task.
    pub fn take() -> Option<Self> {
        static SPACE: StaticCell<[u8; STEP_SPACE]> = StaticCell::new();
        let space = SPACE.try_init([0; STEP_SPACE])?;
        Some(Self {
            space,
            len: 0,
            room: None,
        })
    }
}

impl LogSpace for RingEnd {
    fn space(&mut self) -> &mut [u8] {
        let room = *self.room.get_or_insert_with(|| {
            if LOGGING.load(Ordering::Relaxed) {
                LOG_RING.free_capacity()
            } else {
                0
            }
        });
        let end = room.min(STEP_SPACE).max(self.len);
        &mut self.space[self.len..end]
    }
    fn commit(&mut self, n: usize) {
        self.len = (self.len + n).min(STEP_SPACE);
    }
}

impl LogRing for RingEnd {
    fn flush(&mut self) {
        // No more than the ring's free room was written, so all of it goes in; a write stops
        // at the end of the pipe's buffer, and the next one goes on from its start.
        let mut rest = &self.space[..self.len];
        while let Ok(n @ 1..) = LOG_RING.try_write(rest) {
            rest = &rest[n..];
        }
        self.len = 0;
        self.room = None;
    }
}

/// Reads the ring into `storage`, forever.
#[embassy_executor::task]
pub async fn logger(mut storage: <Selected as Board>::LogStorage) {
    let mut keeper = LogKeeper::new();
    let mut splitter = Splitter::new();
    let mut chunk = [0u8; 1024];
    let info = LogInfo {
        sys_name: SYS_NAME,
        ver_sw: env!("CARGO_PKG_VERSION"),
        ver_hw: <Selected as Board>::NAME,
        start_us: 0,
    };
    loop {
        let n = LOG_RING.read(&mut chunk).await;
        let mut report = Report::default();
        let config = MISSION_CONFIG.lock(|c| c.get());
        splitter.push(&chunk[..n], &mut |piece| match keeper.take(
            &mut storage,
            piece,
            &info,
            &config,
        ) {
            Ok(Some(KeeperEvent::Opened(id))) => {
                report.text(Severity::Info, format_args!("flight log {id} started"));
            }
            Ok(Some(KeeperEvent::Closed(id, size))) => report.text(
                Severity::Info,
                format_args!("flight log {id} written: {size} bytes"),
            ),
            Ok(Some(KeeperEvent::Failed)) => report.text(
                Severity::Error,
                format_args!("flight log incomplete: the storage failed during the flight"),
            ),
            Ok(None) => {}
            Err(e) => report.text(Severity::Error, format_args!("flight log stopped: {e}")),
        });
        if !report.texts.is_empty() {
            OUTBOX.send(Outbound::Report(report)).await;
        }
    }
}
