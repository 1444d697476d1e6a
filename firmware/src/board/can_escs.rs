//! DroneCAN ESCs on the Pixhawk 6C's CAN1: FDCAN1 on PD0 (RX) and PD1 (TX) through the
//! board's transceiver, classic CAN at [`BITRATE`] (docs/hardware.md#can-escs). The decisions
//! (what goes out each update, what a frame means, which ESC failed) are
//! [`drivers::dronecan::esc_output`]'s, host-tested; this is its glue.
//!
//! The control step hands its commands over with [`command`]; the sending task, at the
//! control priority, puts each step's `RawCommand` (and a `NodeStatus` a second) on the bus,
//! or stop commands each [`FEED_TIMEOUT`] without a step. The receiving task hands every
//! frame to the same core, whose RPM and failed ESCs the control step reads ([`rpm`],
//! [`failed`]) while `ESC_PROTOCOL` is DroneCAN.

use core::cell::RefCell;

use drivers::dronecan::esc_bus::MAX_ESCS;
use drivers::dronecan::esc_output::{CanEscCommand, CanEscOutput};
use drivers::dronecan::transfer::CanFrame;
use drivers::esc_gate::EscCommand;
use drivers::pulse::EscProtocol;
use embassy_stm32::can::{self, CanRx, CanTx, Frame};
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use embassy_time::{Duration, Instant, with_timeout};

/// The bus's bit rate, as PX4 runs its ESC bus (`UAVCAN_BITRATE`).
pub const BITRATE: u32 = 1_000_000;
/// No command for this long sends stop commands (10 control steps at 400 Hz).
pub const FEED_TIMEOUT: Duration = Duration::from_millis(25);

static COMMAND: Signal<CriticalSectionRawMutex, CanEscCommand> = Signal::new();

/// The core, shared by the two tasks and the control step's reads.
static OUTPUT: Mutex<CriticalSectionRawMutex, RefCell<CanEscOutput>> =
    Mutex::new(RefCell::new(CanEscOutput::new(1)));

/// Hands one control step's commands (fractions of full command, robot `j` at `j`) to the CAN
/// ESCs: sent while `protocol` is DroneCAN, zeros unless `armed`.
pub fn command(protocol: EscProtocol, fractions: &[f32], armed: bool) {
    let mut all = [0.0; MAX_ESCS];
    for (slot, &f) in all.iter_mut().zip(fractions) {
        *slot = f;
    }
    COMMAND.signal(CanEscCommand {
        command: EscCommand {
            protocol,
            fractions: all,
            armed,
        },
        escs: fractions.len().min(MAX_ESCS),
    });
}

fn now_us() -> u64 {
    Instant::now().as_micros()
}

/// Each rotor's RPM from its ESC's latest Status, while DroneCAN is in force.
pub fn rpm() -> Option<[f32; MAX_ESCS]> {
    let now = now_us();
    OUTPUT.lock(|o| o.borrow().rpm(now))
}

/// The payload's ESCs gone silent or saying they failed (bit `j`: robot `j + 1`).
pub fn failed() -> u16 {
    let now = now_us();
    OUTPUT.lock(|o| o.borrow().failed(now))
}

/// What ESCs `4 message` to `4 message + 3` last said in their Status beside the RPM (NaN
/// for one not heard of within its RPM's age), while DroneCAN is in force.
pub fn electrical(message: usize) -> Option<link::esc::EscElectrical> {
    use drivers::dronecan::esc_bus::RPM_MAX_AGE_US;
    use link::esc::{ESCS_PER_MESSAGE, EscElectrical};
    let now = now_us();
    OUTPUT.lock(|o| {
        let o = o.borrow();
        if !o.active() {
            return None;
        }
        let mut e = EscElectrical::NONE;
        for k in 0..ESCS_PER_MESSAGE {
            let Some(r) = o.bus().esc(ESCS_PER_MESSAGE * message + k) else {
                continue;
            };
            if now.saturating_sub(r.time_us) > RPM_MAX_AGE_US {
                continue;
            }
            e.voltage[k] = r.status.voltage;
            e.current[k] = r.status.current;
            // The Status carries kelvin.
            e.temperature_c[k] = r.status.temperature - 273.15;
            e.errors[k] = r.status.error_count;
        }
        Some(e)
    })
}

/// Sets this node's ID (`UAVCAN_NODE_ID`), taken while disarmed.
pub fn set_node_id(node: u8) {
    OUTPUT.lock(|o| {
        let mut o = o.borrow_mut();
        if o.bus().own_node() != node {
            *o = CanEscOutput::new(node);
        }
    });
}

/// Opens CAN1 at [`BITRATE`], or says why not.
pub fn open(
    peripheral: embassy_stm32::Peri<'static, embassy_stm32::peripherals::FDCAN1>,
    rx: embassy_stm32::Peri<'static, embassy_stm32::peripherals::PD0>,
    tx: embassy_stm32::Peri<'static, embassy_stm32::peripherals::PD1>,
) -> (CanTx<'static>, CanRx<'static>) {
    let mut configurator = can::CanConfigurator::new(peripheral, rx, tx, super::pixhawk6c::Irqs);
    configurator.set_bitrate(BITRATE);
    let (tx, rx, _) = configurator.into_normal_mode().split();
    (tx, rx)
}

/// Sends each update's frames, forever.
#[embassy_executor::task]
pub async fn send(mut tx: CanTx<'static>) {
    let mut frames = heapless::Vec::<CanFrame, 8>::new();
    loop {
        let command = with_timeout(FEED_TIMEOUT, COMMAND.wait()).await.ok();
        let now = now_us();
        frames.clear();
        OUTPUT.lock(|o| {
            o.borrow_mut().update(command.as_ref(), now, |f| {
                let _ = frames.push(f);
            })
        });
        for f in &frames {
            if let Ok(frame) = Frame::new_extended(f.id, f.bytes()) {
                // Waits for room in the transmit FIFO; a frame of lower priority it displaced
                // is dropped (the next step sends a fresh command).
                let _ = tx.write(&frame).await;
            }
        }
    }
}

/// Hands every frame received to the core, forever.
#[embassy_executor::task]
pub async fn receive(mut rx: CanRx<'static>) {
    loop {
        let Ok(envelope) = rx.read().await else {
            // A bus error (the error counters count it); the next frame is read again.
            continue;
        };
        let frame = envelope.frame;
        let embedded_can::Id::Extended(id) = *frame.id() else {
            continue;
        };
        let data = frame.data();
        let mut bytes = [0u8; 8];
        bytes[..data.len()].copy_from_slice(data);
        let f = CanFrame {
            id: id.as_raw(),
            data: bytes,
            len: data.len() as u8,
        };
        let now = now_us();
        OUTPUT.lock(|o| {
            let _ = o.borrow_mut().receive(&f, now);
        });
    }
}
