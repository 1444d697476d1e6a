//! The application, written once for every board: five tasks on three
//! executors, embassy's multi-priority pattern.
//!
//! | task | executor | does |
//! |---|---|---|
//! | [`control`] | [`CONTROL_EXECUTOR`], an `InterruptExecutor` at the highest priority | one step of the autonomy per IMU sample (400 Hz), actuator outputs |
//! | [`comms`] receive and send | [`LINK_EXECUTOR`], an `InterruptExecutor` below control | MAVLink: HIL sensors in, commands, FTP, status out |
//! | [`jobs`] | thread mode (`WFI` between polls) | the autonomy's long computations, off the tick |
//! | [`logger`] | thread mode | the flight log from its ring into the board's storage |
//!
//! The tasks talk through the channels and signals below, never by shared mutable state. The
//! autonomy sits behind one narrow seam, [`autonomy`]: the integration point of the mission.

pub use onboard::autonomy;
pub mod comms;
pub mod control;
pub mod jobs;
pub mod logger;
pub mod rc;

use core::sync::atomic::{AtomicBool, AtomicU8, AtomicU32, Ordering};

use core::cell::Cell;
use embassy_executor::{InterruptExecutor, SendSpawner, Spawner, raw};

use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::channel::Channel;
use embassy_sync::signal::Signal;
use link::signing::Signing;
use link::telemetry::{Schedule, VehicleSnapshot};
use link::timesync::TimeSync;
use shared::mission::MissionConfig;
use static_cell::StaticCell;

use crate::board::{Parts, Selected};

/// The control executor (highest priority of the three).
pub static CONTROL_EXECUTOR: InterruptExecutor = InterruptExecutor::new();
/// The link executor.
pub static LINK_EXECUTOR: InterruptExecutor = InterruptExecutor::new();

type Cs = CriticalSectionRawMutex;

/// IMU samples for the control task (from the HIL link; from the IMU driver on hardware).
pub static SENSOR: Channel<Cs, comms::SensorSample, 2> = Channel::new();
/// The latest motion-capture fix not yet taken by a control step.
pub static MOCAP: Signal<Cs, link::hil::MocapFix> = Signal::new();
/// Operator commands for the autonomy, with what their acknowledgement needs.
pub static COMMANDS: Channel<Cs, comms::PendingCommand, 4> = Channel::new();
/// A payload description received and checked, for the job task to load the planner with.
pub static TO_LOAD: Channel<Cs, comms::Received, 1> = Channel::new();
/// A payload description loaded into the planner, for the autonomy, with the configuration
/// the planner was loaded with (the mission takes the same). Only the newest counts: see
/// [`offer_payload`]. (A channel, not a `Signal`: a `Signal` of this type starts from a
/// non-zero bit pattern, so its 1.7 KB would be a `.data` image in flash.)
pub static PAYLOAD: Channel<Cs, LoadedPayload, 1> = Channel::new();

/// Robots of the payload description last loaded into the planner (0: none yet): the
/// parameter service refuses an `ESC_PROTOCOL` with which the board would drive fewer.
pub static PAYLOAD_ROBOTS: core::sync::atomic::AtomicU8 = core::sync::atomic::AtomicU8::new(0);

/// Hands `payload` to the autonomy in place of any the control task has not taken yet.
pub fn offer_payload(payload: LoadedPayload) {
    PAYLOAD.clear();
    // The job task is the only sender and the channel was just emptied: this cannot be full.
    let _ = PAYLOAD.try_send(payload);
}
/// A change of the ground station's route (docs/ground-link.md#missions), from the link's
/// mission service for the autonomy, in order.
pub static ROUTE: Channel<Cs, autonomy::RouteChange, 2> = Channel::new();
/// Set after a send to [`ROUTE`]: the control step looks in the channel only then (a load
/// costs it two instructions, a look at the channel a critical section).
pub static ROUTE_SENT: AtomicBool = AtomicBool::new(false);
/// Counts the control steps that changed the mode, the route's progress or the landed state
/// in [`VEHICLE`]: the send task looks at those only when it moved.
pub static STATUS_CHANGES: AtomicU32 = AtomicU32::new(0);
/// Items of the mission in force (`MISSION_CURRENT`'s `total`).
pub static MISSION_ITEMS: core::sync::atomic::AtomicU16 = core::sync::atomic::AtomicU16::new(0);

/// The mission configuration the parameters make now (set by the link task from the stored
/// parameters and each accepted `PARAM_SET`; taken when a payload description is loaded).
pub static MISSION_CONFIG: Mutex<Cs, Cell<MissionConfig>> =
    Mutex::new(Cell::new(MissionConfig::DEFAULT));

/// The parameters changed (at start, or a `PARAM_SET`): the control step puts
/// [`BENCH_CONFIG`] in force (a load each step; the settings are read only when set).
pub static CONFIG_CHANGED: AtomicBool = AtomicBool::new(false);

/// The part of [`MISSION_CONFIG`] the mission takes without a payload description: the IMU's
/// offsets and the hardware settings (small: the control step copies it).
pub static BENCH_CONFIG: Mutex<Cs, Cell<shared::mission::bringup::BenchConfig>> =
    Mutex::new(Cell::new(shared::mission::bringup::BenchConfig {
        sensors: shared::mission::bringup::SensorOffsets::ZERO,
        hardware: shared::mission::HardwareConfig::DEFAULT,
    }));

/// Puts `config` in force for the next payload description, and its bench part for the
/// control step now.
pub fn set_config(config: MissionConfig) {
    MISSION_CONFIG.lock(|c| c.set(config));
    BENCH_CONFIG.lock(|c| c.set((&config).into()));
    CONFIG_CHANGED.store(true, Ordering::Release);
}

/// A calibration's offsets, from the control task for the receive task to store as
/// parameters (docs/ground-link.md#bring-up-commands).
pub static CALIBRATED: Channel<Cs, (shared::mission::bringup::CalibrationKind, [f32; 3]), 1> =
    Channel::new();

/// A parameter changed: the job task loads the last payload description again with the new
/// configuration (when the mission is not running).
pub static RELOAD: Signal<Cs, ()> = Signal::new();

/// The job task is loading the planner (a description received, or new parameters) and has
/// not offered the result to the control task yet: a start now would fly the mission the
/// planner no longer matches, so the control task refuses it as temporarily rejected. Set
/// before the job task looks at the mission's state, cleared after the offer; the control
/// step runs whole between two of the job task's instructions, so it sees either the mission
/// not yet started (and the job task then skips the reload) or the flag.
pub static LOADING: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(false);

pub use onboard::payload_loading::LoadedPayload;
/// A job for the thread-mode task, numbered by the control task.
pub static JOB_REQUESTS: Channel<Cs, (u32, autonomy::JobRequest), 1> = Channel::new();
/// Results of jobs, with their numbers.
pub static JOB_RESULTS: Channel<Cs, (u32, autonomy::JobResult), 2> = Channel::new();
/// Replies, texts and values for the link, in order (docs/ground-link.md#under-a-flood): sent
/// after a control step's messages and the heartbeat, within the link's rate. The receive task
/// never waits for room: a reply that finds it full is dropped and counted.
pub static OUTBOX: Channel<Cs, comms::Outbound, 4> = Channel::new();
/// A control step's messages (in HIL the lockstep reply), sent before anything else.
pub static STEP_OUT: Channel<Cs, comms::StepMessages, 1> = Channel::new();
/// Bulk transfers' messages (FTP, mission items, logs), sent when nothing else waits and the
/// link has room.
pub static BULK: Channel<Cs, comms::Bulk, 2> = Channel::new();
/// What the receive and send tasks share besides their queues: the parameters in force, the
/// parameter lists in flight and the link's drop counts.
pub static LINK: Mutex<Cs, core::cell::RefCell<comms::LinkShared>> =
    Mutex::new(core::cell::RefCell::new(comms::LinkShared::START));
/// A parameter list was asked for: the send task looks at [`LINK`]'s lists.
pub static LIST_STARTED: Signal<Cs, ()> = Signal::new();

/// The vehicle's state after the last control step, for telemetry.
pub static VEHICLE: Mutex<Cs, Cell<VehicleSnapshot>> =
    Mutex::new(Cell::new(VehicleSnapshot::START));
/// When each telemetry stream is next due (the send task sends them; the receive task sets
/// their rates from `MAV_CMD_SET_MESSAGE_INTERVAL`), on the board's clock
/// (`embassy_time::Instant`, us).
pub static TELEMETRY: Mutex<Cs, Cell<Schedule>> = Mutex::new(Cell::new(Schedule::new()));

/// Changes the value kept in `cell` with `change` (a copy taken and put back in one critical
/// section), returning what `change` returns.
fn update<T: Copy, R>(cell: &Mutex<Cs, Cell<T>>, change: impl FnOnce(&mut T) -> R) -> R {
    cell.lock(|cell| {
        let mut value = cell.get();
        let result = change(&mut value);
        cell.set(value);
        result
    })
}

/// Changes the telemetry schedule with `change`, returning what it returns.
pub fn telemetry<R>(change: impl FnOnce(&mut Schedule) -> R) -> R {
    update(&TELEMETRY, change)
}
/// The telemetry schedule changed: the send task looks at it again.
pub static TELEMETRY_CHANGED: Signal<Cs, ()> = Signal::new();

/// The estimate of the motion-capture computer's clock (`TIMESYNC`): the send task sends the
/// requests, the receive task takes the answers and stamps the fixes.
pub static TIMESYNC: Mutex<Cs, Cell<TimeSync>> = Mutex::new(Cell::new(TimeSync::new()));

/// Changes the time synchronisation with `change`, returning what it returns.
pub fn timesync<R>(change: impl FnOnce(&mut TimeSync) -> R) -> R {
    update(&TIMESYNC, change)
}

/// MAVLink 2 signing: the key, the vehicle's timestamp, the streams heard. Only the two link
/// tasks use it, and they run on one executor and never preempt each other, so a copy taken,
/// changed (a signature computed outside the critical section) and put back is never stale.
pub static SIGNING: Mutex<Cs, Cell<Signing>> = Mutex::new(Cell::new(Signing::new()));

/// Changes the signing state with `change` (from a link task only), returning what it returns.
pub fn signing<R>(change: impl FnOnce(&mut Signing) -> R) -> R {
    let mut state = SIGNING.lock(|cell| cell.get());
    let result = change(&mut state);
    SIGNING.lock(|cell| cell.set(state));
    result
}

/// The mission state as last reported by the control task (for the heartbeat).
pub static MISSION_STATE: AtomicU8 = AtomicU8::new(0);
/// Whether the vehicle is armed (for the heartbeat).
pub static ARMED: AtomicBool = AtomicBool::new(false);
/// Whether the vehicle runs in hardware-in-the-loop (a `HIL_SENSOR` has arrived).
pub static IN_HIL: AtomicBool = AtomicBool::new(false);

/// A ground station's heartbeat arrived since the control task last looked (it takes it).
pub static GCS_HEARTBEAT: AtomicBool = AtomicBool::new(false);
/// The newest joystick input (`MANUAL_CONTROL`), checked by the link's service, for the
/// control task (docs/hardware.md#rc-receivers: the mission does not fly it yet).
pub static MANUAL: Signal<Cs, shared::manual::ManualInput> = Signal::new();
/// The newest manual input of the RC receiver (docs/hardware.md#rc-receivers), from the
/// receiver task for the control step: one sample per channel frame that is not in failsafe.
pub static RC_INPUT: Signal<Cs, shared::manual::ManualInput> = Signal::new();
/// The RC receiver's last frame and counts, for the ground station (`RC_CHANNELS`,
/// `SYS_STATUS`).
pub static RC_STATUS: Mutex<Cs, Cell<link::telemetry::RcStatus>> =
    Mutex::new(Cell::new(link::telemetry::RcStatus::NONE));
/// The pack voltage the HIL plant last sent (`BATTERY_STATUS`), mV; `u32::MAX`: none yet.
/// Taken only in HIL: on a board the pack is measured by its own ADC.
pub static LINK_BATTERY_MV: AtomicU32 = AtomicU32::new(u32::MAX);
/// The rotors' RPM the HIL plant last sent (`ESC_STATUS`, docs/firmware.md#esc-telemetry).
/// Taken only in HIL: on a board the ESCs answer over bidirectional DShot.
pub static LINK_ESC_RPM: Mutex<Cs, core::cell::RefCell<link::esc::EscRpmInbox>> =
    Mutex::new(core::cell::RefCell::new(link::esc::EscRpmInbox::new()));
/// Each rotor's RPM of the last control step that had any, for the ground station
/// (`ESC_STATUS`, `ESC_INFO`); `None` once a step has none.
pub static ESC_RPM: Mutex<Cs, Cell<Option<shared::mission::EscRpm>>> = Mutex::new(Cell::new(None));

/// The thread-mode wake-up interrupt fired since the executor last looked.
static THREAD_WOKEN: AtomicBool = AtomicBool::new(false);

/// Counts of the board's cycle counter the processor spent asleep (`WFI`) since the control
/// task last took them: the rest of the time it was busy.
pub static IDLE_COUNTS: AtomicU32 = AtomicU32::new(0);

/// Called by the board's thread-wake interrupt handler.
pub fn thread_woken() {
    THREAD_WOKEN.store(true, Ordering::Release);
}

static THREAD_EXECUTOR: StaticCell<raw::Executor> = StaticCell::new();
/// Built at start ([`autonomy::Autonomy::new`]): a constant initialiser would keep its 18 KB
/// image in flash.
static AUTONOMY: StaticCell<autonomy::Autonomy> = StaticCell::new();

/// Starts the application on a board that is up; `control_tasks` spawns the board's tasks
/// that run at the control priority (sensors, ESCs; first spawner) and on the link executor
/// (its link's own tasks; second), `board_tasks` its thread-mode tasks (status LEDs). Never
/// returns: thread mode then runs the jobs.
pub fn run(
    parts: Parts<Selected>,
    control_tasks: impl FnOnce(SendSpawner, SendSpawner),
    board_tasks: impl FnOnce(Spawner),
) -> ! {
    let Parts {
        link_rx,
        link_tx,
        outputs,
        param_flash,
        log_storage,
        rc_serial,
        irqs,
    } = parts;

    // Before any task runs: the link reports the log storage from its first SYS_STATUS.
    let keeps_logs = <Selected as crate::board::Board>::keeps_logs();
    logger::LOGGING.store(keeps_logs, Ordering::Relaxed);

    let control = CONTROL_EXECUTOR.start(irqs.control);
    let autonomy = AUTONOMY.init_with(autonomy::Autonomy::new);
    match control::control(autonomy, outputs) {
        Ok(token) => control.spawn(token),
        Err(_) => panic!("control task not spawned"),
    }

    let comms_spawner = LINK_EXECUTOR.start(irqs.link);
    match comms::receive(link_rx, param_flash) {
        Ok(token) => comms_spawner.spawn(token),
        Err(_) => panic!("link receive task not spawned"),
    }
    match comms::send(link_tx) {
        Ok(token) => comms_spawner.spawn(token),
        Err(_) => panic!("link send task not spawned"),
    }
    // Below the control step, beside the link: a frame waits for neither the step nor a job.
    match rc::rc_receiver(rc_serial) {
        Ok(token) => comms_spawner.spawn(token),
        Err(_) => panic!("RC receiver task not spawned"),
    }
    control_tasks(control, comms_spawner);

    // Thread mode: a raw executor whose pender pends the board's wake-up interrupt, so `WFI`
    // (not `WFE`, which QEMU does not halt on under -icount) wakes when a job is woken.
    use cortex_m::interrupt::InterruptNumber;
    let executor = THREAD_EXECUTOR.init(raw::Executor::new(
        usize::from(irqs.thread_wake.number()) as *mut ()
    ));
    let spawner = executor.spawner();
    match jobs::jobs() {
        Ok(token) => spawner.spawn(token),
        Err(_) => panic!("job task not spawned"),
    }
    if keeps_logs {
        match logger::logger(log_storage) {
            Ok(token) => spawner.spawn(token),
            Err(_) => panic!("logger task not spawned"),
        }
    }
    board_tasks(spawner);
    loop {
        // SAFETY: polled from thread mode only, never re-entrantly.
        unsafe { executor.poll() };
        cortex_m::interrupt::free(|_| {
            // A wake-up between the poll and here has set the flag; one after is pending and
            // ends the WFI at once.
            if !THREAD_WOKEN.swap(false, Ordering::Acquire) {
                // Interrupts wait until the critical section ends: this is the sleep alone.
                let asleep = <Selected as crate::board::Board>::cycle_count();
                cortex_m::asm::wfi();
                let woke = <Selected as crate::board::Board>::cycle_count();
                IDLE_COUNTS.fetch_add(woke.wrapping_sub(asleep), Ordering::Relaxed);
            }
        });
    }
}
