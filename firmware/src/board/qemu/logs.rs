//! The flight logs of QEMU's board: host files `log-000.ulg`, `log-001.ulg`, ... in QEMU's
//! working directory (`host-sim hil --storage DIR` starts QEMU there, so the logs outlive the
//! emulator and a restart finds them), written and read through semihosting file I/O as the
//! parameters are (`flash.rs`). Log `N` is the file numbered `N`; the logs are the numbered
//! files from 0 up to the first missing one.

use cortex_m_semihosting::{nr, syscall};
use flight_log::keeper::LogStorage;

/// The most logs kept (the names have three digits).
const MAX_LOGS: u16 = 1000;

/// Why a log operation failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogFileError {
    /// The host refused to open or create a log file.
    CannotOpen,
    /// A read, write or seek on a log file failed.
    Io,
    /// No log with that id.
    NoSuchLog,
    /// A thousand logs are kept already.
    Full,
    /// No log is being written.
    NotWriting,
    /// A log is being written (the mission runs): nothing is erased.
    Writing,
}

impl core::fmt::Display for LogFileError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::CannotOpen => "the host refused to open a log file",
            Self::Io => "a log file could not be read or written",
            Self::NoSuchLog => "no such log",
            Self::Full => "a thousand logs are kept: erase them",
            Self::NotWriting => "no log is being written",
            Self::Writing => "a log is being written",
        })
    }
}

/// `log-NNN.ulg` with its NUL, and the name's length without it.
fn name(id: u16) -> ([u8; 12], usize) {
    let mut n = *b"log-000.ulg\0";
    n[4] = b'0' + (id / 100 % 10) as u8;
    n[5] = b'0' + (id / 10 % 10) as u8;
    n[6] = b'0' + (id % 10) as u8;
    (n, 11)
}

/// Opens log `id`'s file in semihosting `mode`.
fn open(id: u16, mode: usize) -> Option<usize> {
    let (name, len) = name(id);
    // SAFETY: a semihosting call with a NUL-terminated name that lives for the call.
    let handle = unsafe { syscall!(OPEN, name.as_ptr(), mode, len) };
    (handle != usize::MAX).then_some(handle)
}

fn close(handle: usize) {
    // SAFETY: a handle this module opened, closed once.
    unsafe { syscall!(CLOSE, handle) };
}

/// The logs in host files.
pub struct LogFiles {
    /// How many logs there are (found at the first use).
    count: Option<u16>,
    /// The file being written.
    writing: Option<usize>,
    /// A file open for reading: its log and handle (kept between the blocks of a download).
    reading: Option<(u16, usize)>,
}

impl LogFiles {
    /// The logs in QEMU's working directory (nothing is touched until first used).
    pub const fn new() -> Self {
        Self {
            count: None,
            writing: None,
            reading: None,
        }
    }

    fn drop_reader(&mut self) {
        if let Some((_, handle)) = self.reading.take() {
            close(handle);
        }
    }

    fn reader(&mut self, id: u16) -> Result<usize, LogFileError> {
        match self.reading {
            Some((open_id, handle)) if open_id == id => Ok(handle),
            _ => {
                self.drop_reader();
                if id >= self.count()? {
                    return Err(LogFileError::NoSuchLog);
                }
                let handle = open(id, nr::open::R_BINARY).ok_or(LogFileError::NoSuchLog)?;
                self.reading = Some((id, handle));
                Ok(handle)
            }
        }
    }
}

impl Default for LogFiles {
    fn default() -> Self {
        Self::new()
    }
}

impl LogStorage for LogFiles {
    type Error = LogFileError;

    fn count(&mut self) -> Result<u16, LogFileError> {
        if let Some(n) = self.count {
            return Ok(n);
        }
        let mut n = 0;
        while n < MAX_LOGS {
            match open(n, nr::open::R_BINARY) {
                Some(handle) => close(handle),
                None => break,
            }
            n += 1;
        }
        self.count = Some(n);
        Ok(n)
    }

    fn size(&mut self, id: u16) -> Result<u32, LogFileError> {
        let handle = self.reader(id)?;
        // SAFETY: a handle opened by `reader`.
        let len = unsafe { syscall!(FLEN, handle) };
        if len == usize::MAX {
            return Err(LogFileError::Io);
        }
        Ok(len as u32)
    }

    fn create(&mut self) -> Result<u16, LogFileError> {
        let id = self.count()?;
        if id >= MAX_LOGS {
            return Err(LogFileError::Full);
        }
        if let Some(handle) = self.writing.take() {
            close(handle);
        }
        let handle = open(id, nr::open::W_TRUNC_BINARY).ok_or(LogFileError::CannotOpen)?;
        self.writing = Some(handle);
        self.count = Some(id + 1);
        Ok(id)
    }

    fn append(&mut self, bytes: &[u8]) -> Result<(), LogFileError> {
        let handle = self.writing.ok_or(LogFileError::NotWriting)?;
        // SAFETY: `bytes` is valid for its length during the call.
        let left = unsafe { syscall!(WRITE, handle, bytes.as_ptr(), bytes.len()) };
        if left == 0 {
            Ok(())
        } else {
            Err(LogFileError::Io)
        }
    }

    fn close(&mut self) -> Result<(), LogFileError> {
        if let Some(handle) = self.writing.take() {
            close(handle);
        }
        Ok(())
    }

    fn read(&mut self, id: u16, offset: u32, buf: &mut [u8]) -> Result<usize, LogFileError> {
        let handle = self.reader(id)?;
        // SAFETY: a handle opened by `reader`.
        let len = unsafe { syscall!(FLEN, handle) };
        if len == usize::MAX {
            return Err(LogFileError::Io);
        }
        let from = (offset as usize).min(len);
        let n = buf.len().min(len - from);
        if n == 0 {
            return Ok(0);
        }
        // SAFETY: as above; `buf` is valid for `n` bytes during the call.
        let done = unsafe {
            if syscall!(SEEK, handle, from) != 0 {
                return Err(LogFileError::Io);
            }
            syscall!(READ, handle, buf.as_mut_ptr(), n)
        };
        // READ returns how many bytes it did not read.
        Ok(n - done.min(n))
    }

    fn erase_all(&mut self) -> Result<(), LogFileError> {
        self.drop_reader();
        if self.writing.is_some() {
            return Err(LogFileError::Writing);
        }
        let n = self.count()?;
        for id in 0..n {
            let (name, len) = name(id);
            // SAFETY: a NUL-terminated name that lives for the call.
            unsafe { syscall!(REMOVE, name.as_ptr(), len) };
        }
        self.count = Some(0);
        Ok(())
    }
}
