//! The flight log's two ends (docs/formats.md#flight-logs): the ring the control step writes
//! the mission's log into ([`LOG_RING`], through [`RingEnd`]), never waiting, and the logger
//! task in thread mode, below everything else, that reads it out into the board's log storage
//! (`link::flight_log::keeper`: a numbered log per mission, written in blocks). What the
//! keeper reports (a log opened or closed, the storage failing) goes to the ground as a
//! `STATUSTEXT`; the flight never waits on the storage.

use core::sync::atomic::{AtomicBool, Ordering};

use embassy_sync::channel::TrySendError;
use embassy_sync::once_lock::OnceLock;
use embassy_sync::pipe::Pipe;
use link::flight_log::file::{LogInfo, SYS_NAME};
use link::flight_log::keeper::{KeeperEvent, LogKeeper};
use link::flight_log::session::STEP_BYTES;
use link::flight_log::stream::{LogRing, LogSpace, Splitter};

use super::autonomy::{Report, Severity};
use super::comms::Outbound;
use super::{Cs, MISSION_CONFIG, OUTBOX};
use crate::board::{Board, LogRam, Selected};

/// The ring between the control step and the logger task.
type Ring = Pipe<Cs, { <Selected as Board>::LOG_RING_BYTES }>;

/// The ring between the control step and the logger task, once the task has written it into
/// its memory ([`RING_MEMORY`]; until then the control step records nothing).
pub static LOG_RING: OnceLock<&'static Ring> = OnceLock::new();

// The log's buffers live in the board's log memory, outside the static RAM budget
// (docs/firmware.md#memory): not initialised at start, each written once by the logger task.
/// [`LOG_RING`]'s memory.
#[cfg_attr(feature = "pixhawk6c", unsafe(link_section = ".log_ram"))]
static RING_MEMORY: LogRam<Ring> = LogRam::new();
/// The logger task's working memory.
#[cfg_attr(feature = "pixhawk6c", unsafe(link_section = ".log_ram"))]
static LOGGER_MEMORY: LogRam<LoggerMemory> = LogRam::new();

/// What the logger task works in: the keeper (with its 4 KiB block), the splitter, the
/// chunk read from the ring and the texts for the ground.
struct LoggerMemory {
    keeper: LogKeeper,
    splitter: Splitter,
    chunk: [u8; 1024],
    report: Report,
}

/// Hands `report` to the link, waiting for room without holding a copy of it across the
/// wait (so the task's future, a static in the budgeted RAM, stays small).
async fn send_report(report: &mut Report) {
    loop {
        core::future::poll_fn(|cx| OUTBOX.poll_ready_to_send(cx)).await;
        match OUTBOX.try_send(Outbound::Report(core::mem::take(report))) {
            Ok(()) => return,
            Err(TrySendError::Full(Outbound::Report(back))) => *report = back,
            Err(TrySendError::Full(_)) => return,
        }
    }
}

/// Whether the board keeps flight logs this run (the logger task runs): until then the ring
/// has no room and the control step records nothing.
pub static LOGGING: AtomicBool = AtomicBool::new(false);

/// Bytes of the control step's space on a board that keeps logs (none on one that does not).
const STEP_SPACE: usize = if <Selected as Board>::LOG_RING_BYTES > 0 {
    STEP_BYTES
} else {
    0
};

/// The control step's space, in the log's memory.
#[cfg_attr(feature = "pixhawk6c", unsafe(link_section = ".log_ram"))]
static STEP_MEMORY: LogRam<[u8; STEP_SPACE]> = LogRam::new();

/// The control step's end of [`LOG_RING`]: the step's messages are built in its space, kept
/// between steps (nothing cleared), and go into the ring in one write when the step ends.
pub struct RingEnd {
    space: &'static mut [u8; STEP_SPACE],
    len: usize,
    /// The ring's free bytes when the step began (only the logger changes it, upwards).
    room: Option<usize>,
}

impl RingEnd {
    /// The control step's end.
    ///
    /// # Safety
    ///
    /// Called once (by the control task, its only writer).
    pub unsafe fn take() -> Self {
        Self {
            // SAFETY: the one call, as the caller promises.
            space: unsafe { STEP_MEMORY.init([0; STEP_SPACE]) },
            len: 0,
            room: None,
        }
    }
}

impl LogSpace for RingEnd {
    fn space(&mut self) -> &mut [u8] {
        let room = *self.room.get_or_insert_with(|| match LOG_RING.try_get() {
            Some(ring) if LOGGING.load(Ordering::Relaxed) => ring.free_capacity(),
            _ => 0,
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
        let written = core::mem::take(&mut self.len);
        self.room = None;
        let Some(ring) = LOG_RING.try_get() else {
            return;
        };
        // No more than the ring's free room was written, so all of it goes in; a write stops
        // at the end of the pipe's buffer, and the next one goes on from its start.
        let mut rest = &self.space[..written];
        while let Ok(n @ 1..) = ring.try_write(rest) {
            rest = &rest[n..];
        }
    }
}

/// Reads the ring into `storage`, forever.
#[embassy_executor::task]
pub async fn logger(mut storage: <Selected as Board>::LogStorage) {
    // SAFETY: the task is spawned once and never ends (a pool of one): the only calls.
    let (ring, memory) = unsafe {
        let memory = LOGGER_MEMORY.init(LoggerMemory {
            keeper: LogKeeper::new(),
            splitter: Splitter::new(),
            chunk: [0; 1024],
            report: Report::default(),
        });
        (&*RING_MEMORY.init(Pipe::new()), memory)
    };
    let _ = LOG_RING.init(ring);
    let LoggerMemory {
        keeper,
        splitter,
        chunk,
        report,
    } = memory;
    let info = LogInfo {
        sys_name: SYS_NAME,
        ver_sw: env!("CARGO_PKG_VERSION"),
        ver_hw: <Selected as Board>::NAME,
        start_us: 0,
    };
    loop {
        let n = ring.read(chunk).await;
        // The mission's settings (for a new log's definitions) only until the next wait.
        {
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
        }
        if !report.texts.is_empty() {
            send_report(report).await;
        }
    }
}
