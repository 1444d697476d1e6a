//! A NOR flash for QEMU whose bytes outlive the emulator: a host
//! file, `firmware-params.bin` in QEMU's working directory, reached through semihosting file
//! I/O (`SYS_OPEN`, `SYS_SEEK`, `SYS_READ`, `SYS_WRITE`; QEMU's `-semihosting-config
//! enable=on,target=native`). It behaves as NOR flash does: erase sets whole pages to 0xFF, a
//! write only clears bits (read, AND, write back), so the parameter store above it runs the
//! same code as on a board. `host-sim hil --storage DIR` starts QEMU in `DIR` so a restart
//! finds the file; without it each run gets an empty flash.
//!
//! No flash at all (the file cannot be opened) is an error on every access: the parameters
//! then stay at their defaults and the ground is told why.

use cortex_m_semihosting::{nr, syscall};
use embedded_storage_async::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};

/// Erase page, bytes.
pub const PAGE: usize = 4096;
/// Pages of the file.
pub const PAGES: usize = PARAM_PAGES + 4;
/// Pages of the parameters; the two after them hold the payload description, the last two
/// the mission.
pub const PARAM_PAGES: usize = 4;
/// Name of the host file, NUL-terminated for `SYS_OPEN`.
const FILE_NAME: &[u8] = b"firmware-params.bin\0";
/// Bytes moved per semihosting call.
const CHUNK: usize = 256;

/// The flash in a host file.
pub struct FileFlash {
    handle: Option<usize>,
}

fn host_call_failed() -> NorFlashErrorKind {
    NorFlashErrorKind::Other
}

impl FileFlash {
    /// Opens the host file (creating it erased when it is missing or short).
    pub fn open() -> Self {
        let name_len = FILE_NAME.len() - 1;
        // SAFETY: semihosting calls with a NUL-terminated name that lives for the call.
        let mut handle =
            unsafe { syscall!(OPEN, FILE_NAME.as_ptr(), nr::open::RW_BINARY, name_len) };
        let mut fresh = false;
        if handle == usize::MAX {
            // SAFETY: as above.
            handle = unsafe {
                syscall!(
                    OPEN,
                    FILE_NAME.as_ptr(),
                    nr::open::RW_TRUNC_BINARY,
                    name_len
                )
            };
            fresh = true;
        }
        if handle == usize::MAX {
            return Self { handle: None };
        }
        let mut flash = Self {
            handle: Some(handle),
        };
        // SAFETY: a handle this function opened.
        let len = unsafe { syscall!(FLEN, handle) };
        if fresh || len < PAGE * PAGES {
            // A new file is erased whole; a shorter one (from a firmware with fewer pages)
            // grows by erased pages, what it holds kept.
            let from = if fresh { 0 } else { len - len % CHUNK };
            let ff = [0xFFu8; CHUNK];
            for at in (from..PAGE * PAGES).step_by(CHUNK) {
                if flash.put(at, &ff).is_err() {
                    flash.handle = None;
                    break;
                }
            }
        }
        flash
    }

    fn seek(&self, at: usize) -> Result<usize, NorFlashErrorKind> {
        let handle = self.handle.ok_or_else(host_call_failed)?;
        // SAFETY: a handle opened by `open`.
        if unsafe { syscall!(SEEK, handle, at) } != 0 {
            return Err(host_call_failed());
        }
        Ok(handle)
    }

    fn get(&self, at: usize, out: &mut [u8]) -> Result<(), NorFlashErrorKind> {
        let handle = self.seek(at)?;
        // SAFETY: `out` is valid for its length during the call.
        let left = unsafe { syscall!(READ, handle, out.as_mut_ptr(), out.len()) };
        if left == 0 {
            Ok(())
        } else {
            Err(host_call_failed())
        }
    }

    fn put(&self, at: usize, data: &[u8]) -> Result<(), NorFlashErrorKind> {
        let handle = self.seek(at)?;
        // SAFETY: `data` is valid for its length during the call.
        let left = unsafe { syscall!(WRITE, handle, data.as_ptr(), data.len()) };
        if left == 0 {
            Ok(())
        } else {
            Err(host_call_failed())
        }
    }
}

impl ErrorType for FileFlash {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for FileFlash {
    const READ_SIZE: usize = 1;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        crate::board::check_flash_access(offset, bytes.len(), 1, self.capacity())?;
        for (i, chunk) in bytes.chunks_mut(CHUNK).enumerate() {
            self.get(offset as usize + i * CHUNK, chunk)?;
        }
        Ok(())
    }

    fn capacity(&self) -> usize {
        PAGE * PAGES
    }
}

impl NorFlash for FileFlash {
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
        let ff = [0xFFu8; CHUNK];
        for at in (from as usize..to as usize).step_by(CHUNK) {
            self.put(at, &ff)?;
        }
        Ok(())
    }

    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        crate::board::check_flash_access(offset, bytes.len(), Self::WRITE_SIZE, self.capacity())?;
        let mut cells = [0u8; CHUNK];
        for (i, chunk) in bytes.chunks(CHUNK).enumerate() {
            let at = offset as usize + i * CHUNK;
            let cells = &mut cells[..chunk.len()];
            self.get(at, cells)?;
            // NOR flash: a write only clears bits.
            for (cell, &b) in cells.iter_mut().zip(chunk) {
                *cell &= b;
            }
            self.put(at, cells)?;
        }
        Ok(())
    }
}
