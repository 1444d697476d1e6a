//! The flight logs' driver tested on a card in memory: a FAT16 volume formatted by another
//! implementation (the `fatfs` crate), which also reads back what was written; writes that
//! fail after a count stand in for a card pulled out.

use super::*;
use core::cell::{Cell, RefCell};
use embedded_sdmmc::{Block, BlockCount, BlockIdx};
use std::io::{Cursor, Read, Write};
use std::rc::Rc;
use std::string::{String, ToString};
use std::vec;
use std::vec::Vec;

/// Blocks in memory shared between "restarts"; `fail_writes_after` writes succeed, then
/// every write fails.
#[derive(Clone)]
struct MemoryCard {
    blocks: Rc<RefCell<Vec<u8>>>,
    writes: Rc<Cell<usize>>,
    fail_writes_after: Rc<Cell<Option<usize>>>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct CardError;
impl fmt::Display for CardError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("write refused")
    }
}
impl core::error::Error for CardError {}

impl BlockDevice for MemoryCard {
    type Error = CardError;
    fn read(&self, blocks: &mut [Block], start: BlockIdx) -> Result<(), CardError> {
        let bytes = self.blocks.borrow();
        for (i, block) in blocks.iter_mut().enumerate() {
            let at = (start.0 as usize + i) * Block::LEN;
            block
                .contents
                .copy_from_slice(bytes.get(at..at + Block::LEN).ok_or(CardError)?);
        }
        Ok(())
    }
    fn write(&self, blocks: &[Block], start: BlockIdx) -> Result<(), CardError> {
        self.writes.set(self.writes.get() + 1);
        if self
            .fail_writes_after
            .get()
            .is_some_and(|n| self.writes.get() > n)
        {
            return Err(CardError);
        }
        let mut bytes = self.blocks.borrow_mut();
        for (i, block) in blocks.iter().enumerate() {
            let at = (start.0 as usize + i) * Block::LEN;
            bytes
                .get_mut(at..at + Block::LEN)
                .ok_or(CardError)?
                .copy_from_slice(&block.contents);
        }
        Ok(())
    }
    fn num_blocks(&self) -> Result<BlockCount, CardError> {
        Ok(BlockCount((self.blocks.borrow().len() / Block::LEN) as u32))
    }
}

/// Where the partition starts (as a card's does, on an erase-block boundary).
const PARTITION_START: usize = 2048;

/// A card of `mib` MiB: an MBR with one FAT partition formatted by the `fatfs` crate.
fn card(mib: usize) -> MemoryCard {
    let total = mib * 1024 * 1024 / 512;
    let mut image = vec![0u8; total * 512];
    let sectors = (total - PARTITION_START) as u32;
    let entry = &mut image[446..462];
    entry[4] = 0x0e; // FAT16 (LBA)
    entry[8..12].copy_from_slice(&(PARTITION_START as u32).to_le_bytes());
    entry[12..16].copy_from_slice(&sectors.to_le_bytes());
    image[510] = 0x55;
    image[511] = 0xaa;
    let mut partition = Cursor::new(image.split_off(PARTITION_START * 512));
    fatfs::format_volume(
        &mut partition,
        fatfs::FormatVolumeOptions::new().fat_type(fatfs::FatType::Fat16),
    )
    .expect("formats");
    image.extend_from_slice(&partition.into_inner());
    MemoryCard {
        blocks: Rc::new(RefCell::new(image)),
        writes: Rc::new(Cell::new(0)),
        fail_writes_after: Rc::new(Cell::new(None)),
    }
}

/// The card's files as another implementation (`fatfs`) reads them: `/LOGS`'s names
/// and contents.
fn files(card: &MemoryCard) -> Vec<(String, Vec<u8>)> {
    let image = card.blocks.borrow()[PARTITION_START * 512..].to_vec();
    let fs =
        fatfs::FileSystem::new(Cursor::new(image), fatfs::FsOptions::new()).expect("a FAT volume");
    let dir = fs.root_dir().open_dir(DIRECTORY).expect("LOGS");
    let mut out = Vec::new();
    for entry in dir.iter() {
        let entry = entry.expect("an entry");
        if entry.is_file() {
            let mut bytes = Vec::new();
            entry.to_file().read_to_end(&mut bytes).expect("readable");
            out.push((entry.short_file_name(), bytes));
        }
    }
    out.sort();
    out
}

fn logs(card: &MemoryCard) -> SdLogs<MemoryCard, FixedTime> {
    SdLogs::new(card.clone(), FixedTime)
}

fn pattern(len: usize, seed: u8) -> Vec<u8> {
    (0..len)
        .map(|i| (i as u8).wrapping_mul(31) ^ seed)
        .collect()
}

/// Writes one log of `bytes` in 4 KiB appends, as the keeper does.
fn write_log(logs: &mut SdLogs<MemoryCard, FixedTime>, bytes: &[u8]) -> u16 {
    let id = logs.create().expect("created");
    for chunk in bytes.chunks(4096) {
        logs.append(chunk).expect("appended");
    }
    logs.close().expect("closed");
    id
}

fn read_all(logs: &mut SdLogs<MemoryCard, FixedTime>, id: u16) -> Vec<u8> {
    let mut out = Vec::new();
    let mut buf = [0u8; 700];
    loop {
        let n = logs.read(id, out.len() as u32, &mut buf).expect("read");
        if n == 0 {
            return out;
        }
        out.extend_from_slice(&buf[..n]);
    }
}

#[test]
fn names_are_8_3_and_read_back() {
    assert_eq!(file_name(7).to_string(), "LOG-007.ULG");
    assert_eq!(log_id(&file_name(0)), Some(0));
    assert_eq!(log_id(&file_name(999)), Some(999));
    let other = ShortFileName::create_from_str("LOG-12X.ULG").expect("8.3");
    assert_eq!(log_id(&other), None);
    let other = ShortFileName::create_from_str("LOG-001.TXT").expect("8.3");
    assert_eq!(log_id(&other), None);
}

#[test]
fn logs_are_written_numbered_and_read_back_at_any_offset() {
    let card = card(8);
    let mut logs = logs(&card);
    assert_eq!(logs.count(), Ok(0));
    let first = pattern(50_000, 1);
    let second = pattern(4096 * 3 + 17, 2);
    assert_eq!(write_log(&mut logs, &first), 0);
    assert_eq!(write_log(&mut logs, &second), 1);
    assert_eq!(logs.count(), Ok(2));
    assert_eq!(logs.size(0), Ok(50_000));
    assert_eq!(logs.size(1), Ok(second.len() as u32));
    assert_eq!(read_all(&mut logs, 0), first);
    assert_eq!(read_all(&mut logs, 1), second);
    let mut buf = [0u8; 10];
    assert_eq!(logs.read(0, 49_995, &mut buf), Ok(5));
    assert_eq!(buf[..5], first[49_995..]);
    assert_eq!(logs.read(0, 60_000, &mut buf), Ok(0));
    assert_eq!(logs.size(2), Err(SdLogError::NoSuchLog));
    // Another FAT implementation finds the same files.
    let names: Vec<_> = files(&card).into_iter().collect();
    assert_eq!(
        names,
        [
            ("LOG-000.ULG".to_string(), first),
            ("LOG-001.ULG".to_string(), second)
        ]
    );
}

#[test]
fn a_restart_finds_the_logs_and_numbers_the_next_after_them() {
    let card = card(8);
    let mut before = logs(&card);
    write_log(&mut before, &pattern(10_000, 3));
    write_log(&mut before, &pattern(20_000, 4));
    drop(before);
    let mut after = logs(&card);
    assert_eq!(after.count(), Ok(2));
    assert_eq!(read_all(&mut after, 1), pattern(20_000, 4));
    assert_eq!(write_log(&mut after, &pattern(100, 5)), 2);
    assert_eq!(logs(&card).count(), Ok(3));
}

#[test]
fn a_log_being_written_is_flushed_as_it_goes() {
    // A power cut mid-log: what was flushed is there after the restart.
    let card = card(8);
    let mut logs_before = logs(&card);
    logs_before.create().expect("created");
    for chunk in pattern(100_000, 6).chunks(4096) {
        logs_before.append(chunk).expect("appended");
    }
    drop(logs_before); // never closed
    let mut after = logs(&card);
    assert_eq!(after.count(), Ok(1));
    let size = after.size(0).expect("a size");
    assert!((FLUSH_EVERY..100_000).contains(&size), "{size}");
    assert_eq!(
        read_all(&mut after, 0),
        pattern(100_000, 6)[..size as usize]
    );
}

#[test]
fn a_full_card_is_a_clear_error_and_erasing_makes_room_again() {
    let card = card(8);
    let mut logs = logs(&card);
    logs.create().expect("created");
    let block = pattern(4096, 7);
    let error = loop {
        if let Err(e) = logs.append(&block) {
            break e;
        }
    };
    assert_eq!(error, SdLogError::Full);
    assert_eq!(
        error.to_string(),
        "the microSD card is full: erase the logs"
    );
    assert_eq!(logs.erase_all(), Err(SdLogError::Writing));
    logs.close().expect("closed");
    assert_eq!(logs.erase_all(), Ok(()));
    assert_eq!(logs.count(), Ok(0));
    assert!(files(&card).is_empty());
    // The clusters came back: a log as large as the first fits again.
    let id = logs.create().expect("created");
    assert_eq!(id, 0);
    for _ in 0..200 {
        logs.append(&block).expect("room again");
    }
    logs.close().expect("closed");
    assert_eq!(self::logs(&card).count(), Ok(1));
}

#[test]
fn erase_all_removes_every_log_and_numbering_starts_over() {
    let card = card(8);
    let mut logs = logs(&card);
    for seed in 0..3 {
        write_log(&mut logs, &pattern(9000, seed));
    }
    let mut buf = [0u8; 16];
    logs.read(1, 0, &mut buf).expect("read");
    assert_eq!(logs.erase_all(), Ok(()));
    assert_eq!(logs.count(), Ok(0));
    assert_eq!(logs.size(0), Err(SdLogError::NoSuchLog));
    assert_eq!(write_log(&mut logs, &pattern(10, 9)), 0);
    assert_eq!(self::logs(&card).count(), Ok(1));
}

#[test]
fn a_card_failing_mid_write_is_an_error_and_the_next_log_is_clean() {
    let card = card(8);
    let mut logs = logs(&card);
    write_log(&mut logs, &pattern(5000, 1));
    logs.create().expect("created");
    card.fail_writes_after.set(Some(card.writes.get() + 10));
    let error = (0..100)
        .find_map(|_| logs.append(&pattern(4096, 2)).err())
        .expect("fails");
    assert_eq!(error, SdLogError::Device(CardError));
    assert_eq!(
        error.to_string(),
        "the microSD card failed a read or write (write refused)"
    );
    assert_eq!(logs.append(b"more"), Err(SdLogError::NotWriting));
    assert_eq!(logs.close(), Ok(()));
    // The card answers again (pushed back in): the next log is numbered after the others.
    card.fail_writes_after.set(None);
    assert_eq!(write_log(&mut logs, &pattern(3000, 3)), 2);
    assert_eq!(read_all(&mut logs, 2), pattern(3000, 3));
    assert_eq!(read_all(&mut logs, 0), pattern(5000, 1));
}

#[test]
fn no_card_and_no_file_system_are_told_apart() {
    let blank = card(4);
    blank.blocks.borrow_mut().iter_mut().for_each(|b| *b = 0);
    assert_eq!(logs(&blank).count(), Err(SdLogError::NoFilesystem));
    let missing = MemoryCard {
        blocks: Rc::new(RefCell::new(Vec::new())),
        writes: Rc::new(Cell::new(0)),
        fail_writes_after: Rc::new(Cell::new(None)),
    };
    let mut logs = logs(&missing);
    assert_eq!(logs.count(), Err(SdLogError::NoCard));
    assert_eq!(logs.create(), Err(SdLogError::NoCard));
    assert_eq!(
        SdLogError::<CardError>::NoCard.to_string(),
        "no microSD card (none answers in the slot)"
    );
}

#[test]
fn other_files_on_the_card_are_left_alone() {
    let card = card(8);
    {
        let mut image = card.blocks.borrow_mut();
        let partition = Cursor::new(&mut image[PARTITION_START * 512..]);
        let fs = fatfs::FileSystem::new(partition, fatfs::FsOptions::new()).expect("a FAT volume");
        let dir = fs.root_dir().create_dir(DIRECTORY).expect("LOGS");
        dir.create_file("NOTES.TXT")
            .and_then(|mut f| f.write_all(b"keep"))
            .expect("written");
        dir.create_file("LOG-004.ULG")
            .and_then(|mut f| f.write_all(b"old log"))
            .expect("written");
    }
    let mut logs = logs(&card);
    assert_eq!(logs.count(), Ok(5), "one past the highest number");
    assert_eq!(logs.size(0), Err(SdLogError::NoSuchLog));
    assert_eq!(read_all(&mut logs, 4), b"old log");
    assert_eq!(write_log(&mut logs, b"new"), 5);
    logs.erase_all().expect("erased");
    let left: Vec<_> = files(&card).into_iter().map(|(n, _)| n).collect();
    assert_eq!(left, ["NOTES.TXT"]);
}
