//! The Pixhawk 6C's 32 KiB SPI FRAM (an FM25V02A-class part on SPI2, chip select PD4:
//! PX4 `boards/px4/fmu-v6c/src/spi.cpp`, `SPIDEV_FLASH(0)` on `SPI::Bus::SPI2` with
//! `SPI::CS{GPIO::PortD, GPIO::Pin4}`; pins in `nuttx-config/include/board.h`: SCK PD3,
//! MISO PC2, MOSI PC3) as the NOR flash the parameters' store expects.
//!
//! FRAM writes in place without erase or wait, and survives power loss at any byte; the store
//! (`onboard::store`, on `sequential-storage`) is written for NOR flash, so this presents the
//! FRAM as NOR: an erase writes 0xFF over whole pages, a write stores bytes as given. The
//! command set (FM25V02A datasheet, "Command structure"): WREN 0x06 before every write, WRITE
//! 0x02 and READ 0x03, each followed by a two-byte address.
//!
//! The transfers are blocking (polled, no DMA): a parameter write is about 20 bytes, 16 us at
//! 10 MHz, and the link task that writes runs below the control task, which preempts it.
//! DMA cost 9 KiB of flash the image does not have to spare.

use embassy_stm32::gpio::Output;
use embassy_stm32::mode::Blocking;
use embassy_stm32::spi::Spi;
use embedded_storage_async::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};

/// Bytes in the part.
pub const CAPACITY: usize = 32 * 1024;
/// The page an erase covers (the store's unit; FRAM itself has none).
pub const PAGE: usize = 1024;

/// Write enable.
const WREN: u8 = 0x06;
/// Write from the address on.
const WRITE: u8 = 0x02;
/// Read from the address on.
const READ: u8 = 0x03;

/// Bytes of 0xFF an erase writes per transfer.
const ERASE_CHUNK: usize = 64;

/// The FRAM on its bus.
pub struct Fram {
    spi: Spi<'static, Blocking, embassy_stm32::spi::mode::Master>,
    cs: Output<'static>,
}

impl Fram {
    /// The part on `spi` with chip select `cs` (high: deselected).
    pub fn new(
        spi: Spi<'static, Blocking, embassy_stm32::spi::mode::Master>,
        cs: Output<'static>,
    ) -> Self {
        Self { spi, cs }
    }

    /// One transaction: `command` and the address, then `data` out.
    fn write_at(&mut self, offset: u32, data: &[u8]) -> Result<(), NorFlashErrorKind> {
        self.cs.set_low();
        let enabled = self.spi.blocking_write(&[WREN]);
        self.cs.set_high();
        enabled.map_err(|_| NorFlashErrorKind::Other)?;
        let [_, _, hi, lo] = offset.to_be_bytes();
        self.cs.set_low();
        let mut result = self.spi.blocking_write(&[WRITE, hi, lo]);
        if result.is_ok() {
            result = self.spi.blocking_write(data);
        }
        self.cs.set_high();
        result.map_err(|_| NorFlashErrorKind::Other)
    }
}

impl ErrorType for Fram {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for Fram {
    const READ_SIZE: usize = 1;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        super::check_flash_access(offset, bytes.len(), 1, CAPACITY)?;
        let [_, _, hi, lo] = offset.to_be_bytes();
        self.cs.set_low();
        let mut result = self.spi.blocking_write(&[READ, hi, lo]);
        if result.is_ok() {
            result = self.spi.blocking_read(bytes);
        }
        self.cs.set_high();
        result.map_err(|_| NorFlashErrorKind::Other)
    }

    fn capacity(&self) -> usize {
        CAPACITY
    }
}

impl NorFlash for Fram {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = PAGE;

    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        if to < from {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        super::check_flash_access(from, (to - from) as usize, PAGE, CAPACITY)?;
        let blank = [0xFF; ERASE_CHUNK];
        let mut at = from;
        while at < to {
            let n = (to - at).min(ERASE_CHUNK as u32);
            self.write_at(at, &blank[..n as usize])?;
            at += n;
        }
        Ok(())
    }

    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        super::check_flash_access(offset, bytes.len(), Self::WRITE_SIZE, CAPACITY)?;
        self.write_at(offset, bytes)
    }
}
