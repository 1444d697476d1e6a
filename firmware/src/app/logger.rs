//! The flight log's two ends (docs/formats.md#flight-logs): the ring of slots the control step
//! builds the mission's log in (through [`RingEnd`]), never waiting, and the logger
//! task in thread mode, below everything else, that reads it out into the board's log storage
//! (`link::flight_log::keeper`: a numbered log per mission, written in blocks). What the
//! keeper reports (a log opened or closed, the storage failing) goes to the ground as a
//! `STATUSTEXT`; the flight never waits on the storage.

use core::sync::atomic::{AtomicBool, Ordering};

use core::cell::Cell;
use embassy_sync::channel::TrySendError;

use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::zerocopy_channel::{Channel, Sender};
use link::flight_log::file::{LogInfo, SYS_NAME};
use link::flight_log::keeper::{KeeperEvent, LogKeeper};
use link::flight_log::session::STEP_BYTES;
use link::flight_log::stream::{LogRing, Splitter};

use super::autonomy::{Report, Severity};
use super::comms::Outbound;
use super::{Cs, MISSION_CONFIG, OUTBOX};
use crate::board::{Board, LogRam, Selected};

/// Bytes of one slot of the ring.
const SLOT_BYTES: usize = 4096;
/// Slots of the ring.
const SLOTS: usize = <Selected as Board>::LOG_RING_BYTES / SLOT_BYTES;
/// Steps a slot stays with the control step at most before it goes to the logger task, full or
/// not (0.1 s: a mission's last messages are stored at once).
const SLOT_STEPS: u16 = 40;

/// One slot of the ring: whole messages of one or more steps, built there in place.
pub struct LogSlot {
    /// Bytes written.
    len: usize,
    /// Steps that wrote into it.
    steps: u16,
    bytes: [u8; SLOT_BYTES],
}

/// The ring between the control step and the logger task: slots the control step fills in
/// place and the logger task empties.
type Ring = Channel<'static, Cs, LogSlot>;
/// The control step's end of the ring.
type RingSender = Sender<'static, Cs, LogSlot>;

// The log's buffers live in the board's log memory, outside the static RAM budget
// (docs/firmware.md#memory): not initialised at start, each written once by the logger task.
/// The ring's state.
#[cfg_attr(feature = "pixhawk6c", unsafe(link_section = ".log_ram"))]
static RING_MEMORY: LogRam<Ring> = LogRam::new();
/// The ring's slots.
#[cfg_attr(feature = "pixhawk6c", unsafe(link_section = ".log_ram"))]
static SLOT_MEMORY: LogRam<[LogSlot; SLOTS]> = LogRam::new();
/// The logger task's working memory.
#[cfg_attr(feature = "pixhawk6c", unsafe(link_section = ".log_ram"))]
static LOGGER_MEMORY: LogRam<LoggerMemory> = LogRam::new();

/// The control step's end of the ring, once the logger task has set the ring up (until then,
/// and on a board that keeps no logs, the control step records nothing).
static RING_SENDER: Mutex<Cs, Cell<Option<RingSender>>> = Mutex::new(Cell::new(None));

/// What the logger task works in: the keeper (with its 4 KiB block), the splitter and the
/// texts for the ground.
struct LoggerMemory {
    keeper: LogKeeper,
    splitter: Splitter,
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

/// The control step's end of the ring: each step's messages are built in place in the slot
/// being filled, which goes to the logger task when it has no room for another step, has
/// held its steps for [`SLOT_STEPS`] or holds the log's end. With every slot full the step's records are lost (and
/// counted, then said in a dropout message).
pub struct RingEnd {
    sender: Option<RingSender>,
}

impl Default for RingEnd {
    fn default() -> Self {
        Self::new()
    }
}

impl RingEnd {
    /// The control step's end, before the ring is set up.
    pub const fn new() -> Self {
        Self { sender: None }
    }

    /// The ring's sender, once the logger task has handed it over.
    fn sender(&mut self) -> Option<&mut RingSender> {
        if self.sender.is_none() && LOGGING.load(Ordering::Relaxed) {
            self.sender = RING_SENDER.lock(Cell::take);
        }
        self.sender.as_mut()
    }
}

impl LogRing for RingEnd {
    fn step_space(&mut self) -> &mut [u8] {
        match self.sender().and_then(Sender::try_send) {
            Some(slot) => {
                let from = slot.len.min(SLOT_BYTES);
                let to = (from + STEP_BYTES).min(SLOT_BYTES);
                &mut slot.bytes[from..to]
            }
            None => &mut [],
        }
    }

    fn commit_step(&mut self, n: usize, ended: bool) {
        let Some(sender) = self.sender.as_mut() else {
            return;
        };
        let Some(slot) = sender.try_send() else {
            return;
        };
        if n == 0 && slot.len == 0 {
            return;
        }
        slot.len = (slot.len + n).min(SLOT_BYTES);
        slot.steps += 1;
        if ended || SLOT_BYTES - slot.len < STEP_BYTES || slot.steps >= SLOT_STEPS {
            sender.send_done();
        }
    }
}

/// Reads the ring into `storage`, forever.
#[embassy_executor::task]
pub async fn logger(mut storage: <Selected as Board>::LogStorage) {
    // SAFETY: the task is spawned once and never ends (a pool of one): the only calls; a slot
    // of zeros is an empty slot.
    let (ring, memory) = unsafe {
        let memory = LOGGER_MEMORY.init(LoggerMemory {
            keeper: LogKeeper::new(),
            splitter: Splitter::new(),
            report: Report::default(),
        });
        (
            RING_MEMORY.init(Channel::new(SLOT_MEMORY.init_zeroed())),
            memory,
        )
    };
    let (sender, mut receiver) = ring.split();
    RING_SENDER.lock(|s| s.set(Some(sender)));
    let LoggerMemory {
        keeper,
        splitter,
        report,
    } = memory;
    let info = LogInfo {
        sys_name: SYS_NAME,
        ver_sw: env!("CARGO_PKG_VERSION"),
        ver_hw: <Selected as Board>::NAME,
        start_us: 0,
    };
    loop {
        let slot = receiver.receive().await;
        // The mission's settings (for a new log's definitions) only until the next wait.
        {
            let config = MISSION_CONFIG.lock(|c| c.get());
            splitter.push(&slot.bytes[..slot.len], &mut |piece| match keeper.take(
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
        slot.len = 0;
        slot.steps = 0;
        receiver.receive_done();
        if !report.texts.is_empty() {
            send_report(report).await;
        }
    }
}
