//! Which of the emulated board's two links carries MAVLink (docs/firmware.md#hil-transports):
//! the LAN9118 Ethernet controller when QEMU's kernel command line says `hil-link=ethernet`
//! (`host-sim hil` starts QEMU so, with a `socket` network back end to the plant), otherwise
//! CMSDK UART 0 (QEMU's `-serial`; a serial device for `hil --serial`, or a person's own
//! QEMU). One link at a time, chosen at start, as the Pixhawk chooses USB or TELEM1.

use core::convert::Infallible;

use cortex_m_semihosting::nr;

use super::{ethernet, uart};

/// The command-line word that picks the Ethernet link.
const ETHERNET_WORD: &[u8] = b"hil-link=ethernet";

/// Receiving half of the link in use.
#[allow(
    clippy::large_enum_variant,
    reason = "one for the whole run, owned by the link task; no allocator to box the frame buffer"
)]
pub enum LinkRx {
    /// CMSDK UART 0.
    Uart(uart::UartRx),
    /// The LAN9118.
    Ethernet(ethernet::EthernetRx),
}

/// Sending half of the link in use.
#[allow(
    clippy::large_enum_variant,
    reason = "one for the whole run, owned by the send task; no allocator to box the frame buffer"
)]
pub enum LinkTx {
    /// CMSDK UART 0.
    Uart(uart::UartTx),
    /// The LAN9118.
    Ethernet(ethernet::EthernetTx),
}

/// Calls `f` with QEMU's command line for the image (`-append`, through semihosting's
/// `SYS_GET_CMDLINE`), if it has one.
fn with_command_line<R>(f: impl FnOnce(&[u8]) -> R) -> Option<R> {
    let mut text = [0u8; 256];
    let mut block = [text.as_mut_ptr() as usize, text.len()];
    // SAFETY: SYS_GET_CMDLINE writes at most `block[1]` bytes to `block[0]` and the length it
    // wrote back to `block[1]`; both live for the call.
    let failed =
        unsafe { cortex_m_semihosting::syscall1(nr::GET_CMDLINE, block.as_mut_ptr() as usize) };
    if failed != 0 {
        return None;
    }
    let len = block[1].min(text.len());
    Some(f(&text[..len]))
}

/// Whether QEMU's command line for the image holds `word`.
pub fn command_line_has(word: &[u8]) -> bool {
    with_command_line(|text| text.split(|b| b.is_ascii_whitespace()).any(|w| w == word))
        .unwrap_or(false)
}

/// The decimal number after `prefix` (e.g. `max-robots=`) in a word of QEMU's command line
/// for the image, if one is there and is a number.
pub fn command_line_number(prefix: &[u8]) -> Option<u32> {
    with_command_line(|text| {
        let digits = text
            .split(|b| b.is_ascii_whitespace())
            .find_map(|w| w.strip_prefix(prefix))?;
        core::str::from_utf8(digits).ok()?.parse().ok()
    })
    .flatten()
}

/// Brings up the link the command line picks (the UART when the Ethernet controller is
/// missing); returns its halves and whether it is the Ethernet link.
pub fn init() -> (LinkRx, LinkTx, bool) {
    if command_line_has(ETHERNET_WORD)
        && let Some((rx, tx)) = ethernet::init()
    {
        return (LinkRx::Ethernet(rx), LinkTx::Ethernet(tx), true);
    }
    let (rx, tx) = uart::init();
    (LinkRx::Uart(rx), LinkTx::Uart(tx), false)
}

impl embedded_io_async::ErrorType for LinkRx {
    type Error = Infallible;
}

impl embedded_io_async::ErrorType for LinkTx {
    type Error = Infallible;
}

impl embedded_io_async::Read for LinkRx {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, Infallible> {
        match self {
            Self::Uart(rx) => rx.read(buf).await,
            Self::Ethernet(rx) => rx.read(buf).await,
        }
    }
}

impl embedded_io_async::Write for LinkTx {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
        match self {
            Self::Uart(tx) => tx.write(buf).await,
            Self::Ethernet(tx) => tx.write(buf).await,
        }
    }

    async fn flush(&mut self) -> Result<(), Infallible> {
        match self {
            Self::Uart(tx) => tx.flush().await,
            Self::Ethernet(tx) => tx.flush().await,
        }
    }
}
