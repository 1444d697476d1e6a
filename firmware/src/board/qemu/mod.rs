//! QEMU's `mps2-an500` board: a Cortex-M7 (Arm AN500 FPGA image on the MPS2 board) with
//! CMSDK APB peripherals, as QEMU 7.2 models it. The HIL target the tests and CI fly: no
//! embassy-stm32 here (only one embassy time driver can be linked).
//!
//! Memory (`memory.x`'s QEMU regions): 4 MiB SSRAM at 0x0000_0000 for code, 4 MiB at 0x2000_0000
//! for data. Peripherals (AN500 and QEMU's `hw/arm/mps2.c`), all clocked at 25 MHz:
//!
//! | peripheral | address | interrupt |
//! |---|---|---|
//! | CMSDK timer 0: the free-running clock ([`time_driver`]) | 0x4000_0000 | 8 |
//! | CMSDK timer 1: the alarm ([`time_driver`]) | 0x4000_1000 | 9 |
//! | CMSDK UART 0: the MAVLink link by default ([`uart`]; QEMU's `-serial`) | 0x4000_4000 | RX 0, TX 1 |
//! | CMSDK UART 1: the RC receiver ([`rc_uart`]; QEMU's second `-serial`) | 0x4000_5000 | RX 2 |
//! | LAN9118 Ethernet: the MAVLink link with `-append hil-link=ethernet` ([`ethernet`], [`link`]) | 0xA000_0000 | 13 |
//! | the parameters' flash: a host file over semihosting ([`flash`]) | - | - |
//! | the flight logs: host files over semihosting ([`logs`]) | - | - |
//! | executors: control, link, thread wake-up (unused lines) | - | 24, 25, 26 |
//!
//! Under `qemu-system-arm -icount shift=0` every instruction advances the virtual clock by
//! 1 ns, so the 25 MHz timer counts one per 40 instructions: [`QemuMps2An500::cycle_count`]
//! measures the control tick in instructions. The thread-mode executor sleeps with `WFI`
//! (QEMU does not halt on `WFE` under `-icount`).

pub mod ethernet;
pub mod flash;
pub mod link;
pub mod logs;
pub mod rc_uart;
pub mod time_driver;
pub mod uart;

use cortex_m::interrupt::InterruptNumber;
use cortex_m::peripheral::NVIC;

use super::{ActuatorOutputs, Board, ExecutorIrqs, Parts};

/// The board.
pub struct QemuMps2An500;

/// Interrupt lines of the mps2-an500 this firmware uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u16)]
pub enum Irq {
    /// UART 0 received a byte.
    Uart0Rx = 0,
    /// UART 0 sent a byte.
    Uart0Tx = 1,
    /// UART 1 (the RC receiver) received a byte.
    Uart1Rx = 2,
    /// Timer 0 wrapped.
    Timer0 = 8,
    /// Timer 1 reached zero.
    Timer1 = 9,
    /// The Ethernet controller received a frame.
    Ethernet = 13,
    /// Control executor (no peripheral on this line).
    ControlExecutor = 24,
    /// Link executor (no peripheral on this line).
    LinkExecutor = 25,
    /// Thread-mode wake-up (no peripheral on this line).
    ThreadWake = 26,
}

// SAFETY: the numbers are interrupt lines of the mps2-an500 (it has 32).
unsafe impl InterruptNumber for Irq {
    fn number(self) -> u16 {
        self as u16
    }
}

/// NVIC priorities (upper bits; smaller is more urgent): the control executor first, then
/// byte I/O and time, then the link's executor, then the thread-mode wake-up.
///
/// The control step comes before the I/O interrupts here (on the Pixhawk 6C they come first):
/// its instruction count ([`QemuMps2An500::cycle_count`]) is then the step's alone, the same
/// however the host's load places QEMU's timer alarms and received frames against it. An
/// interrupt waits for the step's end, some 11 us of the guest's time; the UART's one
/// received byte is not lost meanwhile (QEMU hands the next only once it is read).
const PRIO_CONTROL: u8 = 0x20;
const PRIO_IO: u8 = 0x40;
const PRIO_LINK: u8 = 0x60;
const PRIO_THREAD_WAKE: u8 = 0xE0;

/// No physical outputs on the emulated board: in HIL the commands go to the plant over the
/// link.
pub struct NoOutputs;

impl ActuatorOutputs for NoOutputs {
    fn apply(&mut self, _thrust: &[f32], _rail: &[f32], _armed: bool) {}
}

/// The link chosen at start is the Ethernet controller (not the UART).
static LINK_IS_ETHERNET: core::sync::atomic::AtomicBool =
    core::sync::atomic::AtomicBool::new(false);

impl Board for QemuMps2An500 {
    const NAME: &'static str = "qemu-mps2-an500";

    /// Every robot the link carries, or fewer when QEMU's command line says `max-robots=N`
    /// (`host-sim hil --max-robots`): a board that drives fewer, whose refusals the tests fly.
    fn drives() -> shared::mission::drives::BoardDrives {
        use core::sync::atomic::{AtomicU8, Ordering};
        use shared::mission::drives::QEMU_MPS2_AN500;
        // Read once (a semihosting call); 0: not read yet.
        static MAX_ROBOTS: AtomicU8 = AtomicU8::new(0);
        let mut most = MAX_ROBOTS.load(Ordering::Relaxed);
        if most == 0 {
            let all = QEMU_MPS2_AN500.steppers;
            most = link::command_line_number(b"max-robots=")
                .map_or(all, |n| n.clamp(1, u32::from(all)) as u8);
            MAX_ROBOTS.store(most, Ordering::Relaxed);
        }
        QEMU_MPS2_AN500.at_most(most)
    }
    const TICK_COST_NAME: &'static str = "tick_insn";
    const BUSY_COST_NAME: &'static str = "busy_insn";

    /// Its UART stands for the bench's wired link (the Pixhawk's USB).
    fn key_setup_allowed() -> bool {
        true
    }

    /// The LAN9118's 100 Mbit/s; the UART as TELEM1's 921,600 baud.
    fn link_rate() -> u32 {
        if LINK_IS_ETHERNET.load(core::sync::atomic::Ordering::Relaxed) {
            12_500_000
        } else {
            ::link::bandwidth::bytes_per_second(921_600)
        }
    }
    const TICK_COST_PER_COUNT: u32 = 40;
    /// `-icount shift=0`: one instruction per virtual nanosecond.
    const TICK_PERIOD_COST: u32 = 2_500_000;
    type LinkRx = link::LinkRx;
    type LinkTx = link::LinkTx;
    type Outputs = NoOutputs;
    type Irq = Irq;
    type ParamFlash = flash::FileFlash;
    type LogStorage = logs::LogFiles;
    type RcSerial = rc_uart::RcUart;
    const LOG_RING_BYTES: usize = 64 * 1024;

    /// Only when QEMU's command line asks for it (`flight-log=on`: `host-sim hil --storage`
    /// adds it): the log's recording still costs the control step about 10,000 instructions
    /// at its busiest (docs/formats.md#flight-logs), past the step's budget.
    fn keeps_logs() -> bool {
        link::command_line_has(b"flight-log=on")
    }
    const PARAM_RANGE: core::ops::Range<u32> = 0..(flash::PAGE * flash::PARAM_PAGES) as u32;
    /// The two pages after the parameters'.
    const PAYLOAD_RANGE: core::ops::Range<u32> =
        (flash::PAGE * flash::PARAM_PAGES) as u32..(flash::PAGE * (flash::PARAM_PAGES + 2)) as u32;
    /// The last two pages.
    const MISSION_RANGE: core::ops::Range<u32> =
        (flash::PAGE * (flash::PARAM_PAGES + 2)) as u32..(flash::PAGE * flash::PAGES) as u32;
    const PARAM_FLASH_PERSISTENT: bool = true;

    fn cycle_count() -> u32 {
        time_driver::raw_count()
    }
}

/// Brings the board up: timers, the link, the RC receiver's UART, interrupt priorities.
pub fn init() -> Parts<QemuMps2An500> {
    let Some(mut p) = cortex_m::Peripherals::take() else {
        // Only reachable if called twice; the firmware calls it once from its entry.
        panic!("board::qemu::init called twice");
    };
    // SAFETY: priorities are set before the interrupts are unmasked, on one core.
    unsafe {
        p.NVIC.set_priority(Irq::Uart0Rx, PRIO_IO);
        p.NVIC.set_priority(Irq::Uart0Tx, PRIO_IO);
        p.NVIC.set_priority(Irq::Uart1Rx, PRIO_IO);
        p.NVIC.set_priority(Irq::Timer0, PRIO_IO);
        p.NVIC.set_priority(Irq::Timer1, PRIO_IO);
        p.NVIC.set_priority(Irq::Ethernet, PRIO_IO);
        p.NVIC.set_priority(Irq::ControlExecutor, PRIO_CONTROL);
        p.NVIC.set_priority(Irq::LinkExecutor, PRIO_LINK);
        p.NVIC.set_priority(Irq::ThreadWake, PRIO_THREAD_WAKE);
    }
    time_driver::init();
    let (link_rx, link_tx, ethernet) = link::init();
    LINK_IS_ETHERNET.store(ethernet, core::sync::atomic::Ordering::Relaxed);
    let rc_serial = rc_uart::RcUart::init();
    // SAFETY: the handlers of these lines are in the vector table below.
    unsafe {
        NVIC::unmask(Irq::Timer0);
        NVIC::unmask(Irq::Timer1);
        if ethernet {
            NVIC::unmask(Irq::Ethernet);
        } else {
            NVIC::unmask(Irq::Uart0Rx);
            NVIC::unmask(Irq::Uart0Tx);
        }
        NVIC::unmask(Irq::ThreadWake);
        NVIC::unmask(Irq::Uart1Rx);
    }
    Parts {
        link_rx,
        link_tx,
        outputs: NoOutputs,
        param_flash: flash::FileFlash::open(),
        log_storage: logs::LogFiles::new(),
        rc_serial,
        irqs: ExecutorIrqs {
            control: Irq::ControlExecutor,
            link: Irq::LinkExecutor,
            thread_wake: Irq::ThreadWake,
        },
    }
}

/// One entry of the device part of the vector table.
#[repr(C)]
pub union Vector {
    handler: unsafe extern "C" fn(),
    reserved: usize,
}

unsafe extern "C" fn control_executor() {
    // SAFETY: the control executor's own interrupt, started by the application.
    unsafe { crate::app::CONTROL_EXECUTOR.on_interrupt() }
}

unsafe extern "C" fn link_executor() {
    // SAFETY: the link executor's own interrupt, started by the application.
    unsafe { crate::app::LINK_EXECUTOR.on_interrupt() }
}

unsafe extern "C" fn thread_wake() {
    crate::app::thread_woken();
}

unsafe extern "C" fn default_handler() {}

const NONE: Vector = Vector {
    handler: default_handler,
};

/// The mps2-an500's 32 device interrupts (cortex-m-rt's `device` feature places this after
/// the exceptions).
#[unsafe(link_section = ".vector_table.interrupts")]
#[unsafe(no_mangle)]
pub static __INTERRUPTS: [Vector; 32] = {
    let mut v = [NONE; 32];
    v[Irq::Uart0Rx as usize] = Vector {
        handler: uart::on_rx_interrupt,
    };
    v[Irq::Uart0Tx as usize] = Vector {
        handler: uart::on_tx_interrupt,
    };
    v[Irq::Uart1Rx as usize] = Vector {
        handler: rc_uart::on_rx_interrupt,
    };
    v[Irq::Ethernet as usize] = Vector {
        handler: ethernet::on_interrupt,
    };
    v[Irq::Timer0 as usize] = Vector {
        handler: time_driver::on_timer0_interrupt,
    };
    v[Irq::Timer1 as usize] = Vector {
        handler: time_driver::on_timer1_interrupt,
    };
    v[Irq::ControlExecutor as usize] = Vector {
        handler: control_executor,
    };
    v[Irq::LinkExecutor as usize] = Vector {
        handler: link_executor,
    };
    v[Irq::ThreadWake as usize] = Vector {
        handler: thread_wake,
    };
    v
};

/// Stops QEMU with a failure status after printing `message` on the host's terminal
/// (semihosting): how a panic ends an emulated run.
pub fn fail(message: core::fmt::Arguments<'_>) -> ! {
    cortex_m_semihosting::hprintln!("firmware panicked: {}", message);
    cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
    cortex_m::interrupt::disable();
    fail(format_args!("{info}"))
}
