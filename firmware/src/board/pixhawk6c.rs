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
//! - The MAVLink link: USB when a cable powers VBUS at start (CDC-ACM on OTG_FS, PA11/PA12,
//!   VBUS PA9; `board.h`), see [`super::usb_link`]; TELEM1 otherwise, UART7 (TX PE8, RX PE7)
//!   at [`LINK_BAUD`].
//! - Parameters: the 32 KiB FRAM on SPI2 (SCK PD3, MISO PC2, MOSI PC3, chip select PD4;
//!   `board.h` "SPI2 is FRAM", `spi.cpp` `SPIDEV_FLASH(0)`), see [`super::fram`] (polled).
//! - Executors on interrupt lines the board does not use: SPDIF_RX (control), CEC (link),
//!   JPEG (thread-mode wake-up).
//! - IMU: the ICM-42688-P on SPI1 (SCK PA5, MISO PA6, MOSI PA7; `spi.cpp`: chip select PC13,
//!   data ready PE6; sensor bus power PB2), mounted yaw 270 deg (`init/rc.board_sensors`
//!   `icm42688p -R 6`), see [`super::imu_spi`]. Its samples drive the control step. (The
//!   BMI088 on PC14/PC15, yaw 180 deg, `-R 4`, is not used.)
//! - ESCs: DShot600 (or PWM, OneShot125) on the eight FMU outputs (`timer_config.cpp`: TIM1 CH1-4 on PA8, PE11,
//!   PE13, PE14; TIM4 CH3-4 on PD14, PD15; TIM5 CH1-2 on PA0, PA1), see [`super::escs`];
//!   bidirectional DShot's answers captured through DMA2 streams 1-4 and the timers' own
//!   update streams, FMU_CH6's by TIM4's interrupt.
//! - Watchdog: the independent watchdog (IWDG1, [`WATCHDOG_TIMEOUT_US`]), started by the
//!   first control step and fed by every one after it ([`Outputs::apply`]); the reset reason
//!   (RCC_RSR) goes to the ground at start, a watchdog reset as an error.
//!
//! - Flight logs: the microSD card on SDMMC2, 4 bits (CK PD6, CMD PD7, D0-D3 PB14, PB15,
//!   PB3, PB4; `board.h`), kernel clock PLL1Q 240 MHz, 24 MHz on the bus; no card-detect
//!   line (`board_config.h` has none). See [`super::sdcard`].
//! - DroneCAN ESCs: CAN1, FDCAN1 on PD0 (RX) and PD1 (TX) (`board.h`), see [`super::can_escs`].
//! - Steppers: TMC2209s on TELEM2 (UART5, TX PC12), TELEM3 (USART2, TX PD5), GPS1 (USART1,
//!   TX PB6) and the debug port (USART3, TX PD8), half duplex, see [`super::steppers`] and
//!   docs/hardware.md#the-pixhawk-6cs-wiring.

use defmt_rtt as _;
use drivers::pulse::EscProtocol;
use drivers::reset::ResetReason;
use drivers::thrust_map::ThrustMap;
use embassy_executor::{SendSpawner, Spawner};
use embassy_stm32::exti::{self, ExtiInput};
use embassy_stm32::gpio::{Level, Output, OutputType, Pull, Speed};
use embassy_stm32::interrupt::{Interrupt, InterruptExt, Priority};
use embassy_stm32::rcc::{
    AHBPrescaler, APBPrescaler, Hse, HseMode, Pll, PllDiv, PllMul, PllPreDiv, PllSource, Sysclk,
    VoltageScale,
};
use embassy_stm32::spi::{self, Spi};
use embassy_stm32::time::Hertz;
use embassy_stm32::timer::low_level::CountingMode;
use embassy_stm32::timer::simple_pwm::{PwmPin, SimplePwm};
use embassy_stm32::usart::{self, BufferedUart, BufferedUartRx, BufferedUartTx};
use embassy_stm32::wdg::IndependentWatchdog;
use embassy_stm32::{Config, bind_interrupts, interrupt, peripherals};
use embassy_stm32::{dma, pac};
use embassy_time::{Duration, Ticker};
use panic_probe as _;
use shared::mission::{HardwareConfig, HardwareFaults};
use static_cell::{ConstStaticCell, StaticCell};

use super::{ActuatorOutputs, Board, ExecutorIrqs, Parts};

/// Frequency of the board's HSE crystal.
pub const HSE_HZ: u32 = 16_000_000;
/// Core clock the configuration below produces.
pub const CORE_HZ: u32 = 480_000_000;
/// Baud rate of the MAVLink link on TELEM1.
pub const LINK_BAUD: u32 = 921_600;

/// The board.
pub struct Pixhawk6c;

/// Timeout of the independent watchdog: 100 control steps.
pub const WATCHDOG_TIMEOUT_US: u32 = 250_000;

/// The rotor outputs ([`super::escs`]), the steppers ([`super::steppers`]) and the watchdog
/// the control step feeds.
pub struct Outputs {
    watchdog: IndependentWatchdog<'static, peripherals::IWDG1>,
    watchdog_running: bool,
    thrust_map: ThrustMap,
    protocol: EscProtocol,
    /// The parameters' hardware settings last seen, refused or taken.
    settings: HardwareConfig,
}

impl Outputs {
    /// Takes the ESC protocol and the thrust map from the parameters, while disarmed; says
    /// what it refuses.
    fn follow_parameters(&mut self, armed: bool) {
        if armed {
            return;
        }
        let settings = crate::app::MISSION_CONFIG.lock(|c| c.get().hardware);
        if settings == self.settings {
            return;
        }
        self.settings = settings;
        let refuse = |args: core::fmt::Arguments<'_>| {
            let _ = crate::app::OUTBOX.try_send(crate::app::comms::report(
                crate::app::autonomy::Severity::Error,
                args,
            ));
        };
        match ThrustMap::new(settings.thrust_map) {
            Ok(map) => self.thrust_map = map,
            Err(e) => refuse(format_args!("{e}; the previous map stays")),
        }
        match EscProtocol::from_value(i32::from(settings.esc_protocol)) {
            Ok(p) => self.protocol = p,
            Err(e) => refuse(format_args!("{e}")),
        }
        super::escs::set_telemetry(settings.dshot_bidirectional, settings.motor_poles);
        super::can_escs::set_node_id(settings.can_node_id);
    }
}

impl ActuatorOutputs for Outputs {
    fn apply(&mut self, thrust: &[f32], rail: &[f32], armed: bool) {
        if !self.watchdog_running {
            // Started by the first step, so a board whose IMU never came up stays up to say so.
            self.watchdog.unleash();
            self.watchdog_running = true;
        }
        self.watchdog.pet();
        self.follow_parameters(armed);
        let mut commands = [0.0f32; shared::scenario::MAX_ROBOTS];
        for (command, &t) in commands.iter_mut().zip(thrust) {
            *command = self.thrust_map.command(t);
        }
        let robots = thrust.len().min(commands.len());
        super::escs::command(self.protocol, &commands[..robots], armed);
        super::can_escs::command(self.protocol, &commands[..robots], armed);
        super::steppers::command(rail);
    }
}

impl Board for Pixhawk6c {
    const NAME: &'static str = "pixhawk6c";

    /// Its eight FMU outputs ([`super::escs`]) and eight steppers ([`super::steppers`]).
    fn drives() -> shared::mission::drives::BoardDrives {
        shared::mission::drives::PIXHAWK_6C
    }
    const TICK_COST_NAME: &'static str = "tick_cyc";
    const BUSY_COST_NAME: &'static str = "busy_cyc";
    const TICK_COST_PER_COUNT: u32 = 1;
    /// 2.5 ms of the 480 MHz core clock.
    const TICK_PERIOD_COST: u32 = CORE_HZ / 400;
    type LinkRx = super::usb_link::LinkRx;
    type LinkTx = super::usb_link::LinkTx;
    type Outputs = Outputs;
    type Irq = Interrupt;
    type ParamFlash = super::fram::Fram;
    type LogStorage = super::sdcard::SdStorage;
    type RcSerial = super::rc_serial::RcUart;
    /// 32 KiB, 0.35 s of the mission's log, in the log memory (memory.x) with the rest of the
    /// log's buffers.
    const LOG_RING_BYTES: usize = 32 * 1024;
    /// The first 8 KiB of the FRAM: eight pages, room for every parameter many times over
    /// (the rest stays free for the payload description).
    const PARAM_RANGE: core::ops::Range<u32> = 0..(8 * super::fram::PAGE) as u32;
    const PARAM_FLASH_PERSISTENT: bool = true;
    /// The 2 KiB after the parameters' 8 KiB of FRAM: two 1 KiB slots (a description is at
    /// most 983 bytes).
    const PAYLOAD_RANGE: core::ops::Range<u32> =
        (8 * super::fram::PAGE) as u32..(10 * super::fram::PAGE) as u32;
    /// The 2 KiB after the payload description's: two 1 KiB slots (a mission of 16 items is
    /// 522 bytes).
    const MISSION_RANGE: core::ops::Range<u32> =
        (10 * super::fram::PAGE) as u32..(12 * super::fram::PAGE) as u32;

    fn cycle_count() -> u32 {
        cortex_m::peripheral::DWT::cycle_count()
    }

    /// Over USB only: TELEM1 carries the telemetry radio.
    fn key_setup_allowed() -> bool {
        LINK_IS_USB.load(core::sync::atomic::Ordering::Relaxed)
    }

    /// USB full speed's 12 Mbit/s carries about 1 MB/s of CDC-ACM bulk transfers; TELEM1 runs
    /// at 921,600 baud.
    fn link_rate() -> u32 {
        if LINK_IS_USB.load(core::sync::atomic::Ordering::Relaxed) {
            1_000_000
        } else {
            link::bandwidth::bytes_per_second(921_600)
        }
    }

    fn battery_volts() -> Option<f32> {
        match BATTERY_MV.load(core::sync::atomic::Ordering::Relaxed) {
            u32::MAX => None,
            mv => Some(mv as f32 * 1e-3),
        }
    }

    fn hardware_faults() -> HardwareFaults {
        HardwareFaults {
            imu: super::imu_spi::FAULTED.load(core::sync::atomic::Ordering::Relaxed),
            stalled_robots: super::steppers::STALLED.load(core::sync::atomic::Ordering::Relaxed),
            // DShot ESCs' word is their RPM ([`Self::esc_rpm`]), which the rotor monitor
            // judges; a DroneCAN ESC gone silent, or saying it failed, is its rotor's failure.
            rotors_out: super::can_escs::failed(),
        }
    }

    /// The DroneCAN ESCs' voltage, current, temperature and error count from their Status.
    fn esc_electrical(message: usize) -> Option<link::esc::EscElectrical> {
        super::can_escs::electrical(message)
    }

    /// The DroneCAN ESCs' latest Status, or the answers to the latest bidirectional DShot
    /// frame (`DSHOT_BIDIR_EN` with DShot600).
    fn esc_rpm() -> Option<shared::mission::EscRpm> {
        if let Some(rpm) = super::can_escs::rpm() {
            return Some(core::array::from_fn(|i| {
                rpm.get(i).copied().unwrap_or(f32::NAN)
            }));
        }
        let rpm = super::escs::take_rpm()?;
        Some(core::array::from_fn(|i| {
            rpm.get(i).copied().unwrap_or(f32::NAN)
        }))
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
    // USB's 48 MHz from HSI48 (on by default).
    rcc.mux.usbsel = embassy_stm32::rcc::mux::Usbsel::HSI48;
    // The ADC's kernel clock from per_ck (HSI, 64 MHz; the driver divides it to its limit).
    rcc.mux.adcsel = embassy_stm32::rcc::mux::Adcsel::PER;
    // The microSD card's kernel clock: PLL1Q, 240 MHz (PX4's too).
    rcc.mux.sdmmcsel = embassy_stm32::rcc::mux::Sdmmcsel::PLL1_Q;
    // CAN1's kernel clock: the 16 MHz crystal, 16 time quanta a bit at 1 Mbit/s (the reset
    // value, named so a change of the PLLs leaves it alone).
    rcc.mux.fdcansel = embassy_stm32::rcc::mux::Fdcansel::HSE;
    config
}

/// The board's status LEDs.
pub struct Leds {
    /// Red LED (PD10): faults.
    pub red: Output<'static>,
    /// Blue LED (PD11): heartbeat.
    pub blue: Output<'static>,
    /// The power module's voltage input (POWER1 `BAT1 VOLTAGE`: PC5 on ADC1, channel 8),
    /// read with the heartbeat.
    pub battery: BatteryInput,
}

/// The power module's voltage input: ADC1 and its pin.
pub struct BatteryInput {
    adc: embassy_stm32::adc::Adc<'static, peripherals::ADC1>,
    pin: embassy_stm32::Peri<'static, peripherals::PC5>,
}

/// The pack's voltage last read, mV (`u32::MAX`: not read yet).
static BATTERY_MV: core::sync::atomic::AtomicU32 = core::sync::atomic::AtomicU32::new(u32::MAX);

impl BatteryInput {
    /// One reading (16 conversions averaged by the ADC), into [`BATTERY_MV`].
    fn read(&mut self) {
        use embassy_stm32::adc::SampleTime;
        let counts = self
            .adc
            .blocking_read(&mut self.pin, SampleTime::CYCLES64_5);
        let volts = drivers::battery::BatteryScale::PIXHAWK6C.volts(counts);
        BATTERY_MV.store(
            (volts * 1000.0) as u32,
            core::sync::atomic::Ordering::Relaxed,
        );
    }
}

bind_interrupts!(struct LinkIrqs {
    UART7 => usart::BufferedInterruptHandler<peripherals::UART7>;
});

bind_interrupts!(
    /// The DMA streams and the IMU's data-ready line.
    pub struct Irqs {
    DMA1_STREAM0 => dma::InterruptHandler<peripherals::DMA1_CH0>;
    DMA1_STREAM1 => dma::InterruptHandler<peripherals::DMA1_CH1>;
    DMA1_STREAM2 => dma::InterruptHandler<peripherals::DMA1_CH2>;
    DMA1_STREAM3 => dma::InterruptHandler<peripherals::DMA1_CH3>;
    DMA1_STREAM4 => dma::InterruptHandler<peripherals::DMA1_CH4>;
    DMA1_STREAM5 => dma::InterruptHandler<peripherals::DMA1_CH5>;
    DMA1_STREAM6 => dma::InterruptHandler<peripherals::DMA1_CH6>;
    DMA1_STREAM7 => dma::InterruptHandler<peripherals::DMA1_CH7>;
    DMA2_STREAM0 => dma::InterruptHandler<peripherals::DMA2_CH0>;
    DMA2_STREAM1 => dma::InterruptHandler<peripherals::DMA2_CH1>;
    DMA2_STREAM2 => dma::InterruptHandler<peripherals::DMA2_CH2>;
    DMA2_STREAM3 => dma::InterruptHandler<peripherals::DMA2_CH3>;
    DMA2_STREAM4 => dma::InterruptHandler<peripherals::DMA2_CH4>;
    DMA2_STREAM5 => dma::InterruptHandler<peripherals::DMA2_CH5>;
    UART8 => usart::InterruptHandler<peripherals::UART8>;
    UART5 => usart::InterruptHandler<peripherals::UART5>;
    USART2 => usart::InterruptHandler<peripherals::USART2>;
    USART1 => usart::BufferedInterruptHandler<peripherals::USART1>;
    USART3 => usart::BufferedInterruptHandler<peripherals::USART3>;
    EXTI9_5 => exti::InterruptHandler<interrupt::typelevel::EXTI9_5>;
    SDMMC2 => embassy_stm32::sdmmc::InterruptHandler<peripherals::SDMMC2>;
    FDCAN1_IT0 => embassy_stm32::can::IT0InterruptHandler<peripherals::FDCAN1>;
    FDCAN1_IT1 => embassy_stm32::can::IT1InterruptHandler<peripherals::FDCAN1>;
});

/// SPI clock of the IMU: 10 MHz (the ICM-42688-P takes up to 24 MHz).
const IMU_SPI_HZ: u32 = 10_000_000;

/// What the board's own tasks take.
pub struct BoardParts {
    /// The status LEDs (thread mode).
    pub leds: Leds,
    /// The IMU and the ESCs (control priority).
    pub control_tasks: ControlTasks,
}

/// The board's tasks at the control priority.
pub struct ControlTasks {
    usb_device: Option<super::usb_link::UsbDeviceTask>,
    imu: super::imu_spi::ImuBus,
    escs: super::escs::EscTimers,
    can: (
        embassy_stm32::can::CanTx<'static>,
        embassy_stm32::can::CanRx<'static>,
    ),
    steppers: [Option<super::steppers::StepperBus>; super::steppers::BUSES],
    reset: ResetReason,
}

/// SPI clock of the FRAM: 10 MHz, well inside the part's 40 MHz.
const FRAM_SPI_HZ: u32 = 10_000_000;

/// TELEM1's transmit ring: a control step's messages are at most ~1.3 KB (three texts in
/// chunks, six values, the acknowledgement, the heartbeat, the actuators), 12 ms at 921,600
/// baud; the send task waits on a full ring, so a larger one only buys latency slack. 768
/// bytes (8 ms) keep static RAM inside its 128 KiB with the failsafes' monitors.
static LINK_TX_BUFFER: StaticCell<[u8; 768]> = StaticCell::new();
static USB_EP_OUT_BUFFER: StaticCell<[u8; 256]> = StaticCell::new();
/// The stepper buses' receive rings.
static STEPPER_RX: [ConstStaticCell<[u8; 64]>; 2] =
    [ConstStaticCell::new([0; 64]), ConstStaticCell::new([0; 64])];
/// The interrupt-driven stepper buses' (GPS1, the debug port) send and receive buffers: a
/// request is at most 8 bytes, its echo and reply 16.
static STEPPER_BUFFERS: ConstStaticCell<[([u8; 16], [u8; 32]); 2]> =
    ConstStaticCell::new([([0; 16], [0; 32]); 2]);
/// TELEM1's receive ring: 5.5 ms at 921,600 baud, 14 ms of a HIL plant's traffic (400 Hz
/// `HIL_SENSOR` and 100 Hz motion capture); the receive task drains it far more often.
static LINK_RX_BUFFER: StaticCell<[u8; 512]> = StaticCell::new();
/// The link chosen at start is USB (a cable powered VBUS).
static LINK_IS_USB: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(false);

/// Opens TELEM1 (UART7) for MAVLink at [`LINK_BAUD`].
fn telem1(
    uart: embassy_stm32::Peri<'static, peripherals::UART7>,
    rx: embassy_stm32::Peri<'static, peripherals::PE7>,
    tx: embassy_stm32::Peri<'static, peripherals::PE8>,
) -> (BufferedUartRx<'static>, BufferedUartTx<'static>) {
    let mut config = usart::Config::default();
    config.baudrate = LINK_BAUD;
    let uart = match BufferedUart::new(
        uart,
        rx,
        tx,
        LINK_TX_BUFFER.init([0; 768]),
        LINK_RX_BUFFER.init([0; 512]),
        LinkIrqs,
        config,
    ) {
        Ok(uart) => uart,
        Err(e) => defmt::panic!("TELEM1 (UART7) configuration refused: {}", e),
    };
    let (tx, rx) = uart.split();
    (rx, tx)
}

/// Why the MCU last reset (RCC_RSR), its flags then cleared for the next start.
fn take_reset_reason() -> ResetReason {
    let rsr = pac::RCC.rsr().read().0;
    pac::RCC.rsr().modify(|w| w.set_rmvf(true));
    ResetReason::from_rsr(rsr)
}

/// Brings the clocks up, claims the pins, opens the link; returns what the application takes
/// and what the board's own tasks take.
pub fn init() -> (Parts<Pixhawk6c>, BoardParts) {
    let reset = take_reset_reason();
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
        battery: BatteryInput {
            adc: embassy_stm32::adc::Adc::new_with_config(
                p.ADC1,
                embassy_stm32::adc::AdcConfig {
                    resolution: Some(embassy_stm32::adc::Resolution::BITS16),
                    averaging: Some(embassy_stm32::adc::Averaging::Samples16),
                },
            ),
            pin: p.PC5,
        },
    };
    // The link: USB if a cable powers VBUS (PA9) at start, TELEM1 otherwise.
    let (link_rx, link_tx, usb_device) = {
        use super::usb_link::{LinkRx, LinkTx};
        use embassy_stm32::gpio::Input;
        use embassy_stm32::usb;
        bind_interrupts!(struct UsbIrqs {
            OTG_FS => usb::InterruptHandler<peripherals::USB_OTG_FS>;
        });
        if Input::new(p.PA9, Pull::Down).is_high() {
            LINK_IS_USB.store(true, core::sync::atomic::Ordering::Relaxed);
            let mut usb_config = usb::Config::default();
            usb_config.vbus_detection = true;
            let driver = usb::Driver::new_fs(
                p.USB_OTG_FS,
                UsbIrqs,
                p.PA12,
                p.PA11,
                USB_EP_OUT_BUFFER.init([0; 256]),
                usb_config,
            );
            let (device, rx, tx) = super::usb_link::open(driver);
            (LinkRx::Usb(rx), LinkTx::Usb(tx), Some(device))
        } else {
            let (rx, tx) = telem1(p.UART7, p.PE7, p.PE8);
            (LinkRx::Telem1(rx), LinkTx::Telem1(tx), None)
        }
    };

    let mut spi_config = spi::Config::default();
    spi_config.frequency = Hertz(FRAM_SPI_HZ);
    let fram_spi = Spi::new_blocking(p.SPI2, p.PD3, p.PC3, p.PC2, spi_config);
    let fram = super::fram::Fram::new(fram_spi, Output::new(p.PD4, Level::High, Speed::High));

    // IMU on SPI1, its bus powered (PB2 high), chip select PC13, data ready PE6.
    let imu_power = Output::new(p.PB2, Level::High, Speed::Low);
    core::mem::forget(imu_power); // keep the sensors powered for good
    let mut imu_spi_config = spi::Config::default();
    imu_spi_config.frequency = Hertz(IMU_SPI_HZ);
    imu_spi_config.mode = spi::MODE_3;
    let imu = super::imu_spi::ImuBus {
        spi: Spi::new(
            p.SPI1,
            p.PA5,
            p.PA7,
            p.PA6,
            p.DMA1_CH3,
            p.DMA1_CH4,
            Irqs,
            imu_spi_config,
        ),
        cs: Output::new(p.PC13, Level::High, Speed::VeryHigh),
        drdy: ExtiInput::new(p.PE6, p.EXTI6, Pull::None, Irqs),
    };

    // ESCs: each timer counts one DShot600 bit per period.
    let dshot = Hertz(drivers::dshot::DSHOT600_BIT_HZ);
    let pin = OutputType::PushPull;
    let escs = super::escs::EscTimers {
        tim1: SimplePwm::new(
            p.TIM1,
            Some(PwmPin::new(p.PA8, pin)),
            Some(PwmPin::new(p.PE11, pin)),
            Some(PwmPin::new(p.PE13, pin)),
            Some(PwmPin::new(p.PE14, pin)),
            dshot,
            CountingMode::EdgeAlignedUp,
        ),
        tim4: SimplePwm::new(
            p.TIM4,
            None,
            None,
            Some(PwmPin::new(p.PD14, pin)),
            Some(PwmPin::new(p.PD15, pin)),
            dshot,
            CountingMode::EdgeAlignedUp,
        ),
        tim5: SimplePwm::new(
            p.TIM5,
            Some(PwmPin::new(p.PA0, pin)),
            Some(PwmPin::new(p.PA1, pin)),
            None,
            None,
            dshot,
            CountingMode::EdgeAlignedUp,
        ),
        up: {
            use super::escs::update_stream;
            use embassy_stm32::timer::{Ch1, Ch3};
            use peripherals::{TIM1, TIM4, TIM5};
            [
                update_stream::<TIM1, Ch1, _>(p.DMA1_CH0),
                update_stream::<TIM4, Ch3, _>(p.DMA1_CH1),
                update_stream::<TIM5, Ch1, _>(p.DMA1_CH2),
            ]
        },
        capture: {
            use super::escs::capture_stream;
            use embassy_stm32::timer::{Ch2, Ch3, Ch4};
            use peripherals::{TIM1, TIM5};
            [
                capture_stream::<TIM1, Ch2, _>(p.DMA2_CH1),
                capture_stream::<TIM1, Ch3, _>(p.DMA2_CH2),
                capture_stream::<TIM1, Ch4, _>(p.DMA2_CH3),
                capture_stream::<TIM5, Ch2, _>(p.DMA2_CH4),
            ]
        },
    };
    let can = super::can_escs::open(p.FDCAN1, p.PD0, p.PD1);
    // Steppers: TMC2209s on TELEM2 (UART5) and TELEM3 (USART2), TX through 1 kOhm and RX on
    // the drivers' single wire.
    let mut stepper_config = usart::Config::default();
    stepper_config.baudrate = super::steppers::BAUD;
    let telem2 = usart::Uart::new(
        p.UART5,
        p.PD2,
        p.PC12,
        p.DMA1_CH5,
        p.DMA1_CH6,
        Irqs,
        stepper_config,
    );
    let telem3 = usart::Uart::new(
        p.USART2,
        p.PA3,
        p.PD5,
        p.DMA1_CH7,
        p.DMA2_CH0,
        Irqs,
        stepper_config,
    );
    let bus = |uart: usart::Uart<'static, embassy_stm32::mode::Async>,
               ring: &'static mut [u8; 64],
               first_robot,
               name| {
        let (tx, rx) = uart.split();
        super::steppers::StepperBus {
            port: super::steppers::StepperPort::Dma {
                tx,
                rx: rx.into_ring_buffered(ring),
            },
            first_robot,
            name,
        }
    };
    // Robots 9-16 on GPS1 (USART1) and the debug port (USART3), by interrupt: DMA1's eight
    // streams are taken, and DMA2's two left would serve one bus.
    let [(gps1_tx, gps1_rx), (debug_tx, debug_rx)] = STEPPER_BUFFERS.take();
    let gps1 = BufferedUart::new(
        p.USART1,
        p.PA10,
        p.PB6,
        gps1_tx,
        gps1_rx,
        Irqs,
        stepper_config,
    );
    let debug = BufferedUart::new(
        p.USART3,
        p.PD9,
        p.PD8,
        debug_tx,
        debug_rx,
        Irqs,
        stepper_config,
    );
    let buffered = |uart: BufferedUart<'static>, first_robot, name| super::steppers::StepperBus {
        port: super::steppers::StepperPort::Buffered(uart),
        first_robot,
        name,
    };
    let steppers = [
        telem2
            .ok()
            .map(|uart| bus(uart, STEPPER_RX[0].take(), 0, "TELEM2")),
        telem3
            .ok()
            .map(|uart| bus(uart, STEPPER_RX[1].take(), 4, "TELEM3")),
        gps1.ok().map(|uart| buffered(uart, 8, "GPS1")),
        debug.ok().map(|uart| buffered(uart, 12, "the debug port")),
    ];
    // The RC receiver on GPS2 (UART8, RX PE0), receive only; opened for CRSF, reconfigured by
    // the receiver task for the protocol the parameters ask for.
    let rc_serial = super::rc_serial::RcUart::new(
        usart::UartRx::new(
            p.UART8,
            p.PE0,
            p.DMA2_CH5,
            Irqs,
            super::rc_serial::config(drivers::rc_receiver::CRSF_LINE),
        )
        .ok(),
    );
    // A core halted by a debug probe freezes the watchdog too, so a breakpoint does not reset.
    pac::DBGMCU.apb4fzr1().modify(|w| w.set_iwdg1(true));
    let outputs = Outputs {
        watchdog: IndependentWatchdog::new(p.IWDG1, WATCHDOG_TIMEOUT_US),
        watchdog_running: false,
        thrust_map: ThrustMap::SQUARE,
        protocol: EscProtocol::Dshot600,
        settings: HardwareConfig::DEFAULT,
    };

    // The microSD card on SDMMC2, for the flight logs; its transfers are polled by the logger
    // task, so its interrupt (which only wakes) runs at the lowest priority but one.
    let sdmmc = embassy_stm32::sdmmc::Sdmmc::new_4bit(
        p.SDMMC2,
        Irqs,
        p.PD6,
        p.PD7,
        p.PB14,
        p.PB15,
        p.PB3,
        p.PB4,
        Default::default(),
    );
    interrupt::SDMMC2.set_priority(Priority::P14);
    let log_storage = super::sdcard::open(sdmmc);

    interrupt::SPDIF_RX.set_priority(Priority::P2);
    interrupt::CEC.set_priority(Priority::P3);
    interrupt::JPEG.set_priority(Priority::P15);
    // SAFETY: its handler below only raises the thread-mode wake-up flag.
    unsafe { interrupt::JPEG.enable() };
    let parts = Parts {
        link_rx,
        link_tx,
        outputs,
        param_flash: fram,
        log_storage,
        rc_serial,
        irqs: ExecutorIrqs {
            control: Interrupt::SPDIF_RX,
            link: Interrupt::CEC,
            thread_wake: Interrupt::JPEG,
        },
    };
    let board = BoardParts {
        leds,
        control_tasks: ControlTasks {
            usb_device,
            imu,
            escs,
            can,
            steppers,
            reset,
        },
    };
    (parts, board)
}

/// Spawns the board's tasks at the control priority (the IMU, the ESCs, the steppers) and on
/// the link executor (the USB device), and reports why the board started.
pub fn spawn_control_tasks(spawner: SendSpawner, link_spawner: SendSpawner, tasks: ControlTasks) {
    let ControlTasks {
        usb_device,
        imu,
        escs,
        can: (can_tx, can_rx),
        steppers,
        reset,
    } = tasks;
    let severity = if reset.is_fault() {
        crate::app::autonomy::Severity::Critical
    } else {
        crate::app::autonomy::Severity::Info
    };
    let _ = crate::app::OUTBOX.try_send(crate::app::comms::report(
        severity,
        format_args!("{}; disarmed", reset.describe()),
    ));
    if let Some(device) = usb_device {
        match super::usb_link::usb_device(device) {
            Ok(token) => link_spawner.spawn(token),
            Err(e) => defmt::error!("USB task not spawned: {}", e),
        }
    }
    match super::imu_spi::imu(imu) {
        Ok(token) => spawner.spawn(token),
        Err(e) => defmt::error!("IMU task not spawned: {}", e),
    }
    match super::escs::escs(escs) {
        Ok(token) => spawner.spawn(token),
        Err(e) => defmt::error!("ESC task not spawned: {}", e),
    }
    match super::can_escs::send(can_tx) {
        Ok(token) => spawner.spawn(token),
        Err(e) => defmt::error!("CAN send task not spawned: {}", e),
    }
    match super::can_escs::receive(can_rx) {
        Ok(token) => spawner.spawn(token),
        Err(e) => defmt::error!("CAN receive task not spawned: {}", e),
    }
    // Two tasks, each two buses: TELEM2 and GPS1 (robots 1-4, 9-12), TELEM3 and the debug
    // port (robots 5-8, 13-16).
    let [telem2, telem3, gps1, debug] = steppers;
    let pairs = [[telem2, gps1], [telem3, debug]];
    if pairs.iter().flatten().any(Option::is_none) {
        let _ = crate::app::OUTBOX.try_send(crate::app::comms::report(
            crate::app::autonomy::Severity::Critical,
            format_args!("a stepper bus UART refused its configuration"),
        ));
    }
    for pair in pairs {
        match super::steppers::steppers(pair) {
            Ok(token) => spawner.spawn(token),
            Err(e) => defmt::error!("stepper task not spawned: {}", e),
        }
    }
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
    let Leds {
        red: _red,
        blue,
        battery,
    } = leds;
    match heartbeat(blue, battery) {
        Ok(token) => spawner.spawn(token),
        Err(e) => defmt::error!("heartbeat task not spawned: {}", e),
    }
}

/// Blinks `led` (active low) 100 ms on, 900 ms off, forever: the executor runs; reads the
/// pack's voltage every 100 ms meanwhile (a few microseconds, blocking).
#[embassy_executor::task]
async fn heartbeat(mut led: Output<'static>, mut battery: BatteryInput) {
    let mut ticker = Ticker::every(Duration::from_millis(100));
    loop {
        for tenth in 0..10u8 {
            battery.read();
            if tenth == 0 {
                led.set_low();
            } else {
                led.set_high();
            }
            ticker.next().await;
        }
    }
}
