//! MAVLink over the Pixhawk 6C's USB: a CDC-ACM serial port (embassy-usb) on the
//! full-speed OTG peripheral (D- PA11, D+ PA12, VBUS sensed on PA9, as PX4's fmu-v6c
//! `board.h` has it), so a laptop sees `/dev/ttyACM0` and `host-sim hil --serial /dev/ttyACM0`
//! is the bench set-up with a real board.
//!
//! The board's link ([`LinkRx`], [`LinkTx`]) is USB when a USB cable powers VBUS at start, and
//! TELEM1 otherwise: one link at a time. The USB device task and both link tasks run on the
//! link executor, one priority: the CDC-ACM halves share the class's state (a `RefCell`) with
//! the device task, which is sound only because none of them preempts another.

use embassy_stm32::peripherals::USB_OTG_FS;
use embassy_stm32::usart::{BufferedUartRx, BufferedUartTx};
use embassy_stm32::usb::Driver;
use embassy_usb::UsbDevice;
use embassy_usb::class::cdc_acm::{CdcAcmClass, Receiver, Sender, State};
use embedded_io_async::{ErrorKind, ErrorType, Read, Write};
use static_cell::StaticCell;

/// The USB driver of this board.
pub type UsbDriver = Driver<'static, USB_OTG_FS>;

/// Largest write per USB packet: one byte short of the 64-byte packet, so every packet ends
/// its transfer and the host passes it on at once (no zero-length packets needed).
const WRITE_CHUNK: usize = 63;

/// The USB serial port's receiving half, with the last packet's unread bytes.
pub struct UsbRx {
    receiver: Receiver<'static, UsbDriver>,
    packet: [u8; 64],
    start: usize,
    end: usize,
}
/// The USB serial port's sending half.
pub struct UsbTx(Sender<'static, UsbDriver>);

// SAFETY: the halves and the device task share the CDC-ACM state (`RefCell`s, not `Sync`);
// all three run on the link executor only (module docs), so no access preempts another.
unsafe impl Send for UsbRx {}
// SAFETY: as for `UsbRx`.
unsafe impl Send for UsbTx {}

/// The USB device, for its task on the link executor.
pub struct UsbDeviceTask(UsbDevice<'static, UsbDriver>);
// SAFETY: as for `UsbRx`: it runs on the link executor with the halves.
unsafe impl Send for UsbDeviceTask {}

impl ErrorType for UsbRx {
    type Error = ErrorKind;
}

impl Read for UsbRx {
    /// Waits for a host while none is connected.
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, ErrorKind> {
        while self.start == self.end {
            match self.receiver.read_packet(&mut self.packet).await {
                Ok(n) => (self.start, self.end) = (0, n.min(self.packet.len())),
                Err(_) => self.receiver.wait_connection().await,
            }
        }
        let n = buf.len().min(self.end - self.start);
        buf[..n].copy_from_slice(&self.packet[self.start..self.start + n]);
        self.start += n;
        Ok(n)
    }
}

impl ErrorType for UsbTx {
    type Error = ErrorKind;
}

impl Write for UsbTx {
    /// Waits for a host while none is connected (the control step then drops its telemetry,
    /// counted, rather than wait).
    async fn write(&mut self, buf: &[u8]) -> Result<usize, ErrorKind> {
        let len = buf.len().min(WRITE_CHUNK);
        loop {
            match self.0.write_packet(&buf[..len]).await {
                Ok(()) => return Ok(len),
                Err(_) => self.0.wait_connection().await,
            }
        }
    }

    async fn flush(&mut self) -> Result<(), ErrorKind> {
        Ok(())
    }
}

/// The board's MAVLink link, receiving half: USB or TELEM1.
pub enum LinkRx {
    /// TELEM1 (UART7).
    Telem1(BufferedUartRx<'static>),
    /// USB CDC-ACM.
    Usb(UsbRx),
}

/// The board's MAVLink link, sending half: USB or TELEM1.
pub enum LinkTx {
    /// TELEM1 (UART7).
    Telem1(BufferedUartTx<'static>),
    /// USB CDC-ACM.
    Usb(UsbTx),
}

impl ErrorType for LinkRx {
    type Error = ErrorKind;
}

impl Read for LinkRx {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, ErrorKind> {
        match self {
            Self::Telem1(rx) => rx.read(buf).await.map_err(|_| ErrorKind::Other),
            Self::Usb(rx) => rx.read(buf).await,
        }
    }
}

impl ErrorType for LinkTx {
    type Error = ErrorKind;
}

impl Write for LinkTx {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, ErrorKind> {
        match self {
            Self::Telem1(tx) => tx.write(buf).await.map_err(|_| ErrorKind::Other),
            Self::Usb(tx) => tx.write(buf).await,
        }
    }

    /// The send task flushes after each group of messages (the end of a frame on the QEMU
    /// board's Ethernet link). Here the bytes are in TELEM1's ring or USB's packets already:
    /// that is as far as the link needs them, and waiting for TELEM1 to drain would hold the
    /// send task for the whole group's time on the wire.
    async fn flush(&mut self) -> Result<(), ErrorKind> {
        Ok(())
    }
}

static CONFIG_DESCRIPTOR: StaticCell<[u8; 256]> = StaticCell::new();
/// The BOS descriptor embassy-usb writes: its 5-byte header and the USB 2.0 extension's 7 bytes
/// (no Microsoft OS descriptors here), 12 of these 32 bytes (its examples' 256 cost the static
/// RAM budget 224 bytes).
const BOS_LEN: usize = 32;
static BOS_DESCRIPTOR: StaticCell<[u8; BOS_LEN]> = StaticCell::new();
static CONTROL_BUF: StaticCell<[u8; 64]> = StaticCell::new();
static CDC_STATE: StaticCell<State<'static>> = StaticCell::new();

/// The USB device on `driver` with one CDC-ACM port: the device (its task runs it) and the
/// port's halves.
pub fn open(driver: UsbDriver) -> (UsbDeviceTask, UsbRx, UsbTx) {
    // pid.codes' test VID/PID; a product needs its own.
    let mut config = embassy_usb::Config::new(0x1209, 0x0001);
    config.manufacturer = Some("rail-rotor");
    config.product = Some("flight controller (MAVLink)");
    config.max_power = 100;
    config.max_packet_size_0 = 64;
    let mut builder = embassy_usb::Builder::new(
        driver,
        config,
        CONFIG_DESCRIPTOR.init([0; 256]),
        BOS_DESCRIPTOR.init([0; BOS_LEN]),
        &mut [],
        CONTROL_BUF.init([0; 64]),
    );
    let class = CdcAcmClass::new(&mut builder, CDC_STATE.init(State::new()), 64);
    let (sender, receiver) = class.split();
    let device = builder.build();
    let rx = UsbRx {
        receiver,
        packet: [0; 64],
        start: 0,
        end: 0,
    };
    (UsbDeviceTask(device), rx, UsbTx(sender))
}

/// Runs the USB device (enumeration, control requests) forever.
#[embassy_executor::task]
pub async fn usb_device(mut device: UsbDeviceTask) -> ! {
    device.0.run().await
}
