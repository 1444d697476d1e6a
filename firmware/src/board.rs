//! The Pixhawk 6C-class board: clock tree and pin assignment.
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

use embassy_stm32::Config;
use embassy_stm32::gpio::{Level, Output, Speed};
use embassy_stm32::rcc::{
    AHBPrescaler, APBPrescaler, Hse, HseMode, Pll, PllDiv, PllMul, PllPreDiv, PllSource, Sysclk,
    VoltageScale,
};
use embassy_stm32::time::Hertz;

/// Frequency of the board's HSE crystal.
pub const HSE_HZ: u32 = 16_000_000;
/// Core clock the configuration below produces.
pub const CORE_HZ: u32 = 480_000_000;

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

/// The board's peripherals, claimed and configured.
pub struct Board {
    /// Status LEDs.
    pub leds: Leds,
}

impl Board {
    /// Brings the clocks up and claims the pins this firmware uses.
    pub fn init() -> Self {
        let p = embassy_stm32::init(clock_config());
        // Active low: High is off.
        let leds = Leds {
            red: Output::new(p.PD10, Level::High, Speed::Low),
            blue: Output::new(p.PD11, Level::High, Speed::Low),
        };
        Self { leds }
    }
}
