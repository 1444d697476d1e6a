//! The Pixhawk 6C's eight ESC outputs: FMU_CH1-4 on TIM1 CH1-4 (PA8, PE11, PE13,
//! PE14), FMU_CH5-6 on TIM4 CH3-4 (PD14, PD15), FMU_CH7-8 on TIM5 CH1-2 (PA0, PA1), as PX4's
//! `fmu-v6c/src/timer_config.cpp` assigns them.
//!
//! DShot600 (the default): each timer runs at the bit rate and a DMA burst on its update event
//! writes the next bit's compare values of all its channels (frames from
//! [`drivers::dshot`]). PWM and OneShot125 ([`drivers::pulse`]): the timers run at 400 Hz and
//! each control step sets the pulse widths. The protocol (parameter `ESC_PROTOCOL`) changes
//! only while disarmed.
//!
//! The control step hands its commands over with [`command`]; this task, at the control
//! priority, sends them. Outputs stop (DShot value 0, or the stop pulse) while disarmed, and
//! when no command has come for [`FEED_TIMEOUT`]: if the control task stops, so do the rotors.

use drivers::dshot::{self, BitTiming, SLOTS};
use drivers::esc_gate::{EscCommand, EscGate};
use drivers::pulse::{self, EscProtocol, PERIOD_400HZ_NS};
use embassy_futures::join::join3;
use embassy_stm32::Peri;
use embassy_stm32::peripherals::{DMA1_CH0, DMA1_CH1, DMA1_CH2, TIM1, TIM4, TIM5};
use embassy_stm32::time::Hertz;
use embassy_stm32::timer::simple_pwm::SimplePwm;
use embassy_stm32::timer::{Channel, GeneralInstance4Channel};
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use embassy_time::{Duration, with_timeout};

/// Outputs (one rotor per robot, robot `i` on FMU_CH`i+1`).
pub const OUTPUTS: usize = 8;
/// No command for this long stops the rotors (10 control steps at 400 Hz).
pub const FEED_TIMEOUT: Duration = Duration::from_millis(25);

static COMMAND: Signal<CriticalSectionRawMutex, EscCommand<OUTPUTS>> = Signal::new();

/// Hands one control step's commands to the ESCs: command fractions `[0, 1]` (from the thrust
/// map), all stopped unless `armed`, in `protocol`.
pub fn command(protocol: EscProtocol, fractions: &[f32], armed: bool) {
    let mut all = [0.0; OUTPUTS];
    for (slot, &f) in all.iter_mut().zip(fractions) {
        *slot = f;
    }
    COMMAND.signal(EscCommand {
        protocol,
        fractions: all,
        armed,
    });
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

/// The channels each timer drives, first to last.
const TIM1_CHANNELS: (Channel, Channel) = (Channel::Ch1, Channel::Ch4);
const TIM4_CHANNELS: (Channel, Channel) = (Channel::Ch3, Channel::Ch4);
const TIM5_CHANNELS: (Channel, Channel) = (Channel::Ch1, Channel::Ch2);

fn channels((first, last): (Channel, Channel)) -> impl Iterator<Item = Channel> {
    [Channel::Ch1, Channel::Ch2, Channel::Ch3, Channel::Ch4]
        .into_iter()
        .filter(move |c| c.index() >= first.index() && c.index() <= last.index())
}

/// Sets a timer to `protocol`'s rate (its channels enabled for pulses).
fn set_rate<T: GeneralInstance4Channel>(
    pwm: &mut SimplePwm<'static, T>,
    protocol: EscProtocol,
    chans: (Channel, Channel),
) {
    match protocol {
        EscProtocol::Dshot600 => pwm.set_frequency(Hertz(dshot::DSHOT600_BIT_HZ)),
        EscProtocol::Pwm | EscProtocol::OneShot125 => {
            pwm.set_frequency(Hertz(pulse::EscProtocol::Pwm.update_hz(400)));
            for c in channels(chans) {
                pwm.channel(c).enable();
            }
        }
    }
}

/// Sets the pulse widths of a timer's channels for `fractions` (one per channel).
fn set_pulses<T: GeneralInstance4Channel>(
    pwm: &mut SimplePwm<'static, T>,
    protocol: EscProtocol,
    chans: (Channel, Channel),
    fractions: &[f32],
) {
    let max = pwm.max_duty_cycle();
    for (c, &f) in channels(chans).zip(fractions) {
        let duty = pulse::duty_of(protocol.pulse_ns(f), PERIOD_400HZ_NS, max);
        pwm.channel(c).set_duty_cycle(duty);
    }
}

fn timing<T: GeneralInstance4Channel>(pwm: &SimplePwm<'static, T>) -> BitTiming {
    BitTiming::from_period(pwm.max_duty_cycle().min(u32::from(u16::MAX)) as u16)
}

/// Sends the latest command to the ESCs each time one comes, or stop commands each
/// [`FEED_TIMEOUT`] without one; forever.
#[embassy_executor::task]
pub async fn escs(mut t: EscTimers) {
    // The timers start at DShot600's bit rate.
    let mut gate = EscGate::new(EscProtocol::Dshot600);
    let mut burst1 = [0u16; SLOTS * 4];
    let mut burst4 = [0u16; SLOTS * 2];
    let mut burst5 = [0u16; SLOTS * 2];
    loop {
        let command = with_timeout(FEED_TIMEOUT, COMMAND.wait()).await.ok();
        let update = gate.update(command.as_ref());
        if let Some(protocol) = update.switch_to {
            set_rate(&mut t.tim1, protocol, TIM1_CHANNELS);
            set_rate(&mut t.tim4, protocol, TIM4_CHANNELS);
            set_rate(&mut t.tim5, protocol, TIM5_CHANNELS);
        }
        let protocol = gate.protocol();
        let fractions = update.fractions;
        match protocol {
            EscProtocol::Dshot600 => {
                let frames = fractions.map(|f| dshot::frame(dshot::throttle_value(f), false));
                // The buffers are sized for their timer's channels: these cannot fail.
                let _ = dshot::fill_burst(&frames[0..4], timing(&t.tim1), &mut burst1);
                let _ = dshot::fill_burst(&frames[4..6], timing(&t.tim4), &mut burst4);
                let _ = dshot::fill_burst(&frames[6..8], timing(&t.tim5), &mut burst5);
                let irqs = super::pixhawk6c::Irqs;
                join3(
                    t.tim1.waveform_up_multi_channel(
                        t.dma1.reborrow(),
                        irqs,
                        TIM1_CHANNELS.0,
                        TIM1_CHANNELS.1,
                        &burst1,
                    ),
                    t.tim4.waveform_up_multi_channel(
                        t.dma4.reborrow(),
                        irqs,
                        TIM4_CHANNELS.0,
                        TIM4_CHANNELS.1,
                        &burst4,
                    ),
                    t.tim5.waveform_up_multi_channel(
                        t.dma5.reborrow(),
                        irqs,
                        TIM5_CHANNELS.0,
                        TIM5_CHANNELS.1,
                        &burst5,
                    ),
                )
                .await;
            }
            EscProtocol::Pwm | EscProtocol::OneShot125 => {
                set_pulses(&mut t.tim1, protocol, TIM1_CHANNELS, &fractions[0..4]);
                set_pulses(&mut t.tim4, protocol, TIM4_CHANNELS, &fractions[4..6]);
                set_pulses(&mut t.tim5, protocol, TIM5_CHANNELS, &fractions[6..8]);
            }
        }
    }
}
