//! The storing side of the flight log: takes the pieces the control step wrote
//! ([`super::stream::Piece`]), opens a numbered log in storage at each mission's start with
//! the log's definitions, appends the messages in blocks (storage is written a block at a
//! time: an SD card's sector, a semihosting call) and closes the log at the end. A storage
//! that fails is a state with its reason, reported once; the flight never waits on it.

use super::file::{LogInfo, write_start};
use super::stream::Piece;
use heapless::Vec;
use shared::mission::MissionConfig;

/// Bytes gathered before a write to storage.
pub const BLOCK: usize = 4096;

/// Where the logs are kept: numbered logs, each written once from its start to its end.
pub trait LogStorage {
    /// Why an operation failed, for people.
    type Error: core::fmt::Display;
    /// How many logs are kept (their ids are `0..count`, oldest first).
    fn count(&mut self) -> Result<u16, Self::Error>;
    /// The size of log `id`, bytes.
    fn size(&mut self, id: u16) -> Result<u32, Self::Error>;
    /// Starts a new log after the last: its id.
    fn create(&mut self) -> Result<u16, Self::Error>;
    /// Appends to the log being written.
    fn append(&mut self, bytes: &[u8]) -> Result<(), Self::Error>;
    /// Ends the log being written (it is complete in storage after this).
    fn close(&mut self) -> Result<(), Self::Error>;
    /// Reads log `id` from `offset` into `buf`: the bytes read (0 at its end).
    fn read(&mut self, id: u16, offset: u32, buf: &mut [u8]) -> Result<usize, Self::Error>;
    /// Erases every log.
    fn erase_all(&mut self) -> Result<(), Self::Error>;
}

/// What happened that people should hear of (a `STATUSTEXT`), once each.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeeperEvent {
    /// A log was opened.
    Opened(u16),
    /// A log was closed complete, of this many bytes.
    Closed(u16, u32),
    /// The storage failed: the mission's log is lost from here (the flight goes on).
    Failed,
}

/// The storing side's state.
#[derive(Debug)]
pub struct LogKeeper {
    /// The log being written and its bytes so far.
    open: Option<(u16, u32)>,
    block: Vec<u8, BLOCK>,
    /// The storage failed in this log (what is left of it is dropped).
    failed: bool,
}

impl Default for LogKeeper {
    fn default() -> Self {
        Self::new()
    }
}

impl LogKeeper {
    /// No log open.
    pub const fn new() -> Self {
        Self {
            open: None,
            block: Vec::new(),
            failed: false,
        }
    }

    /// The log being written, if one is: its id.
    pub fn writing(&self) -> Option<u16> {
        self.open.map(|(id, _)| id)
    }

    /// Takes one piece; `config` and `info` make a new log's definitions. Returns what people
    /// should hear of, if anything, with the storage's error for a failure.
    pub fn take<S: LogStorage>(
        &mut self,
        storage: &mut S,
        piece: Piece<'_>,
        info: &LogInfo<'_>,
        config: &MissionConfig,
    ) -> Result<Option<KeeperEvent>, S::Error> {
        match piece {
            Piece::Start(start_us) => {
                // A log left open (its end marker lost) is closed first.
                self.finish(storage)?;
                let id = storage.create().inspect_err(|_| self.fail())?;
                self.open = Some((id, 0));
                self.failed = false;
                let info = LogInfo { start_us, ..*info };
                let mut result = Ok(());
                // The definitions fit the message capacity (`file`'s test writes them).
                let _ = write_start(&info, config, &mut |bytes| {
                    if result.is_ok() {
                        result = self.put(storage, bytes);
                    }
                });
                result?;
                Ok(Some(KeeperEvent::Opened(id)))
            }
            Piece::Message(bytes) => {
                if self.open.is_some() && !self.failed {
                    self.put(storage, bytes)?;
                }
                Ok(None)
            }
            Piece::End => self.finish(storage),
        }
    }

    /// Adds bytes to the block, writing it out when full.
    fn put<S: LogStorage>(&mut self, storage: &mut S, bytes: &[u8]) -> Result<(), S::Error> {
        if self.failed {
            return Ok(());
        }
        let mut rest = bytes;
        while !rest.is_empty() {
            let room = BLOCK - self.block.len();
            let n = room.min(rest.len());
            // `n` fits the block's room.
            let _ = self.block.extend_from_slice(&rest[..n]);
            rest = &rest[n..];
            if self.block.len() == BLOCK {
                self.flush(storage)?;
            }
        }
        Ok(())
    }

    fn flush<S: LogStorage>(&mut self, storage: &mut S) -> Result<(), S::Error> {
        if self.block.is_empty() {
            return Ok(());
        }
        let written = storage.append(&self.block);
        let n = self.block.len() as u32;
        self.block.clear();
        written.inspect_err(|_| self.fail())?;
        if let Some((_, size)) = &mut self.open {
            *size += n;
        }
        Ok(())
    }

    fn fail(&mut self) {
        self.failed = true;
        self.block.clear();
    }

    /// Writes out what is gathered and closes the open log.
    fn finish<S: LogStorage>(&mut self, storage: &mut S) -> Result<Option<KeeperEvent>, S::Error> {
        let Some((id, _)) = self.open else {
            return Ok(None);
        };
        let flushed = self.flush(storage);
        let (_, size) = self.open.take().unwrap_or((id, 0));
        let failed = self.failed;
        self.failed = false;
        flushed?;
        storage.close()?;
        Ok(Some(if failed {
            KeeperEvent::Failed
        } else {
            KeeperEvent::Closed(id, size)
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::memory::MemoryLogs;
    use crate::stream::{LogSpace, LogWriter, Splitter};
    use crate::topics::Record;
    use std::vec::Vec as StdVec;

    /// Every byte the writer commits, with a kilobyte of room each time.
    struct Bytes(StdVec<u8>, [u8; 1024]);
    impl LogSpace for Bytes {
        fn space(&mut self) -> &mut [u8] {
            &mut self.1
        }
        fn commit(&mut self, n: usize) {
            self.0.extend_from_slice(&self.1[..n]);
        }
    }

    const INFO: LogInfo<'static> = LogInfo {
        sys_name: "test",
        ver_sw: "1",
        ver_hw: "bench",
        start_us: 0,
    };

    /// A mission's ring bytes: `records` status records between the markers.
    fn mission(records: u64) -> StdVec<u8> {
        let mut ring = Bytes(StdVec::new(), [0; 1024]);
        let mut w = LogWriter::new();
        w.start(&mut ring, 100);
        for t in 0..records {
            let r = Record::VehicleStatus {
                timestamp: 100 + t,
                armed: true,
                nav_state: 3,
                mission_phase: 9,
            };
            w.record(&mut ring, &r, 100 + t);
        }
        w.end(&mut ring);
        ring.0
    }

    fn keep(storage: &mut MemoryLogs, ring: &[u8], chunk: usize) -> StdVec<KeeperEvent> {
        let mut keeper = LogKeeper::new();
        let mut splitter = Splitter::new();
        let mut events = StdVec::new();
        for c in ring.chunks(chunk) {
            splitter.push(c, &mut |piece| match keeper.take(
                storage,
                piece,
                &INFO,
                &MissionConfig::DEFAULT,
            ) {
                Ok(Some(e)) => events.push(e),
                Ok(None) => {}
                Err(_) => events.push(KeeperEvent::Failed),
            });
        }
        events
    }

    #[test]
    fn each_mission_is_one_log_with_its_definitions_and_every_message() {
        let mut storage = MemoryLogs::default();
        let ring = [mission(1000), mission(3)].concat();
        let events = keep(&mut storage, &ring, 333);
        assert_eq!(storage.logs.len(), 2);
        assert!(!storage.writing);
        let sizes: StdVec<u32> = storage.logs.iter().map(|l| l.len() as u32).collect();
        assert_eq!(
            events,
            [
                KeeperEvent::Opened(0),
                KeeperEvent::Closed(0, sizes[0]),
                KeeperEvent::Opened(1),
                KeeperEvent::Closed(1, sizes[1])
            ]
        );
        // The definitions, then the 1000 records of 16 bytes each (3 + 2 + 8 + 3).
        let mut definitions = StdVec::new();
        write_start(
            &LogInfo {
                start_us: 100,
                ..INFO
            },
            &MissionConfig::DEFAULT,
            &mut |b| definitions.extend_from_slice(b),
        )
        .expect("fits");
        assert_eq!(storage.logs[0][..definitions.len()], definitions[..]);
        assert_eq!(storage.logs[0].len(), definitions.len() + 1000 * 16);
        assert_eq!(storage.logs[1].len(), definitions.len() + 3 * 16);
    }

    #[test]
    fn a_storage_that_fails_mid_log_is_reported_and_the_next_log_starts_clean() {
        let mut storage = MemoryLogs {
            fail_after: Some(2),
            ..MemoryLogs::default()
        };
        let events = keep(&mut storage, &mission(2000), 100);
        assert!(events.contains(&KeeperEvent::Failed), "{events:?}");
        assert_eq!(events.last(), Some(&KeeperEvent::Failed));
        assert!(!storage.writing, "closed all the same");
        storage.fail_after = None;
        let events = keep(&mut storage, &mission(10), 100);
        assert_eq!(events[0], KeeperEvent::Opened(1));
        assert!(matches!(events[1], KeeperEvent::Closed(1, _)));
    }
}
