//! The boards the application runs on, and the small interface each one gives it. One board per
//! build, chosen by cargo feature:
//!
//! | feature | board | binary |
//! |---|---|---|
//! | `pixhawk6c` | Pixhawk 6C, STM32H743 with embassy-stm32 ([`pixhawk6c`]) | `firmware` (`cargo fw`) |
//! | `qemu` | QEMU's mps2-an500 Cortex-M7 ([`qemu`]) | `firmware-qemu` (`cargo fw-qemu`) |
//!
//! A board brings up its clocks and pins, gives the application its MAVLink link as an
//! `embedded-io-async` byte stream, its actuator outputs, a cycle counter for the tick's cost,
//! a flash for the parameters, the RC receiver's serial port, and three spare interrupts for the executors (control, link, thread-mode wake-up) with their
//! priorities set. Everything else is the application's ([`crate::app`]).

use cortex_m::interrupt::InterruptNumber;

#[cfg(all(feature = "pixhawk6c", feature = "qemu"))]
compile_error!("firmware: choose one board feature, `pixhawk6c` or `qemu`, not both");
#[cfg(not(any(feature = "pixhawk6c", feature = "qemu")))]
compile_error!(
    "firmware: choose a board feature: `pixhawk6c` (cargo fw) or `qemu` (cargo fw-qemu)"
);

#[cfg(feature = "pixhawk6c")]
pub mod pixhawk6c;
#[cfg(feature = "pixhawk6c")]
pub use pixhawk6c::Pixhawk6c as Selected;

#[cfg(feature = "pixhawk6c")]
pub mod can_escs;
#[cfg(feature = "pixhawk6c")]
pub mod escs;
#[cfg(feature = "pixhawk6c")]
pub mod fram;
#[cfg(feature = "pixhawk6c")]
pub mod imu_spi;
#[cfg(feature = "qemu")]
pub mod qemu;
#[cfg(feature = "pixhawk6c")]
pub mod rc_serial;
#[cfg(feature = "pixhawk6c")]
pub mod sdcard;
#[cfg(feature = "pixhawk6c")]
pub mod steppers;
#[cfg(feature = "pixhawk6c")]
pub mod usb_link;
#[cfg(feature = "qemu")]
pub use qemu::QemuMps2An500 as Selected;

/// What a board provides to the application.
pub trait Board: 'static {
    /// The board's name, as the firmware reports it (`STATUSTEXT` "board: NAME").
    const NAME: &'static str;
    /// Name of the `NAMED_VALUE_INT` carrying the worst control tick's cost, and its unit.
    const TICK_COST_NAME: &'static str;
    /// Name of the named value that carries the processor's busy time, in the units of
    /// [`Board::TICK_COST_NAME`], over each second of vehicle time (`busy_insn` under QEMU,
    /// `busy_cyc` on a board): its CPU load, and in HIL the guest's instructions per step.
    const BUSY_COST_NAME: &'static str;
    /// Units of [`Board::TICK_COST_NAME`] per count of [`Board::cycle_count`].
    const TICK_COST_PER_COUNT: u32;
    /// A whole control period (2.5 ms) in units of [`Board::TICK_COST_NAME`]: the control
    /// loop's load in `SYS_STATUS` is the worst step's share of it.
    const TICK_PERIOD_COST: u32;

    /// The link's receiving half.
    type LinkRx: embedded_io_async::Read + Send + 'static;
    /// The link's sending half.
    type LinkTx: embedded_io_async::Write + Send + 'static;
    /// The rotor and stepper outputs.
    type Outputs: ActuatorOutputs + Send + 'static;
    /// An interrupt line.
    type Irq: InterruptNumber;
    /// The NOR flash (or flash-like memory) the parameters are stored on.
    type ParamFlash: embedded_storage_async::nor_flash::NorFlash + Send + 'static;
    /// The part of [`Board::ParamFlash`] the parameters use: whole erase pages, at least two.
    const PARAM_RANGE: core::ops::Range<u32>;
    /// Whether [`Board::ParamFlash`] keeps its contents over a power cycle (reported to the
    /// ground at start).
    const PARAM_FLASH_PERSISTENT: bool;
    /// Where the payload description is kept (two slots of whole erase pages, apart from
    /// [`Board::PARAM_RANGE`]).
    const PAYLOAD_RANGE: core::ops::Range<u32>;
    /// Where the mission's items are kept (two slots of whole erase pages, apart from the
    /// other two ranges).
    const MISSION_RANGE: core::ops::Range<u32>;
    /// The RC receiver's serial port (docs/hardware.md#rc-receivers).
    type RcSerial: RcSerial + Send + 'static;
    /// Where the flight logs are kept ([`NoLogStorage`] on a board without a driver for it).
    type LogStorage: flight_log::keeper::LogStorage + Send + 'static;
    /// Bytes of the ring between the control step and the logger task (0: no flight log).
    /// At 400 Hz the mission's log comes at about 91 KB/s: 64 KiB hold 0.7 s of it.
    const LOG_RING_BYTES: usize;

    /// A free-running counter (wrapping) for measuring the control tick.
    fn cycle_count() -> u32;

    /// Bytes a second the link in use carries: the send task's budget for what may wait
    /// (docs/ground-link.md#under-a-flood).
    fn link_rate() -> u32;

    /// Whether the link in use may set the signing key (`SETUP_SIGNING`): a wired link the
    /// operator plugs in by hand (the Pixhawk's USB), never a radio.
    fn key_setup_allowed() -> bool;

    /// The robots it drives: rotors for each ESC protocol, and steppers. A payload
    /// description with more robots is refused (docs/hardware.md#robots-a-board-drives).
    fn drives() -> shared::mission::drives::BoardDrives;

    /// Whether the board keeps flight logs this run (it has a ring, and storage for them).
    fn keeps_logs() -> bool {
        Self::LOG_RING_BYTES > 0
    }

    /// What the board's drivers report failed now (none on a board without drivers).
    fn hardware_faults() -> shared::mission::HardwareFaults {
        shared::mission::HardwareFaults::NONE
    }

    /// The battery pack's voltage as the board measures it now, V (`None`: the board
    /// measures none).
    fn battery_volts() -> Option<f32> {
        None
    }

    /// Each rotor's RPM from its ESC's telemetry since the last step (robot `i`'s at `i`; NaN
    /// for an ESC that did not answer), or `None` when the board reads no ESC telemetry (no
    /// bidirectional DShot, or it is switched off).
    fn esc_rpm() -> Option<shared::mission::EscRpm> {
        None
    }

    /// What the four ESCs of `ESC_STATUS` message `message` (robots `4 message + 1` on)
    /// measure beside their RPM, from CAN ESCs' `Status`; `None` when the board reads no such
    /// telemetry (DShot, PWM, HIL).
    fn esc_electrical(message: usize) -> Option<link::esc::EscElectrical> {
        let _ = message;
        None
    }
}

/// The robots' actuators: each rotor's ESC and each robot's stepper. In hardware-in-the-loop
/// the plant receives the commands over the link instead and the outputs stay disarmed.
pub trait ActuatorOutputs {
    /// Applies one control step's commands: thrust fractions `[0, 1]` and rail positions (m),
    /// one per robot; with `armed` false the rotors are stopped whatever `thrust` says.
    fn apply(&mut self, thrust: &[f32], rail: &[f32], armed: bool);
}

/// What one read of the RC receiver's port gave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RcRead {
    /// Bytes written to the start of the buffer.
    pub len: usize,
    /// The UART flagged a byte (parity, framing, noise) or lost some (overrun).
    pub line_error: bool,
    /// The line went idle after the bytes (`false` from a UART that cannot tell).
    pub idle: bool,
}

/// The serial port an RC receiver is wired to (docs/hardware.md#rc-receivers): opened on the
/// port and with the line settings the parameters ask for, then read. The board only moves
/// bytes; which protocol, which port and what the bytes mean are `drivers::rc_receiver`'s.
pub trait RcSerial {
    /// Opens `port` with `line`'s settings (baud, parity, stop bits, inversion), closing what
    /// was open; a reason when the board cannot give that port.
    fn open(
        &mut self,
        port: drivers::rc_receiver::RcPort,
        line: drivers::rc_receiver::LineSettings,
    ) -> Result<(), &'static str>;
    /// Waits for bytes from the open port and puts them in `buf`.
    fn read(&mut self, buf: &mut [u8]) -> impl core::future::Future<Output = RcRead>;
}

/// The interrupts the application's executors run on: spare lines, their priorities set by
/// the board (control above link, link above the thread-mode wake-up).
pub struct ExecutorIrqs<I> {
    /// The 400 Hz control executor (highest of the three).
    pub control: I,
    /// The link executor (MAVLink parsing, FTP, sending).
    pub link: I,
    /// Pended to wake the thread-mode executor (jobs) from `WFI`.
    pub thread_wake: I,
}

/// A board, brought up: what the application takes over.
pub struct Parts<B: Board> {
    /// The link's receiving half.
    pub link_rx: B::LinkRx,
    /// The link's sending half.
    pub link_tx: B::LinkTx,
    /// The actuator outputs.
    pub outputs: B::Outputs,
    /// The parameters' flash.
    pub param_flash: B::ParamFlash,
    /// Where the flight logs go.
    pub log_storage: B::LogStorage,
    /// The RC receiver's port.
    pub rc_serial: B::RcSerial,
    /// The executors' interrupts.
    pub irqs: ExecutorIrqs<B::Irq>,
}

/// Checks a flash access of `len` bytes at `offset` against a flash of `capacity` bytes whose
/// accesses align to `align` (as `embedded-storage`'s checks do for its blocking traits).
pub fn check_flash_access(
    offset: u32,
    len: usize,
    align: usize,
    capacity: usize,
) -> Result<(), embedded_storage_async::nor_flash::NorFlashErrorKind> {
    use embedded_storage_async::nor_flash::NorFlashErrorKind;
    let offset = offset as usize;
    if !offset.is_multiple_of(align) || !len.is_multiple_of(align) {
        return Err(NorFlashErrorKind::NotAligned);
    }
    if offset.checked_add(len).is_none_or(|end| end > capacity) {
        return Err(NorFlashErrorKind::OutOfBounds);
    }
    Ok(())
}

/// A static for the flight log's buffers, placed by the board in its log memory (the
/// Pixhawk 6C's `.log_ram` section, memory.x): memory the start-up code neither zeroes nor
/// initialises, so the static holds nothing until [`LogRam::init`] writes it. (On QEMU's board
/// it is an ordinary static.)
pub struct LogRam<T>(core::cell::UnsafeCell<core::mem::MaybeUninit<T>>);

// SAFETY: the value is reached only through the one `&'static mut` that `init` returns.
unsafe impl<T: Send> Sync for LogRam<T> {}

impl<T> LogRam<T> {
    /// Nothing written yet.
    #[allow(clippy::new_without_default)]
    pub const fn new() -> Self {
        Self(core::cell::UnsafeCell::new(core::mem::MaybeUninit::uninit()))
    }

    /// Writes `value` and returns the only reference to it.
    ///
    /// # Safety
    ///
    /// At most one call per static: a second would alias the reference the first returned.
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn init(&'static self, value: T) -> &'static mut T {
        // SAFETY: the caller calls once, so no other reference to the value exists.
        unsafe { (*self.0.get()).write(value) }
    }

    /// Writes zeros over the value (in place: no copy of it on the stack) and returns the
    /// only reference to it.
    ///
    /// # Safety
    ///
    /// At most one call per static, and all-zero bytes must be a valid `T` (integers and
    /// arrays of them).
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn init_zeroed(&'static self) -> &'static mut T {
        // SAFETY: the caller calls once (no other reference exists) and zeros are a valid `T`.
        unsafe {
            let value = (*self.0.get()).as_mut_ptr();
            core::ptr::write_bytes(value, 0, 1);
            &mut *value
        }
    }
}

/// The log storage of a board that has no driver for one yet: every operation fails, saying
/// so (the vehicle flies and keeps no log).
pub struct NoLogStorage;

/// Why [`NoLogStorage`] fails.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NoLogDriver;

impl core::fmt::Display for NoLogDriver {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("this board has no driver for its log storage yet")
    }
}

impl flight_log::keeper::LogStorage for NoLogStorage {
    type Error = NoLogDriver;
    fn count(&mut self) -> Result<u16, NoLogDriver> {
        Ok(0)
    }
    fn size(&mut self, _: u16) -> Result<u32, NoLogDriver> {
        Err(NoLogDriver)
    }
    fn create(&mut self) -> Result<u16, NoLogDriver> {
        Err(NoLogDriver)
    }
    fn append(&mut self, _: &[u8]) -> Result<(), NoLogDriver> {
        Err(NoLogDriver)
    }
    fn close(&mut self) -> Result<(), NoLogDriver> {
        Ok(())
    }
    fn read(&mut self, _: u16, _: u32, _: &mut [u8]) -> Result<usize, NoLogDriver> {
        Err(NoLogDriver)
    }
    fn erase_all(&mut self) -> Result<(), NoLogDriver> {
        Ok(())
    }
}
