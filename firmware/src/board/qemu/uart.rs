//! The CMSDK APB UART 0 of the mps2-an500 (Arm CMSDK technical reference, "APB UART"; QEMU's
//! `hw/char/cmsdk-apb-uart.c`), interrupt-driven, as an `embedded-io-async` byte stream.
//!
//! Its receive register holds one byte, so the receive interrupt moves each byte at once into
//! a ring buffer ([`embassy_sync::pipe::Pipe`]) the link task reads from; QEMU holds further
//! bytes back until the register is read, so nothing is lost. Sending goes the other way:
//! the task fills a ring buffer and the transmit interrupt drains it while the transmitter
//! takes bytes.

use core::convert::Infallible;
use core::ptr::{read_volatile, write_volatile};
use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::pipe::Pipe;

const BASE: usize = 0x4000_4000;
const DATA: usize = BASE;
const STATE: usize = BASE + 0x04;
const CTRL: usize = BASE + 0x08;
const INTCLEAR: usize = BASE + 0x0C;
const BAUDDIV: usize = BASE + 0x10;

const STATE_TX_FULL: u32 = 1 << 0;
/// `STATE`: a received byte waits in the data register.
pub(super) const STATE_RX_FULL: u32 = 1 << 1;
const CTRL_TX_EN: u32 = 1 << 0;
/// `CTRL`: the receiver on.
pub(super) const CTRL_RX_EN: u32 = 1 << 1;
const CTRL_TX_INT_EN: u32 = 1 << 2;
/// `CTRL`: the receive interrupt on.
pub(super) const CTRL_RX_INT_EN: u32 = 1 << 3;
const INT_TX: u32 = 1 << 0;
/// `INTSTATUS`/`INTCLEAR`: the receive interrupt.
pub(super) const INT_RX: u32 = 1 << 1;
/// Smallest divider the UART accepts (QEMU models no baud rate; below 16 it refuses to send).
pub(super) const MIN_BAUDDIV: u32 = 16;

/// Received bytes not yet read by the link task.
static RX: Pipe<CriticalSectionRawMutex, 1024> = Pipe::new();
/// Bytes waiting to be sent (a whole control step's messages fit).
static TX: Pipe<CriticalSectionRawMutex, 2048> = Pipe::new();
/// The transmitter has nothing in flight: the next write must start it.
static TX_IDLE: AtomicBool = AtomicBool::new(true);
/// Received bytes dropped because the link task fell behind by a whole buffer.
static RX_DROPPED: AtomicU32 = AtomicU32::new(0);

fn read(addr: usize) -> u32 {
    // SAFETY: a register of UART 0 on this board.
    unsafe { read_volatile(addr as *const u32) }
}

fn write(addr: usize, value: u32) {
    // SAFETY: a register of UART 0 on this board.
    unsafe { write_volatile(addr as *mut u32, value) }
}

/// Enables the UART with both interrupts; returns its two halves.
pub fn init() -> (UartRx, UartTx) {
    write(BAUDDIV, MIN_BAUDDIV);
    write(
        CTRL,
        CTRL_TX_EN | CTRL_RX_EN | CTRL_TX_INT_EN | CTRL_RX_INT_EN,
    );
    (UartRx, UartTx)
}

/// Received bytes dropped so far (the receive buffer was full).
pub fn rx_dropped() -> u32 {
    RX_DROPPED.load(Ordering::Relaxed)
}

/// Moves bytes from the send buffer to the transmitter while it takes them. Runs with the
/// transmit interrupt's priority or inside a critical section.
fn pump() {
    let mut byte = [0u8; 1];
    while read(STATE) & STATE_TX_FULL == 0 {
        match TX.try_read(&mut byte) {
            Ok(1) => write(DATA, u32::from(byte[0])),
            _ => {
                TX_IDLE.store(true, Ordering::Relaxed);
                return;
            }
        }
    }
}

/// UART 0 receive interrupt.
pub extern "C" fn on_rx_interrupt() {
    write(INTCLEAR, INT_RX);
    while read(STATE) & STATE_RX_FULL != 0 {
        let byte = read(DATA) as u8;
        if RX.try_write(&[byte]).is_err() {
            RX_DROPPED.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// UART 0 transmit interrupt.
pub extern "C" fn on_tx_interrupt() {
    write(INTCLEAR, INT_TX);
    pump();
}

/// Receiving half of the link.
pub struct UartRx;

/// Sending half of the link.
pub struct UartTx;

impl embedded_io_async::ErrorType for UartRx {
    type Error = Infallible;
}

impl embedded_io_async::ErrorType for UartTx {
    type Error = Infallible;
}

impl embedded_io_async::Read for UartRx {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
        Ok(RX.read(buf).await)
    }
}

impl embedded_io_async::Write for UartTx {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        let n = TX.write(buf).await;
        critical_section::with(|_| {
            if TX_IDLE.swap(false, Ordering::Relaxed) {
                pump();
            }
        });
        Ok(n)
    }

    async fn flush(&mut self) -> Result<(), Infallible> {
        // The bytes are in the send buffer and the transmitter is running: that is as far as
        // the link needs them.
        Ok(())
    }
}
