//! The Pixhawk 6C's eight ESC outputs by DShot600 (issue 13): FMU_CH1-4 on TIM1 CH1-4 (PA8,
//! PE11, PE13, PE14), FMU_CH5-6 on TIM4 CH3-4 (PD14, PD15), FMU_CH7-8 on TIM5 CH1-2 (PA0, PA1),
//! as PX4's `fmu-v6c/src/timer_config.cpp` assigns them. Each timer runs at the DShot600 bit
//! rate and a DMA burst on its update event writes the next bit's compare values of all its
//! channels (frames from [`drivers::dshot`]).
//!
//! The control step hands its commands over with [`command`]; this task, at the control
//! priority, sends them. Outputs stop (DShot value 0) while disarmed, and when no command has
//! come for [`FEED_TIMEOUT`]: if the control task stops, so do the rotors.

use drivers::dshot::{self, BitTiming, SLOTS};
use embassy_stm32::Peri;
use embassy_stm32::peripherals::{DMA1_CH0, DMA1_CH1, DMA1_CH2, TIM1, TIM4, TIM5};
use embassy_stm32::timer::Channel;
use embassy_stm32::timer::simple_pwm::SimplePwm;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use embassy_time::{Duration, with_timeout};

/// Outputs (one rotor per robot, robot `i` on FMU_CH`i+1`).
pub const OUTPUTS: usize = 8;
/// No command for this long stops the rotors (10 control steps at 400 Hz).
pub const FEED_TIMEOUT: Duration = Duration::from_millis(25);

/// DShot values waiting for the ESC task.
static COMMAND: Signal<CriticalSectionRawMutex, [u16; OUTPUTS]> = Signal::new();

/// Hands one control step's commands to the ESCs: command fractions `[0, 1]` (from the thrust
/// map), all stopped unless `armed`.
pub fn command(fractions: &[f32], armed: bool) {
    let mut values = [dshot::STOP; OUTPUTS];
    if armed {
        for (value, &fraction) in values.iter_mut().zip(fractions) {
            *value = dshot::throttle_value(fraction);
        }
    }
    COMMAND.signal(values);
}

/// The three timers, their pins claimed, and a DMA stream each.
pub struct EscTimers {
    /// FMU_CH1-4.
    pub tim1: SimplePwm<'static, TIM1>,
    /// FMU_CH5-6 (CH3-4).
    pub tim4: SimplePwm<'static, TIM4>,
    /// FMU_CH7-8 (CH1-2).
    pub tim5: SimplePwm<'static, TIM5>,
    /// TIM1_UP's stream.
    pub dma1: Peri<'static, DMA1_CH0>,
    /// TIM4_UP's stream.
    pub dma4: Peri<'static, DMA1_CH1>,
    /// TIM5_UP's stream.
    pub dma5: Peri<'static, DMA1_CH2>,
}

/// Sends the latest command to the ESCs each time one comes, or stop frames each
/// [`FEED_TIMEOUT`] without one; forever.
#[embassy_executor::task]
pub async fn escs(mut t: EscTimers) {
    // The timers were set to DShot600's bit rate: their period is the bit.
    let timing = |max_duty: u32| BitTiming::from_period(max_duty.min(u32::from(u16::MAX)) as u16);
    let timing1 = timing(t.tim1.max_duty_cycle());
    let timing4 = timing(t.tim4.max_duty_cycle());
    let timing5 = timing(t.tim5.max_duty_cycle());
    let mut burst1 = [0u16; SLOTS * 4];
    let mut burst4 = [0u16; SLOTS * 2];
    let mut burst5 = [0u16; SLOTS * 2];
    loop {
        let values = with_timeout(FEED_TIMEOUT, COMMAND.wait())
            .await
            .unwrap_or([dshot::STOP; OUTPUTS]);
        let frames = values.map(|v| dshot::frame(v, false));
        // The buffers are sized for their timer's channels: these cannot fail.
        let _ = dshot::fill_burst(&frames[0..4], timing1, &mut burst1);
        let _ = dshot::fill_burst(&frames[4..6], timing4, &mut burst4);
        let _ = dshot::fill_burst(&frames[6..8], timing5, &mut burst5);
        t.tim1
            .waveform_up_multi_channel(
                t.dma1.reborrow(),
                super::pixhawk6c::Irqs,
                Channel::Ch1,
                Channel::Ch4,
                &burst1,
            )
            .await;
        t.tim4
            .waveform_up_multi_channel(
                t.dma4.reborrow(),
                super::pixhawk6c::Irqs,
                Channel::Ch3,
                Channel::Ch4,
                &burst4,
            )
            .await;
        t.tim5
            .waveform_up_multi_channel(
                t.dma5.reborrow(),
                super::pixhawk6c::Irqs,
                Channel::Ch1,
                Channel::Ch2,
                &burst5,
            )
            .await;
    }
}
