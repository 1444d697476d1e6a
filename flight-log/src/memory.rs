//! Logs kept in memory (feature `std`): the [`LogStorage`] the tests store in, this crate's
//! (the keeper's) and `link`'s (the log transfer's), with a storage that fails on demand.

use crate::keeper::LogStorage;
use std::vec::Vec;

/// Logs in memory; `fail_after` appends succeed, then every one fails.
#[derive(Debug, Default)]
pub struct MemoryLogs {
    /// The logs, oldest first: each one's bytes.
    pub logs: Vec<Vec<u8>>,
    /// A log is being written (created and not yet closed).
    pub writing: bool,
    /// How many appends succeed before every one fails (`None`: they all succeed).
    pub fail_after: Option<usize>,
    /// Appends so far, failed ones included.
    pub appends: usize,
}

impl LogStorage for MemoryLogs {
    type Error = &'static str;
    fn count(&mut self) -> Result<u16, Self::Error> {
        Ok(self.logs.len() as u16)
    }
    fn size(&mut self, id: u16) -> Result<u32, Self::Error> {
        self.logs
            .get(usize::from(id))
            .map(|l| l.len() as u32)
            .ok_or("no such log")
    }
    fn create(&mut self) -> Result<u16, Self::Error> {
        self.logs.push(Vec::new());
        self.writing = true;
        Ok(self.logs.len() as u16 - 1)
    }
    fn append(&mut self, bytes: &[u8]) -> Result<(), Self::Error> {
        self.appends += 1;
        if self.fail_after.is_some_and(|n| self.appends > n) {
            return Err("card removed");
        }
        self.logs
            .last_mut()
            .ok_or("no log open")?
            .extend_from_slice(bytes);
        Ok(())
    }
    fn close(&mut self) -> Result<(), Self::Error> {
        self.writing = false;
        Ok(())
    }
    fn read(&mut self, id: u16, offset: u32, buf: &mut [u8]) -> Result<usize, Self::Error> {
        let log = self.logs.get(usize::from(id)).ok_or("no such log")?;
        let from = (offset as usize).min(log.len());
        let n = buf.len().min(log.len() - from);
        buf[..n].copy_from_slice(&log[from..from + n]);
        Ok(n)
    }
    fn erase_all(&mut self) -> Result<(), Self::Error> {
        self.logs.clear();
        Ok(())
    }
}
