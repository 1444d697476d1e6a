//! The Pixhawk 6C's eight ESC outputs: FMU_CH1-4 on TIM1 CH1-4 (PA8, PE11, PE13,
//! PE14), FMU_CH5-6 on TIM4 CH3-4 (PD14, PD15), FMU_CH7-8 on TIM5 CH1-2 (PA0, PA1), as PX4's
//! `fmu-v6c/src/timer_config.cpp` assigns them.
//!
//! DShot600 (the default): each timer runs at the bit rate and a DMA burst on its update event
//! writes the next bit's compare values of all its channels (frames from
//! [`drivers::dshot`]). PWM and OneShot125 ([`drivers::pulse`]): the timers run at 400 Hz and
//! each control step sets the pulse widths. DroneCAN (the ESCs on CAN1, [`super::can_escs`]):
//! the timers run at 400 Hz with no pulse, every line held low. The protocol (parameter `ESC_PROTOCOL`) changes
//! only while disarmed.
//!
//! Bidirectional DShot (parameter `DSHOT_BIDIR_EN`, with DShot600): the channels turn active
//! low (the line idles high, the pins pulled up) and the frames carry the inverted checksum
//! ([`drivers::dshot::bidirectional_frame`]). After each frame every channel turns to input
//! capture on both edges for [`ANSWER_WINDOW_US`] (the timers counting freely at 240 MHz), a
//! DMA stream copying each capture into a buffer of edge times: the timers' update streams for
//! FMU_CH1, CH5 and CH7, DMA2 streams 1-4 for CH2-4 and CH8. FMU_CH6 (TIM4 CH4) has no DMA
//! request on the STM32H743, so the timer's capture interrupt (at the highest priority) stores
//! its edges. Then the channels turn back to outputs, each answer is decoded
//! ([`drivers::dshot_telemetry`]) and the RPM goes to the control step ([`take_rpm`]).
//!
//! The control step hands its commands over with [`command`]; this task, at the control
//! priority, sends them. Outputs stop (DShot value 0, or the stop pulse) while disarmed, and
//! when no command has come for [`FEED_TIMEOUT`]: if the control task stops, so do the rotors.

use core::cell::Cell;
use core::sync::atomic::{AtomicBool, AtomicU8, AtomicUsize, Ordering::Relaxed};
use drivers::dshot::{self, BitTiming, SLOTS};
use drivers::dshot_telemetry::{self as answer, Answer};
use drivers::esc_gate::{EscCommand, EscGate};
use drivers::pulse::{self, EscProtocol, PERIOD_400HZ_NS, Pulses};
use embassy_stm32::interrupt;
use embassy_stm32::interrupt::typelevel::Binding;
use embassy_stm32::interrupt::{InterruptExt, Priority};
use embassy_stm32::pac::timer::{TimGp16, regs};
use embassy_stm32::peripherals::{TIM1, TIM4, TIM5};
use embassy_stm32::time::Hertz;
use embassy_stm32::timer::simple_pwm::SimplePwm;
use embassy_stm32::timer::{Channel, GeneralInstance4Channel, TimerChannel, UpDma};
use embassy_stm32::{Peri, dma, pac};
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use embassy_time::{Duration, Timer, with_timeout};

use super::pixhawk6c::Irqs;

/// Outputs (one rotor per robot, robot `i` on FMU_CH`i+1`).
pub const OUTPUTS: usize = 8;
/// No command for this long stops the rotors (10 control steps at 400 Hz).
pub const FEED_TIMEOUT: Duration = Duration::from_millis(25);

/// How long the channels listen after a frame, us: the ESC answers about 30 us after it,
/// for 21 bits of 1.333 us; the rest is margin.
pub const ANSWER_WINDOW_US: u64 = 70;

static COMMAND: Signal<CriticalSectionRawMutex, EscCommand<OUTPUTS>> = Signal::new();

/// The motors' magnet poles while bidirectional DShot is asked for, 0 while it is not.
static TELEMETRY_POLES: AtomicU8 = AtomicU8::new(0);

/// Each rotor's RPM from the latest answers, NaN once taken until the next; `None` while the
/// outputs read no telemetry.
static RPM: Mutex<CriticalSectionRawMutex, Cell<Option<[f32; OUTPUTS]>>> =
    Mutex::new(Cell::new(None));

/// Edge slots per channel: more than an answer's [`answer::MAX_EDGES`].
const EDGES: usize = 32;

/// FMU_CH6's edge times, stored by the TIM4 interrupt, and how many came.
static CH6_EDGES: Mutex<CriticalSectionRawMutex, Cell<[u16; EDGES]>> =
    Mutex::new(Cell::new([0; EDGES]));
static CH6_COUNT: AtomicUsize = AtomicUsize::new(0);
/// A capture of FMU_CH6 was overwritten before it was read.
static CH6_LOST: AtomicBool = AtomicBool::new(false);

/// Asks for bidirectional DShot (taken with DShot600 only) with motors of `poles` magnet
/// poles, or not.
pub fn set_telemetry(bidirectional: bool, poles: u8) {
    TELEMETRY_POLES.store(if bidirectional { poles.max(1) } else { 0 }, Relaxed);
}

/// Each rotor's RPM from the ESCs' answers to the latest frame (NaN for an ESC that did not
/// answer, or answered wrongly; NaN again until the next frame's answers), or `None` when the
/// outputs read no telemetry. Cheap: one critical section.
pub fn take_rpm() -> Option<[f32; OUTPUTS]> {
    RPM.lock(|cell| {
        let rpm = cell.get();
        if rpm.is_some() {
            cell.set(Some([f32::NAN; OUTPUTS]));
        }
        rpm
    })
}

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

/// The three timers, their pins claimed, and their DMA streams.
pub struct EscTimers {
    /// FMU_CH1-4.
    pub tim1: SimplePwm<'static, TIM1>,
    /// FMU_CH5-6 (CH3-4).
    pub tim4: SimplePwm<'static, TIM4>,
    /// FMU_CH7-8 (CH1-2).
    pub tim5: SimplePwm<'static, TIM5>,
    /// TIM1's, TIM4's and TIM5's update streams ([`update_stream`]): the frames' bursts, then
    /// the captures of FMU_CH1, CH5 and CH7.
    pub up: [(dma::Channel<'static>, u8, u8); 3],
    /// The capture streams of FMU_CH2-4 (TIM1 CH2-4) and FMU_CH8 (TIM5 CH2), with their
    /// requests ([`capture_stream`]).
    pub capture: [(dma::Channel<'static>, u8); 4],
}

/// A timer `T`'s update stream: the DMA channel, its update request, and the capture request of
/// the timer's channel `C`, whose answers the same stream copies after the frame.
pub fn update_stream<T, C, D>(stream: Peri<'static, D>) -> (dma::Channel<'static>, u8, u8)
where
    T: GeneralInstance4Channel,
    C: TimerChannel,
    D: UpDma<T> + embassy_stm32::timer::Dma<T, C>,
    Irqs: Binding<D::Interrupt, dma::InterruptHandler<D>>,
{
    let up = UpDma::request(&*stream);
    let capture = embassy_stm32::timer::Dma::request(&*stream);
    (dma::Channel::new(stream, Irqs), up, capture)
}

/// A DMA stream for the captures of channel `C` of timer `T`, and its request.
pub fn capture_stream<T, C, D>(stream: Peri<'static, D>) -> (dma::Channel<'static>, u8)
where
    T: GeneralInstance4Channel,
    C: TimerChannel,
    D: embassy_stm32::timer::Dma<T, C>,
    Irqs: Binding<D::Interrupt, dma::InterruptHandler<D>>,
{
    let request = stream.request();
    (dma::Channel::new(stream, Irqs), request)
}

/// Starts timer `r`'s frame: its channels `mask` on, each update event writing the next row of
/// `burst` (a value per channel) to their compare registers through DMAR, as embassy's
/// `waveform_up_multi_channel` does (the same DMA burst and FIFO), for all three timers with
/// one function.
#[inline(never)]
fn start_burst<'a>(
    r: TimGp16,
    (dma, request, _): &'a mut (dma::Channel<'static>, u8, u8),
    mask: u32,
    burst: &'a [u16],
) -> dma::Transfer<'a> {
    let ccxe = (0..4)
        .filter(|c| mask & (1 << c) != 0)
        .fold(0, |e, c| e | (1 << (4 * c)));
    r.ccer().modify(|w| w.0 |= ccxe);
    r.dier().modify(|w| w.set_ude(true));
    r.dcr().modify(|w| {
        // CCR1 is register 13 (0x34); the burst writes one register per channel.
        w.set_dba(13 + mask.trailing_zeros() as u8);
        w.set_dbl(mask.count_ones() as u8 - 1);
    });
    let mut options = dma::TransferOptions::default();
    options.fifo_threshold = Some(dma::FifoThreshold::Full);
    options.mburst = dma::Burst::Incr4;
    // SAFETY: the timer's DMA burst register, written by half-words from a buffer the
    // transfer borrows.
    unsafe { dma.write(*request, burst, r.dmar().as_ptr() as *mut u16, options) }
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
        // With DroneCAN the outputs run at 400 Hz with no pulse: their lines held low.
        EscProtocol::Pwm | EscProtocol::OneShot125 | EscProtocol::DroneCan => {
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

/// The outputs' pins by port, with the port's pull-up bits for them and their whole fields
/// (PUPDR, two bits a pin): FMU_CH1, CH7-8 (PA8, PA0, PA1), FMU_CH2-4 (PE11, PE13, PE14),
/// FMU_CH5-6 (PD14, PD15).
const PULL_UPS: [(pac::gpio::Gpio, u32, u32); 3] = [
    (pac::GPIOA, pupdr(&[8, 0, 1], 1), pupdr(&[8, 0, 1], 3)),
    (pac::GPIOE, pupdr(&[11, 13, 14], 1), pupdr(&[11, 13, 14], 3)),
    (pac::GPIOD, pupdr(&[14, 15], 1), pupdr(&[14, 15], 3)),
];

/// A PUPDR value with `bits` in the field of each of `pins`.
const fn pupdr(pins: &[u32], bits: u32) -> u32 {
    let (mut value, mut i) = (0, 0);
    while i < pins.len() {
        value |= bits << (2 * pins[i]);
        i += 1;
    }
    value
}

/// Turns the outputs' lines to bidirectional DShot's (active-low channels, idle high, the pins
/// pulled up for the answers) or back to the plain line.
#[inline(never)]
fn set_inverted(inverted: bool) {
    critical_section::with(|_| {
        for (r, mask) in timer_regs().into_iter().zip(MASKS) {
            // CCxP: bit 1 of each channel's four in CCER.
            let ccp = (0..4)
                .filter(|c| mask & (1 << c) != 0)
                .fold(0, |p, c| p | (2 << (4 * c)));
            r.ccer()
                .modify(|w| w.0 = if inverted { w.0 | ccp } else { w.0 & !ccp });
        }
        for (port, up, field) in PULL_UPS {
            port.pupdr()
                .modify(|w| w.0 = (w.0 & !field) | if inverted { up } else { 0 });
        }
    });
}

/// The channels each timer drives ([`timer_regs`]' order), a bit per channel index.
const MASKS: [u32; 3] = [0b1111, 0b1100, 0b0011];

/// The three timers' registers (TIM1, TIM4, TIM5) as a 16-bit general-purpose timer's: the
/// same layout for what listening touches.
fn timer_regs() -> [TimGp16; 3] {
    // SAFETY: the timers' own register blocks; these channels' registers belong to this task.
    [pac::TIM1.as_ptr(), pac::TIM4.as_ptr(), pac::TIM5.as_ptr()]
        .map(|base| unsafe { TimGp16::from_ptr(base) })
}

/// Each output's timer (index into [`timer_regs`]) and channel index.
const OUTPUT_CHANNELS: [(usize, usize); OUTPUTS] = [
    (0, 0),
    (0, 1),
    (0, 2),
    (0, 3),
    (1, 2),
    (1, 3),
    (2, 0),
    (2, 1),
];

/// The outputs whose captures go by DMA (all but FMU_CH6), in the order of their buffers.
const DMA_OUTPUTS: [usize; 7] = [0, 1, 2, 3, 4, 6, 7];

/// A timer's output set-up, kept while its channels listen.
struct OutputState {
    ccmr: [u32; 2],
    ccer: u32,
    arr: u32,
}

/// Turns timer `r`'s channels `mask` (bit per channel index) to input capture on both edges
/// (a 33 ns filter), each capture requesting DMA (or, `irq_mask`, the capture interrupt), the
/// counter free over 16 bits; returns the output set-up to restore.
#[inline(never)]
fn listen(r: TimGp16, mask: u32, irq_mask: u32) -> OutputState {
    let saved = OutputState {
        ccmr: [r.ccmr_output(0).read().0, r.ccmr_output(1).read().0],
        ccer: r.ccer().read().0,
        arr: r.arr().read().0,
    };
    // Channels off first (CCxS is writable only then): the pull-ups hold the lines high.
    r.ccer().write_value(regs::CcerGp16(0));
    let mut ccmr = saved.ccmr;
    let mut ccer = 0;
    for c in 0..4 {
        if mask & (1 << c) != 0 {
            let shift = (c % 2) * 8;
            // CCxS = 01 (its own pin), ICxF = 0011 (8 samples at 240 MHz), OCxM[3] clear.
            ccmr[c / 2] = (ccmr[c / 2] & !(0x1_00FF << shift)) | (0x31 << shift);
            // CCxE, CCxP and CCxNP: capture on both edges.
            ccer |= 0b1011 << (4 * c);
        }
    }
    r.ccmr_output(0).write_value(regs::CcmrOutputGp16(ccmr[0]));
    r.ccmr_output(1).write_value(regs::CcmrOutputGp16(ccmr[1]));
    r.arr().write_value(regs::ArrCore(0xFFFF));
    r.egr().write(|w| w.set_ug(true));
    r.sr().write_value(regs::SrGp16(0));
    r.ccer().write_value(regs::CcerGp16(ccer));
    // CCxDE (bits 9-12) for the DMA channels, CCxIE (bits 1-4) for the interrupt's.
    r.dier()
        .write_value(regs::DierGp16(((mask & !irq_mask) << 9) | (irq_mask << 1)));
    saved
}

/// Turns timer `r`'s channels back to the outputs `saved`, idle (compare 0), at the bit rate.
#[inline(never)]
fn speak(r: TimGp16, mask: u32, saved: &OutputState) {
    r.dier().write_value(regs::DierGp16(0));
    r.ccer().write_value(regs::CcerGp16(0));
    r.ccmr_output(0)
        .write_value(regs::CcmrOutputGp16(saved.ccmr[0]));
    r.ccmr_output(1)
        .write_value(regs::CcmrOutputGp16(saved.ccmr[1]));
    for c in 0..4 {
        if mask & (1 << c) != 0 {
            r.ccr(c).write_value(regs::Ccr1ch(0));
        }
    }
    r.arr().write_value(regs::ArrCore(saved.arr));
    r.egr().write(|w| w.set_ug(true));
    r.ccer().write_value(regs::CcerGp16(saved.ccer));
}

/// After a bidirectional frame: listens to every output for [`ANSWER_WINDOW_US`] and returns
/// each rotor's RPM (NaN for no or a wrong answer), for answer bits of `bit` timer counts.
async fn hear_answers(
    t: &mut EscTimers,
    edges: &mut [[u16; EDGES]; 7],
    bit: u16,
    poles: u8,
) -> [f32; OUTPUTS] {
    let r = timer_regs();
    let [c1, c2, c3, c4] = &mut t.capture;
    let [u1, u4, u5] = &mut t.up;
    let mut streams = [
        (u1.0.reborrow(), u1.2),
        (c1.0.reborrow(), c1.1),
        (c2.0.reborrow(), c2.1),
        (c3.0.reborrow(), c3.1),
        (u4.0.reborrow(), u4.2),
        (u5.0.reborrow(), u5.2),
        (c4.0.reborrow(), c4.1),
    ];
    let mut jobs = streams.iter_mut().zip(edges.iter_mut()).zip(DMA_OUTPUTS);
    let transfers: [dma::Transfer<'_>; 7] = core::array::from_fn(|_| {
        let Some((((dma, request), buffer), output)) = jobs.next() else {
            unreachable!("seven streams, seven buffers")
        };
        let (timer, channel) = OUTPUT_CHANNELS[output];
        start_capture(
            dma,
            *request,
            r[timer].ccr(channel).as_ptr() as *mut u16,
            buffer,
        )
    });
    CH6_COUNT.store(0, Relaxed);
    CH6_LOST.store(false, Relaxed);
    // FMU_CH6 (TIM4 CH4, bit 3) by its interrupt.
    let irq_masks = [0, 0b1000, 0];
    let saved: [OutputState; 3] = core::array::from_fn(|i| listen(r[i], MASKS[i], irq_masks[i]));
    Timer::after_micros(ANSWER_WINDOW_US).await;
    for i in 0..3 {
        speak(r[i], MASKS[i], &saved[i]);
    }
    let counts = transfers.map(stop_capture);
    let mut rpm = [f32::NAN; OUTPUTS];
    for ((buffer, &n), output) in edges.iter().zip(&counts).zip(DMA_OUTPUTS) {
        rpm[output] = rpm_of(&buffer[..n], bit, poles);
    }
    rpm[5] = ch6_rpm(bit, poles);
    rpm
}

/// Stops a capture's transfer; returns how many edges it copied.
#[inline(never)]
fn stop_capture(transfer: dma::Transfer<'_>) -> usize {
    let left = transfer.get_remaining_transfers() as usize;
    drop(transfer);
    EDGES.saturating_sub(left)
}

/// A rotor's RPM from its answer's edges, NaN for no answer or a wrong one.
#[inline(never)]
fn rpm_of(edges: &[u16], bit: u16, poles: u8) -> f32 {
    match answer::decode(edges, bit) {
        Ok(Answer::Erpm(erpm)) => answer::rpm(erpm, poles),
        _ => f32::NAN,
    }
}

/// FMU_CH6's RPM from the edges its interrupt stored (NaN if one was lost).
#[inline(never)]
fn ch6_rpm(bit: u16, poles: u8) -> f32 {
    if CH6_LOST.load(Relaxed) {
        return f32::NAN;
    }
    let edges = CH6_EDGES.lock(Cell::get);
    rpm_of(&edges[..CH6_COUNT.load(Relaxed).min(EDGES)], bit, poles)
}

/// Starts copying a channel's captures (from its register `from`) into `buffer`.
#[inline(never)]
fn start_capture<'a>(
    dma: &'a mut dma::Channel<'_>,
    request: u8,
    from: *mut u16,
    buffer: &'a mut [u16],
) -> dma::Transfer<'a> {
    // SAFETY: a timer channel's capture register, read by half-words into a buffer the
    // transfer borrows; every transfer is stopped (dropped) before the buffers are read.
    unsafe { dma.read(request, from, buffer, dma::TransferOptions::default()) }
}

/// TIM4's capture interrupt: FMU_CH6's (CH4's) edges while it listens.
#[interrupt]
fn TIM4() {
    let r = pac::TIM4;
    let sr = r.sr().read();
    if sr.ccif(3) {
        // Reading the capture clears its flag.
        let at = r.ccr(3).read().0 as u16;
        let n = CH6_COUNT.load(Relaxed);
        CH6_EDGES.lock(|edges| {
            let edges: &Cell<[u16]> = edges;
            if let Some(slot) = edges.as_slice_of_cells().get(n) {
                slot.set(at);
            }
        });
        CH6_COUNT.store(n.saturating_add(1), Relaxed);
    }
    if sr.ccof(3) {
        CH6_LOST.store(true, Relaxed);
        r.sr().write(|w| {
            w.0 = !0;
            w.set_ccof(3, false);
        });
    }
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
    let mut edges = [[0u16; EDGES]; 7];
    let mut inverted = false;
    interrupt::TIM4.set_priority(Priority::P0);
    // SAFETY: its handler above only stores FMU_CH6's captures, enabled while it listens.
    unsafe { interrupt::TIM4.enable() };
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
        let poles = TELEMETRY_POLES.load(Relaxed);
        let bidirectional = poles != 0 && protocol == EscProtocol::Dshot600;
        if bidirectional != inverted {
            set_inverted(bidirectional);
            inverted = bidirectional;
        }
        match protocol {
            EscProtocol::Dshot600 => {
                let encode = if bidirectional {
                    dshot::bidirectional_frame
                } else {
                    dshot::frame
                };
                let frames = fractions.map(|f| encode(dshot::throttle_value(f), false));
                // The buffers are sized for their timer's channels: these cannot fail.
                let _ = dshot::fill_burst(&frames[0..4], timing(&t.tim1), &mut burst1);
                let _ = dshot::fill_burst(&frames[4..6], timing(&t.tim4), &mut burst4);
                let _ = dshot::fill_burst(&frames[6..8], timing(&t.tim5), &mut burst5);
                let r = timer_regs();
                let [up1, up4, up5] = &mut t.up;
                let sending = [
                    start_burst(r[0], up1, MASKS[0], &burst1),
                    start_burst(r[1], up4, MASKS[1], &burst4),
                    start_burst(r[2], up5, MASKS[2], &burst5),
                ];
                for transfer in sending {
                    transfer.await;
                }
                for r in r {
                    r.dier().modify(|w| w.set_ude(false));
                }
                let rpm = if bidirectional {
                    let bit = answer::answer_bit_counts(timing(&t.tim1).period);
                    Some(hear_answers(&mut t, &mut edges, bit, poles).await)
                } else {
                    None
                };
                RPM.lock(|cell| cell.set(rpm));
            }
            EscProtocol::Pwm | EscProtocol::OneShot125 | EscProtocol::DroneCan => {
                RPM.lock(|cell| cell.set(None));
                set_pulses(&mut t.tim1, protocol, TIM1_CHANNELS, &fractions[0..4]);
                set_pulses(&mut t.tim4, protocol, TIM4_CHANNELS, &fractions[4..6]);
                set_pulses(&mut t.tim5, protocol, TIM5_CHANNELS, &fractions[6..8]);
            }
        }
    }
}
