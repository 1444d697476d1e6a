//! A flash in RAM for the parameter store, shaped as the Pixhawk 6C's FRAM (`firmware`'s
//! `board::fram`: 32 KiB, 1 KiB pages, 4-byte writes, parameters in the first 8 pages and the
//! payload description's two slots in the next 2, the stored mission's two in the 2 after), with NOR semantics: a write can only
//! clear bits (`sequential-storage` never needs more), an erase sets a page to `0xFF`.

use embedded_storage_async::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};

/// Bytes of the flash.
pub const CAPACITY: usize = 32 * 1024;
/// Bytes of an erase page.
pub const PAGE: usize = 1024;
/// The parameters' range (the Pixhawk 6C's `PARAM_RANGE`).
pub const PARAM_RANGE: core::ops::Range<u32> = 0..(8 * PAGE) as u32;
/// The payload description's range (the Pixhawk 6C's `PAYLOAD_RANGE`).
pub const PAYLOAD_RANGE: core::ops::Range<u32> = (8 * PAGE) as u32..(10 * PAGE) as u32;
/// The stored mission's range (the Pixhawk 6C's `MISSION_RANGE`).
pub const MISSION_RANGE: core::ops::Range<u32> = (10 * PAGE) as u32..(12 * PAGE) as u32;

/// The flash: its bytes, blank (`0xFF`) at first.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MemFlash {
    /// The contents.
    pub bytes: Vec<u8>,
}

impl Default for MemFlash {
    fn default() -> Self {
        Self::new()
    }
}

impl MemFlash {
    /// A blank flash.
    pub fn new() -> Self {
        Self {
            bytes: vec![0xFF; CAPACITY],
        }
    }
}

fn check(offset: u32, len: usize, align: usize) -> Result<usize, NorFlashErrorKind> {
    let offset = offset as usize;
    if !offset.is_multiple_of(align) || !len.is_multiple_of(align) {
        return Err(NorFlashErrorKind::NotAligned);
    }
    match offset.checked_add(len) {
        Some(end) if end <= CAPACITY => Ok(offset),
        _ => Err(NorFlashErrorKind::OutOfBounds),
    }
}

impl ErrorType for MemFlash {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for MemFlash {
    const READ_SIZE: usize = 1;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        let at = check(offset, bytes.len(), Self::READ_SIZE)?;
        bytes.copy_from_slice(&self.bytes[at..at + bytes.len()]);
        Ok(())
    }

    fn capacity(&self) -> usize {
        CAPACITY
    }
}

impl NorFlash for MemFlash {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = PAGE;

    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        if to < from {
            return Err(NorFlashErrorKind::OutOfBounds);
        }
        let at = check(from, (to - from) as usize, PAGE)?;
        self.bytes[at..to as usize].fill(0xFF);
        Ok(())
    }

    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        let at = check(offset, bytes.len(), Self::WRITE_SIZE)?;
        for (cell, &b) in self.bytes[at..at + bytes.len()].iter_mut().zip(bytes) {
            *cell &= b;
        }
        Ok(())
    }
}
