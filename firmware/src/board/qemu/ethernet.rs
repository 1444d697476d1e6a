//! The mps2-an500's LAN9118 Ethernet controller (SMSC LAN9118 datasheet, "System Control and
//! Status Registers" and "TX/RX Data Path"; QEMU's `hw/net/lan9118.c`) as the HIL link's fast
//! transport, an `embedded-io-async` byte stream like the UART's
//! (docs/firmware.md#hil-transports).
//!
//! Why: QEMU hands the CMSDK UART's guest one byte per pass of its main loop, and a control
//! step moves about 200 bytes each way, so the UART caps HIL at about half of real time. The
//! LAN9118 takes and gives whole frames: QEMU's `socket` back end turns each frame into one
//! UDP datagram to the plant and back, one main-loop pass per frame.
//!
//! Framing is [`link::hil_ethernet`]'s. Receiving: the controller's own RX FIFOs (about
//! 10 KB) hold the frames until the link task reads them; the interrupt (RX status FIFO level)
//! only wakes the task, which then reads whole frames by 32-bit words. Sending: written bytes
//! are gathered into one frame, sent when it is full or on `flush` (the send task flushes
//! after each message group, so a control step's messages go as one frame).

use core::convert::Infallible;
use core::future::poll_fn;
use core::ptr::{read_volatile, write_volatile};
use core::sync::atomic::{AtomicU32, Ordering};
use core::task::Poll;

use embassy_sync::waitqueue::AtomicWaker;
use link::hil_ethernet::{self, HEADER_LEN, MAX_FRAME, MAX_PAYLOAD, PLANT_MAC, VEHICLE_MAC};

const BASE: usize = 0xA000_0000;
const RX_DATA_FIFO: usize = BASE;
const TX_DATA_FIFO: usize = BASE + 0x20;
const RX_STATUS_FIFO: usize = BASE + 0x40;
const ID_REV: usize = BASE + 0x50;
const IRQ_CFG: usize = BASE + 0x54;
const INT_STS: usize = BASE + 0x58;
const INT_EN: usize = BASE + 0x5C;
const FIFO_INT: usize = BASE + 0x68;
const TX_CFG: usize = BASE + 0x70;
const RX_FIFO_INF: usize = BASE + 0x7C;
const MAC_CSR_CMD: usize = BASE + 0xA4;
const MAC_CSR_DATA: usize = BASE + 0xA8;

/// `ID_REV`'s chip id (upper half).
const CHIP_ID: u32 = 0x0118;
/// `IRQ_CFG`: interrupt output on, active high, push-pull (what the NVIC line wants).
const IRQ_EN_HIGH_PUSH_PULL: u32 = (1 << 8) | (1 << 4) | 1;
/// `INT_STS` / `INT_EN`: RX status FIFO level (a frame has arrived).
const RSFL: u32 = 1 << 3;
/// `FIFO_INT`'s reset value with the RX status level at 0: interrupt from the first frame.
const FIFO_INT_FIRST_FRAME: u32 = 0x4800_0000;
/// `TX_CFG`: transmitter on, TX status FIFO may overrun (no one reads it).
const TX_ON_STATUS_OVERRUN: u32 = (1 << 1) | (1 << 2);
/// `MAC_CSR_CMD`: busy (start), write.
const MAC_CSR_WRITE: u32 = 1 << 31;
/// MAC registers (indirect, through `MAC_CSR_*`).
const MAC_CR: u32 = 1;
const MAC_ADDRH: u32 = 2;
const MAC_ADDRL: u32 = 3;
/// `MAC_CR`: transmitter and receiver on (unicast to our address and broadcast accepted).
const MAC_CR_TX_RX: u32 = (1 << 3) | (1 << 2);
/// RX status word: error summary.
const RX_STATUS_ERROR: u32 = 1 << 15;
/// TX command A: first and last segment of a frame.
const TX_CMD_A_WHOLE_FRAME: u32 = (1 << 13) | (1 << 12);

/// Largest frame the controller hands over, bytes (QEMU takes frames under 2,048 bytes and
/// adds a 4-byte CRC).
const MAX_RX_FRAME: usize = 2048 + 4;

/// The send buffer: the largest frame rounded up to whole words.
const TX_BUFFER: usize = MAX_FRAME.div_ceil(4) * 4;

/// Wakes the receiving task when a frame arrives.
static RX_WAKER: AtomicWaker = AtomicWaker::new();
/// Frames received that were not HIL's or were damaged.
static RX_REFUSED: AtomicU32 = AtomicU32::new(0);

fn read(addr: usize) -> u32 {
    // SAFETY: a register of the LAN9118 on this board.
    unsafe { read_volatile(addr as *const u32) }
}

fn write(addr: usize, value: u32) {
    // SAFETY: a register of the LAN9118 on this board.
    unsafe { write_volatile(addr as *mut u32, value) }
}

fn mac_write(register: u32, value: u32) {
    write(MAC_CSR_DATA, value);
    write(MAC_CSR_CMD, MAC_CSR_WRITE | register);
    // The access completes at once on QEMU; on a LAN9220 it takes a few bus cycles.
    while read(MAC_CSR_CMD) & MAC_CSR_WRITE != 0 {}
}

/// Brings the controller up with the vehicle's address; `None` if there is none on the bus.
pub fn init() -> Option<(EthernetRx, EthernetTx)> {
    if read(ID_REV) >> 16 != CHIP_ID {
        return None;
    }
    let [a0, a1, a2, a3, a4, a5] = VEHICLE_MAC;
    mac_write(MAC_ADDRL, u32::from_le_bytes([a0, a1, a2, a3]));
    mac_write(MAC_ADDRH, u32::from_le_bytes([a4, a5, 0, 0]));
    mac_write(MAC_CR, MAC_CR_TX_RX);
    write(TX_CFG, TX_ON_STATUS_OVERRUN);
    write(FIFO_INT, FIFO_INT_FIRST_FRAME);
    write(INT_STS, u32::MAX);
    write(INT_EN, 0);
    write(IRQ_CFG, IRQ_EN_HIGH_PUSH_PULL);
    Some((
        EthernetRx {
            frame: [0; MAX_RX_FRAME],
            at: 0,
            end: 0,
        },
        EthernetTx {
            frame: [0; TX_BUFFER],
            payload_len: 0,
        },
    ))
}

/// Frames refused so far (not HIL's, damaged, or announcing more bytes than they hold).
pub fn rx_refused() -> u32 {
    RX_REFUSED.load(Ordering::Relaxed)
}

/// The controller's interrupt: masks it and wakes the receiving task, which reads the frames
/// and unmasks it when the FIFO is empty.
pub extern "C" fn on_interrupt() {
    write(INT_EN, 0);
    RX_WAKER.wake();
}

/// Receiving half of the link.
pub struct EthernetRx {
    /// The frame being read.
    frame: [u8; MAX_RX_FRAME],
    /// Next MAVLink byte of it to hand out, and the end of its MAVLink bytes.
    at: usize,
    end: usize,
}

impl EthernetRx {
    /// Reads the next waiting frame into `frame`; false when none is waiting.
    fn next_frame(&mut self) -> bool {
        loop {
            if (read(RX_FIFO_INF) >> 16) & 0xFF == 0 {
                return false;
            }
            let status = read(RX_STATUS_FIFO);
            let len = ((status >> 16) & 0x3FFF) as usize;
            let words = len.div_ceil(4);
            for i in 0..words {
                // The FIFO's words hold the frame's bytes little-endian first.
                let word = read(RX_DATA_FIFO).to_le_bytes();
                if let Some(slot) = self.frame.get_mut(4 * i..4 * i + 4) {
                    slot.copy_from_slice(&word);
                }
            }
            if status & RX_STATUS_ERROR != 0 || len > MAX_RX_FRAME {
                RX_REFUSED.fetch_add(1, Ordering::Relaxed);
                continue;
            }
            match hil_ethernet::payload(&self.frame[..len]) {
                Ok(payload) => {
                    self.at = HEADER_LEN;
                    self.end = HEADER_LEN + payload.len();
                    return true;
                }
                Err(_) => {
                    RX_REFUSED.fetch_add(1, Ordering::Relaxed);
                }
            }
        }
    }
}

/// Sending half of the link: one frame being filled.
pub struct EthernetTx {
    /// The frame: header, then MAVLink bytes (and room to round it up to whole words).
    frame: [u8; TX_BUFFER],
    /// MAVLink bytes in it so far.
    payload_len: usize,
}

impl EthernetTx {
    /// Sends the frame gathered so far, if it holds anything.
    fn send(&mut self) {
        if self.payload_len == 0 {
            return;
        }
        let header = hil_ethernet::header(PLANT_MAC, VEHICLE_MAC, self.payload_len);
        self.frame[..HEADER_LEN].copy_from_slice(&header);
        let len = HEADER_LEN + self.payload_len;
        write(TX_DATA_FIFO, TX_CMD_A_WHOLE_FRAME | len as u32);
        write(TX_DATA_FIFO, len as u32);
        for word in self.frame[..len.div_ceil(4) * 4].chunks_exact(4) {
            write(
                TX_DATA_FIFO,
                u32::from_le_bytes([word[0], word[1], word[2], word[3]]),
            );
        }
        self.payload_len = 0;
    }
}

impl embedded_io_async::ErrorType for EthernetRx {
    type Error = Infallible;
}

impl embedded_io_async::ErrorType for EthernetTx {
    type Error = Infallible;
}

impl embedded_io_async::Read for EthernetRx {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
        if buf.is_empty() {
            return Ok(0);
        }
        loop {
            if self.at < self.end {
                let n = buf.len().min(self.end - self.at);
                let from = self.at;
                buf[..n].copy_from_slice(&self.frame[from..from + n]);
                self.at += n;
                return Ok(n);
            }
            if self.next_frame() {
                continue;
            }
            poll_fn(|cx| {
                RX_WAKER.register(cx.waker());
                // Cleared before the FIFO is looked at: a frame after this sets it again.
                write(INT_STS, RSFL);
                write(INT_EN, RSFL);
                if (read(RX_FIFO_INF) >> 16) & 0xFF != 0 {
                    Poll::Ready(())
                } else {
                    Poll::Pending
                }
            })
            .await;
        }
    }
}

impl embedded_io_async::Write for EthernetTx {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        if self.payload_len == MAX_PAYLOAD {
            self.send();
        }
        let n = buf.len().min(MAX_PAYLOAD - self.payload_len);
        let at = HEADER_LEN + self.payload_len;
        self.frame[at..at + n].copy_from_slice(&buf[..n]);
        self.payload_len += n;
        Ok(n)
    }

    async fn flush(&mut self) -> Result<(), Infallible> {
        self.send();
        Ok(())
    }
}
