//! The emulated board's RC receiver port: CMSDK APB UART 1 (0x4000_5000, receive interrupt 2;
//! QEMU's second `-serial`), receive only, interrupt-driven like UART 0 ([`super::uart`]).
//! `host-sim hil --rc` writes CRSF frames into it (docs/hil.md). QEMU models no baud rate,
//! parity or inversion, and its UART cannot tell an idle line: the line settings are taken as
//! given and every read says not idle (the CRC still drops what is cut short; QEMU's character
//! device loses no byte).

use core::ptr::{read_volatile, write_volatile};

use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::pipe::Pipe;

use super::uart::{CTRL_RX_EN, CTRL_RX_INT_EN, INT_RX, MIN_BAUDDIV, STATE_RX_FULL};
use crate::board::{RcRead, RcSerial};
use drivers::rc_receiver::{LineSettings, RcPort};

const BASE: usize = 0x4000_5000;
const DATA: usize = BASE;
const STATE: usize = BASE + 0x04;
const CTRL: usize = BASE + 0x08;
const INTCLEAR: usize = BASE + 0x0C;
const BAUDDIV: usize = BASE + 0x10;

/// Received bytes not yet read by the receiver task (a few frames).
static RX: Pipe<CriticalSectionRawMutex, 256> = Pipe::new();
/// Bytes dropped because the task fell a whole buffer behind.
static OVERRUN: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(false);

fn read(addr: usize) -> u32 {
    // SAFETY: a register of UART 1 on this board.
    unsafe { read_volatile(addr as *const u32) }
}

fn write(addr: usize, value: u32) {
    // SAFETY: a register of UART 1 on this board.
    unsafe { write_volatile(addr as *mut u32, value) }
}

/// UART 1 receive interrupt.
pub extern "C" fn on_rx_interrupt() {
    write(INTCLEAR, INT_RX);
    while read(STATE) & STATE_RX_FULL != 0 {
        let byte = read(DATA) as u8;
        if RX.try_write(&[byte]).is_err() {
            OVERRUN.store(true, core::sync::atomic::Ordering::Relaxed);
        }
    }
}

/// The receiver's port: UART 1, whatever `RC_PORT_CONFIG` names (the emulated board has one).
pub struct RcUart;

impl RcUart {
    /// Enables UART 1's receiver and its interrupt.
    pub fn init() -> Self {
        write(BAUDDIV, MIN_BAUDDIV);
        write(CTRL, CTRL_RX_EN | CTRL_RX_INT_EN);
        Self
    }
}

impl RcSerial for RcUart {
    fn open(&mut self, _port: RcPort, _line: LineSettings) -> Result<(), &'static str> {
        RX.clear();
        Ok(())
    }

    async fn read(&mut self, buf: &mut [u8]) -> RcRead {
        let len = RX.read(buf).await;
        RcRead {
            len,
            line_error: OVERRUN.swap(false, core::sync::atomic::Ordering::Relaxed),
            idle: false,
        }
    }
}
