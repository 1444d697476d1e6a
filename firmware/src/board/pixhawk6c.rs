//! The Pixhawk 6C-class board: clock tree, pins, the MAVLink link, the executors' interrupts.
//!
//! Checked against the PX4 board files for fmu-v6c (`nuttx-config/include/board.h`,
//! `src/board_config.h`, `src/hw_config.h`):
//! - MCU: STM32H743II (Cortex-M7, 2 MiB flash, 1 MiB RAM), application at 0x0802_0000 behind
//!   the 128 KiB PX4 bootloader (see `memory.x`).
//! - Crystal: 16 MHz HSE. PLL1: 16 MHz / 1 x 60 = 960 MHz VCO; P / 2 = 480 MHz core clock
//!   (voltage scale 0), Q / 4 = 240 MHz for kernel clocks. AHB 240 MHz, APB1..4 120 MHz.
//! - LEDs: red on PD10, blue on PD11, both active low (anodes on 3.3 V).
//! - TIM1, TIM4, TIM5 drive the eight FMU PWM outputs, TIM3 the buzzer and TIM17 the IMU
//!   heater; the time driver therefore takes TIM2, which the board leaves free.
//! - TELEM1 is UART7 (TX PE8, RX PE7): the MAVLink link for now, at [`LINK_BAUD`] (a HIL
//!   bench uses a USB-serial adapter on TELEM1). The HIL link over the board's USB (CDC-ACM)
//!   comes with the USB driver in a later issue.
//! - Parameters: the 32 KiB FRAM on SPI2 (SCK PD3, MISO PC2, MOSI PC3, chip select PD4;
//!   `board.h` "SPI2 is FRAM", `spi.cpp` `SPIDEV_FLASH(0)`), see [`super::fram`] (polled).
//! - Executors on interrupt lines the board does not use: SPDIF_RX (control), CEC (link),
//!   JPEG (thread-mode wake-up).
//!
//! TODO(drivers issue): the IMU (ICM-42688-P on SPI) feeding the control task, the ESC outputs
//! and the steppers. Until then [`Outputs`] keeps everything off and the control task runs
//! only in hardware-in-the-loop.

use defmt_rtt as _;
use embassy_executor::Spawner;
use embassy_stm32::gpio::{Level, Output, Speed};
use embassy_stm32::interrupt::{Interrupt, InterruptExt, Priority};
use embassy_stm32::rcc::{
    AHBPrescaler, APBPrescaler, Hse, HseMode, Pll, PllDiv, PllMul, PllPreDiv, PllSource, Sysclk,
    VoltageScale,
};
use embassy_stm32::spi::{self, Spi};
use embassy_stm32::time::Hertz;
use embassy_stm32::usart::{self, BufferedUart, BufferedUartRx, BufferedUartTx};
use embassy_stm32::{Config, bind_interrupts, interrupt, peripherals};
use embassy_time::{Duration, Ticker};
use panic_probe as _;
use static_cell::StaticCell;

use super::{ActuatorOutputs, Board, ExecutorIrqs, Parts};

/// Frequency of the board's HSE crystal.
pub const HSE_HZ: u32 = 16_000_000;
/// Core clock the configuration below produces.
pub const CORE_HZ: u32 = 480_000_000;
/// Baud rate of the MAVLink link on TELEM1.
pub const LINK_BAUD: u32 = 921_600;

/// The board.
pub struct Pixhawk6c;

/// The rotor and stepper outputs. TODO(drivers issue): ESCs and steppers; all off until then.
pub struct Outputs;

impl ActuatorOutputs for Outputs {
    fn apply(&mut self, _thrust: &[f32], _rail: &[f32], _armed: bool) {}
}

impl Board for Pixhawk6c {
    const NAME: &'static str = "pixhawk6c";
    const TICK_COST_NAME: &'static str = "tick_cyc";
    const TICK_COST_PER_COUNT: u32 = 1;
    type LinkRx = BufferedUartRx<'static>;
    type LinkTx = BufferedUartTx<'static>;
    type Outputs = Outputs;
    type Irq = Interrupt;
    type ParamFlash = super::fram::Fram;
    /// The first 8 KiB of the FRAM: eight pages, room for every parameter many times over
    /// (the rest stays free for the payload description).
    const PARAM_RANGE: core::ops::Range<u32> = 0..(8 * super::fram::PAGE) as u32;
    const PARAM_FLASH_PERSISTENT: bool = true;

    fn cycle_count() -> u32 {
        cortex_m::peripheral::DWT::cycle_count()
    }
}

/// Clock configuration for 480 MHz from the 16 MHz crystal, as PX4 runs this board.
pub fn clock_config() -> Config {
    let mut config = Config::default();
    let rcc = &mut config.rcc;
    rcc.hse = Some(Hse {
        freq: Hertz(HSE_HZ),
        mode: HseMode::Oscillator,
    });
    rcc.pll1 = Some(Pll {
        source: PllSource::HSE,
        prediv: PllPreDiv::DIV1,
        mul: PllMul::MUL60,
        fracn: None,
        divp: Some(PllDiv::DIV2), // 480 MHz system clock
        divq: Some(PllDiv::DIV4), // 240 MHz (SDMMC, SPI kernel clocks)
        divr: None,
    });
    rcc.sys = Sysclk::PLL1_P;
    rcc.d1c_pre = AHBPrescaler::DIV1; // CPU 480 MHz
    rcc.ahb_pre = AHBPrescaler::DIV2; // 240 MHz
    rcc.apb1_pre = APBPrescaler::DIV2; // 120 MHz
    rcc.apb2_pre = APBPrescaler::DIV2;
    rcc.apb3_pre = APBPrescaler::DIV2;
    rcc.apb4_pre = APBPrescaler::DIV2;
    rcc.voltage_scale = VoltageScale::Scale0; // required above 400 MHz
    config
}

/// The board's status LEDs.
pub struct Leds {
    /// Red LED (PD10): faults.
    pub red: Output<'static>,
    /// Blue LED (PD11): heartbeat.
    pub blue: Output<'static>,
}

bind_interrupts!(struct LinkIrqs {
    UART7 => usart::BufferedInterruptHandler<peripherals::UART7>;
});

/// SPI clock of the FRAM: 10 MHz, well inside the part's 40 MHz.
const FRAM_SPI_HZ: u32 = 10_000_000;

static LINK_TX_BUFFER: StaticCell<[u8; 2048]> = StaticCell::new();
static LINK_RX_BUFFER: StaticCell<[u8; 1024]> = StaticCell::new();

/// Brings the clocks up, claims the pins, opens the link; returns what the application takes
/// and the LEDs.
pub fn init() -> (Parts<Pixhawk6c>, Leds) {
    let p = embassy_stm32::init(clock_config());
    if let Some(mut core) = cortex_m::Peripherals::take() {
        core.DCB.enable_trace();
        core.DWT.enable_cycle_counter();
    }
    defmt::info!(
        "flight controller up: core {} MHz from a {} MHz crystal",
        CORE_HZ / 1_000_000,
        HSE_HZ / 1_000_000
    );
    // Active low: High is off.
    let leds = Leds {
        red: Output::new(p.PD10, Level::High, Speed::Low),
        blue: Output::new(p.PD11, Level::High, Speed::Low),
    };
    let mut config = usart::Config::default();
    config.baudrate = LINK_BAUD;
    let uart = match BufferedUart::new(
        p.UART7,
        p.PE7,
        p.PE8,
        LINK_TX_BUFFER.init([0; 2048]),
        LINK_RX_BUFFER.init([0; 1024]),
        LinkIrqs,
        config,
    ) {
        Ok(uart) => uart,
        Err(e) => panic!("TELEM1 (UART7) configuration refused: {:?}", e),
    };
    let (link_tx, link_rx) = uart.split();

    let mut spi_config = spi::Config::default();
    spi_config.frequency = Hertz(FRAM_SPI_HZ);
    let fram_spi = Spi::new_blocking(p.SPI2, p.PD3, p.PC3, p.PC2, spi_config);
    let fram = super::fram::Fram::new(fram_spi, Output::new(p.PD4, Level::High, Speed::High));

    interrupt::SPDIF_RX.set_priority(Priority::P2);
    interrupt::CEC.set_priority(Priority::P3);
    interrupt::JPEG.set_priority(Priority::P15);
    // SAFETY: its handler below only raises the thread-mode wake-up flag.
    unsafe { interrupt::JPEG.enable() };
    let parts = Parts {
        link_rx,
        link_tx,
        outputs: Outputs,
        param_flash: fram,
        irqs: ExecutorIrqs {
            control: Interrupt::SPDIF_RX,
            link: Interrupt::CEC,
            thread_wake: Interrupt::JPEG,
        },
    };
    (parts, leds)
}

#[interrupt]
unsafe fn SPDIF_RX() {
    // SAFETY: the control executor's own interrupt, started by the application.
    unsafe { crate::app::CONTROL_EXECUTOR.on_interrupt() }
}

#[interrupt]
unsafe fn CEC() {
    // SAFETY: the link executor's own interrupt, started by the application.
    unsafe { crate::app::LINK_EXECUTOR.on_interrupt() }
}

#[interrupt]
fn JPEG() {
    crate::app::thread_woken();
}

/// Spawns the board's own tasks (the heartbeat LED) in thread mode.
pub fn spawn_tasks(spawner: Spawner, leds: Leds) {
    let Leds { red: _red, blue } = leds;
    match heartbeat(blue) {
        Ok(token) => spawner.spawn(token),
        Err(e) => defmt::error!("heartbeat task not spawned: {}", e),
    }
}

/// Blinks `led` (active low) 100 ms on, 900 ms off, forever: the executor runs.
#[embassy_executor::task]
async fn heartbeat(mut led: Output<'static>) {
    let mut ticker = Ticker::every(Duration::from_millis(100));
    loop {
        for tenth in 0..10u8 {
            if tenth == 0 {
                led.set_low();
            } else {
                led.set_high();
            }
            ticker.next().await;
        }
    }
}
