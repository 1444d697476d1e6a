//! The flight log's two ends (docs/formats.md#flight-logs): the ring of slots the control step
//! builds the mission's log in (through [`RingEnd`]), never waiting, and the logger
//! task in thread mode, below everything else, that reads it out into the board's log storage
//! (`flight_log::keeper`: a numbered log per mission, written in blocks). What the
//! keeper reports (a log opened or closed, the storage failing) goes to the ground as a
//! `STATUSTEXT`; the flight never waits on the storage.
//!
//! The same task serves the logs to the ground (docs/formats.md#downloading-the-logs,
//! `link::log_transfer`): the link's receive task hands it the log requests ([`request`])
//! and it answers between its writes, the ring first: a turn sends at most
//! [`TURN_MESSAGES`] messages, each only into an empty [`BULK`] queue, then waits [`TURN_PAUSE`],
//! so a download never holds up the control step's messages, the heartbeat or the telemetry.

use core::sync::atomic::{AtomicBool, Ordering};

use core::cell::Cell;

use embassy_futures::select::{Either, select};
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::channel::{self, TrySendError};
use embassy_sync::zerocopy_channel::{Channel, Receiver, Sender};
use embassy_time::{Duration, Timer};
use flight_log::file::{LogInfo, SYS_NAME};
use flight_log::keeper::{KeeperEvent, LogKeeper, LogStorage};
use flight_log::session::STEP_BYTES;
use flight_log::stream::{LogRing, Splitter};
use link::log_transfer::{LogNotice, LogReply, LogRequest, LogService};
use link::telemetry::LogHealth;

use super::autonomy::{Report, Severity};
use super::comms::{Bulk, Outbound};
use super::{ARMED, BULK, Cs, MISSION_CONFIG, OUTBOX};
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

/// What the logger task works in: the keeper (with its 4 KiB block), the splitter, the texts
/// for the ground and the log protocol's state.
struct LoggerMemory {
    keeper: LogKeeper,
    splitter: Splitter,
    report: Report,
    service: LogService,
    /// A log-protocol message the outbox had no room for, sent first at the next turn.
    pending: Option<LogReply>,
}

/// Log-protocol requests from the link, for the logger task (queued from the start, before
/// the task first runs: a ground station may ask as soon as it hears the vehicle).
static REQUESTS: channel::Channel<Cs, LogRequest, 2> = channel::Channel::new();

/// Most log-protocol messages sent in one turn of the logger task.
pub const TURN_MESSAGES: usize = 8;
/// The logger task's pause between two turns of a download.
pub const TURN_PAUSE: Duration = Duration::from_millis(1);

/// Hands a log-protocol request to the logger task (two waiting already means a ground station
/// asking faster than it is answered: the newest counts). `false`: no logger task runs (the
/// board keeps no logs this run).
pub fn request(request: LogRequest) -> bool {
    if !<Selected as Board>::keeps_logs() {
        return false;
    }
    if let Err(TrySendError::Full(request)) = REQUESTS.try_send(request) {
        let _ = REQUESTS.try_receive();
        let _ = REQUESTS.try_send(request);
    }
    true
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

/// The storage failed, and no log has been opened since (`SYS_STATUS` reports it).
static STORAGE_FAILED: AtomicBool = AtomicBool::new(false);

/// The flight log's storage, for `SYS_STATUS`.
pub fn health() -> LogHealth {
    if !LOGGING.load(Ordering::Relaxed) {
        LogHealth::Absent
    } else if STORAGE_FAILED.load(Ordering::Relaxed) {
        LogHealth::Failed
    } else {
        LogHealth::Ready
    }
}

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

    /// Waits until the ring has room for a step, when there is a ring. Only in lockstep, where
    /// the plant waits for the step anyway: a HIL log then loses nothing however the host's
    /// load paces QEMU against the plant (on a board the step never waits: a full ring loses
    /// the step's records, and a dropout says so).
    pub async fn wait_for_room(&mut self) {
        if let Some(sender) = self.sender() {
            // A slot to fill (the one being filled, or a free one), not yet handed on.
            let _ = sender.send().await;
        }
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

/// Reads the ring into `storage` and serves the logs to the ground, forever.
#[embassy_executor::task]
pub async fn logger(mut storage: <Selected as Board>::LogStorage) {
    // SAFETY: the task is spawned once and never ends (a pool of one): the only calls; a slot
    // of zeros is an empty slot.
    let (ring, memory) = unsafe {
        let memory = LOGGER_MEMORY.init(LoggerMemory {
            keeper: LogKeeper::new(),
            splitter: Splitter::new(),
            report: Report::default(),
            service: LogService::new(),
            pending: None,
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
        service,
        pending,
    } = memory;
    let requests = &REQUESTS;
    let info = LogInfo {
        sys_name: SYS_NAME,
        ver_sw: env!("CARGO_PKG_VERSION"),
        ver_hw: <Selected as Board>::NAME,
        start_us: 0,
    };
    loop {
        // The flight log first: whatever the ring holds is stored before anything is served.
        if receiver.try_receive().is_none() {
            if service.sending() || pending.is_some() {
                serve_turn(service, &mut storage, pending, report);
                if !report.texts.is_empty() {
                    send_report(report).await;
                }
                Timer::after(TURN_PAUSE).await;
                if let Ok(request) = requests.try_receive() {
                    take_request(request, service, &mut storage, keeper, report);
                }
            } else if let Either::Second(request) =
                select(receiver.receive(), requests.receive()).await
            {
                take_request(request, service, &mut storage, keeper, report);
            }
        }
        store_slot(&mut receiver, splitter, keeper, &mut storage, &info, report);
        if !report.texts.is_empty() {
            send_report(report).await;
        }
    }
}

/// Stores the slot the ring holds through the keeper and hands it back; what people should
/// hear of goes into `report`.
fn store_slot(
    receiver: &mut Receiver<'static, Cs, LogSlot>,
    splitter: &mut Splitter,
    keeper: &mut LogKeeper,
    storage: &mut <Selected as Board>::LogStorage,
    info: &LogInfo<'_>,
    report: &mut Report,
) {
    let Some(slot) = receiver.try_receive() else {
        return;
    };
    // The mission's settings (for a new log's definitions).
    let config = MISSION_CONFIG.lock(|c| c.get());
    splitter.push(
        &slot.bytes[..slot.len.min(SLOT_BYTES)],
        &mut |piece| match keeper.take(storage, piece, info, &config) {
            Ok(Some(KeeperEvent::Opened(id))) => {
                STORAGE_FAILED.store(false, Ordering::Relaxed);
                report.text(Severity::Info, format_args!("flight log {id} started"));
            }
            Ok(Some(KeeperEvent::Closed(id, size))) => report.text(
                Severity::Info,
                format_args!("flight log {id} written: {size} bytes"),
            ),
            Ok(Some(KeeperEvent::Failed)) => {
                STORAGE_FAILED.store(true, Ordering::Relaxed);
                report.text(
                    Severity::Error,
                    format_args!("flight log incomplete: the storage failed during the flight"),
                );
            }
            Ok(None) => {}
            Err(e) => {
                STORAGE_FAILED.store(true, Ordering::Relaxed);
                report.text(Severity::Error, format_args!("flight log stopped: {e}"));
            }
        },
    );
    slot.len = 0;
    slot.steps = 0;
    receiver.receive_done();
}

/// Takes a log-protocol request; what people should hear of it goes into `report`.
fn take_request<S: LogStorage>(
    request: LogRequest,
    service: &mut LogService,
    storage: &mut S,
    keeper: &LogKeeper,
    report: &mut Report,
) {
    let erase_refused = if ARMED.load(Ordering::Relaxed) {
        Some("the vehicle is armed")
    } else if keeper.writing().is_some() {
        Some("a flight log is being written")
    } else {
        None
    };
    match service.handle(request, storage, erase_refused) {
        Ok(None) => {}
        Ok(Some(notice)) => {
            let severity = match notice {
                LogNotice::Erased(_) => Severity::Notice,
                _ => Severity::Warning,
            };
            report.text(severity, format_args!("{notice}"));
        }
        Err(e) => report.text(Severity::Error, format_args!("flight logs: {e}")),
    }
}

/// Sends up to [`TURN_MESSAGES`] of what the service has to send, each only into an empty
/// bulk queue (which the send task serves after the control step's messages, the heartbeat,
/// the replies and the telemetry), never waiting: a message the outbox had no room for after all waits in
/// `pending` for the next turn. A storage error goes into `report`.
fn serve_turn<S: LogStorage>(
    service: &mut LogService,
    storage: &mut S,
    pending: &mut Option<LogReply>,
    report: &mut Report,
) {
    for _ in 0..TURN_MESSAGES {
        if !BULK.is_empty() {
            return;
        }
        let reply = match pending.take() {
            Some(reply) => reply,
            None => match service.next(storage) {
                Ok(Some(reply)) => reply,
                Ok(None) => return,
                Err(e) => {
                    report.text(Severity::Error, format_args!("log download stopped: {e}"));
                    return;
                }
            },
        };
        if let Err(TrySendError::Full(Bulk::Log(back))) = BULK.try_send(Bulk::Log(reply)) {
            *pending = Some(back);
            return;
        }
    }
}
