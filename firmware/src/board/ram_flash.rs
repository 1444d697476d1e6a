//! A NOR flash in RAM: the parameters' store on a board whose non-volatile memory has no
//! driver yet (the Pixhawk 6C's FRAM). It behaves as NOR flash does (erase to 0xFF, writes
//! clear bits) so the store runs its real code, but forgets everything at power-off; the
//! firmware reports that at start.

use embedded_storage_async::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};

/// Erase page, bytes.
pub const PAGE: usize = 1024;
/// Bytes in all.
pub const CAPACITY: usize = 4 * PAGE;

/// The flash.
pub struct RamFlash {
    bytes: [u8; CAPACITY],
}

impl RamFlash {
    /// Erased.
    pub const fn new() -> Self {
        Self {
            bytes: [0xFF; CAPACITY],
        }
    }
}

impl Default for RamFlash {
    fn default() -> Self {
        Self::new()
    }
}

impl ErrorType for RamFlash {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for RamFlash {
    const READ_SIZE: usize = 1;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        crate::board::check_flash_access(offset, bytes.len(), 1, self.capacity())?;
        let at = offset as usize;
        bytes.copy_from_slice(&self.bytes[at..at + bytes.len()]);
        Ok(())
    }

    fn capacity(&self) -> usize {
        CAPACITY
    }
}

impl NorFlash for RamFlash {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = PAGE;

    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        crate::board::check_flash_access(
            from,
            (to as usize).saturating_sub(from as usize),
            Self::ERASE_SIZE,
            self.capacity(),
        )?;
        if to < from {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        self.bytes[from as usize..to as usize].fill(0xFF);
        Ok(())
    }

    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        crate::board::check_flash_access(offset, bytes.len(), Self::WRITE_SIZE, self.capacity())?;
        let at = offset as usize;
        for (cell, &b) in self.bytes[at..at + bytes.len()].iter_mut().zip(bytes) {
            *cell &= b;
        }
        Ok(())
    }
}
