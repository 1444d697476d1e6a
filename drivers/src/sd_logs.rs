//! The flight logs on a FAT-formatted microSD card (docs/formats.md#flight-logs): one file
//! per mission, `/LOGS/LOG-000.ULG`, `/LOGS/LOG-001.ULG`, ... (8.3 names), log `N` the file
//! numbered `N`, ids counted from 0, oldest first. The card is any `embedded-sdmmc`
//! [`BlockDevice`]: the Pixhawk 6C's SDMMC2 in the firmware (`board/sdcard.rs`), a `Vec` of
//! blocks in the tests. This is the driver's logic (naming, numbering, finding the logs after a
//! restart, erasing, reading at an offset, errors worded for people), kept apart from the
//! embassy glue as Hubris splits a driver core from its server; the file system is
//! `embedded-sdmmc`'s.
//!
//! Nothing is touched until first used: the card is mounted (its first partition, FAT16 or
//! FAT32, and the `LOGS` directory made if missing) by the first operation, and again after a
//! failed read or write (a card pulled out and pushed back in between flights). The log being
//! written has its directory entry (its length) brought up to date every
//! [`FLUSH_EVERY`] bytes, so that a power cut loses at most that much of it.

use core::cell::Cell;
use core::fmt;
use core::ops::ControlFlow;

use embedded_sdmmc::{
    Error as FsError, Mode, RawDirectory, RawFile, ShortFileName, TimeSource, Timestamp, VolumeIdx,
    VolumeManager,
};

/// The block device's interface, for the glue that implements it over a card's driver.
pub use embedded_sdmmc::{Block, BlockCount, BlockDevice, BlockIdx};

/// The directory the logs are kept in (in the card's root).
pub const DIRECTORY: &str = "LOGS";
/// The most logs kept (the names have three digits).
pub const MAX_LOGS: u16 = 1000;
/// Bytes appended between two updates of the written log's directory entry.
pub const FLUSH_EVERY: u32 = 64 * 1024;

/// Why a log operation failed, for people (`STATUSTEXT`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SdLogError<E> {
    /// The card did not answer when it was mounted: no card in the slot (or a dead one).
    NoCard,
    /// The card answered but holds no FAT16/FAT32 volume in its first partition.
    NoFilesystem,
    /// The card has no room left for the log.
    Full,
    /// A block read or write failed on a mounted card (pulled out, worn out): the device's
    /// error. The card is mounted again at the next operation.
    Device(E),
    /// The file system is damaged or refused an operation (`embedded-sdmmc`'s words).
    Filesystem(&'static str),
    /// No log with that id.
    NoSuchLog,
    /// [`MAX_LOGS`] logs are kept already.
    TooManyLogs,
    /// No log is being written.
    NotWriting,
    /// A log is being written (the mission runs): it is not read or erased meanwhile.
    Writing,
}

impl<E: fmt::Display> fmt::Display for SdLogError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NoCard => f.write_str("no microSD card (none answers in the slot)"),
            Self::NoFilesystem => f.write_str("the microSD card has no FAT volume: format it"),
            Self::Full => f.write_str("the microSD card is full: erase the logs"),
            Self::Device(e) => write!(f, "the microSD card failed a read or write ({e})"),
            Self::Filesystem(why) => write!(f, "the microSD card's file system: {why}"),
            Self::NoSuchLog => f.write_str("no such log"),
            Self::TooManyLogs => f.write_str("a thousand logs are kept: erase them"),
            Self::NotWriting => f.write_str("no log is being written"),
            Self::Writing => f.write_str("a log is being written"),
        }
    }
}

/// The time stamped on the log files: the board has no calendar clock, so every file carries
/// the same date (2025-01-01 00:00); the log's own start time is inside the ULog.
#[derive(Clone, Copy, Debug, Default)]
pub struct FixedTime;

impl TimeSource for FixedTime {
    fn get_timestamp(&self) -> Timestamp {
        Timestamp {
            year_since_1970: 55,
            zero_indexed_month: 0,
            zero_indexed_day: 0,
            hours: 0,
            minutes: 0,
            seconds: 0,
        }
    }
}

/// `LOG-NNN.ULG`, log `id`'s file name.
pub fn file_name(id: u16) -> ShortFileName {
    let mut name = *b"LOG-000.ULG";
    name[4] = b'0' + (id / 100 % 10) as u8;
    name[5] = b'0' + (id / 10 % 10) as u8;
    name[6] = b'0' + (id % 10) as u8;
    // Eleven ASCII characters, a valid 8.3 name for every id.
    let name = core::str::from_utf8(&name).unwrap_or("LOG-999.ULG");
    ShortFileName::create_from_str(name).unwrap_or_else(|_| ShortFileName::this_dir())
}

/// The id in a log's file name, if `name` is one (`LOG-NNN.ULG`).
pub fn log_id(name: &ShortFileName) -> Option<u16> {
    let base = name.base_name();
    if name.extension() != b"ULG" || base.len() != 7 || &base[..4] != b"LOG-" {
        return None;
    }
    base[4..].iter().try_fold(0u16, |id, &c| {
        c.is_ascii_digit().then(|| id * 10 + u16::from(c - b'0'))
    })
}

/// The card as the file system sees it, remembering its last error: `embedded-sdmmc` reports
/// a device error while it allocates a cluster as a full disk, and this tells the two apart.
struct Recording<D: BlockDevice> {
    card: D,
    error: Cell<Option<D::Error>>,
}

impl<D: BlockDevice> Recording<D>
where
    D::Error: Copy,
{
    fn record<R>(&self, result: Result<R, D::Error>) -> Result<R, D::Error> {
        if let Err(e) = &result {
            self.error.set(Some(*e));
        }
        result
    }
}

impl<D: BlockDevice> BlockDevice for Recording<D>
where
    D::Error: Copy,
{
    type Error = D::Error;
    fn read(&self, blocks: &mut [Block], start: BlockIdx) -> Result<(), D::Error> {
        self.record(self.card.read(blocks, start))
    }
    fn write(&self, blocks: &[Block], start: BlockIdx) -> Result<(), D::Error> {
        self.record(self.card.write(blocks, start))
    }
    fn num_blocks(&self) -> Result<BlockCount, D::Error> {
        self.record(self.card.num_blocks())
    }
}

/// The card mounted: the logs' directory (in the card's only open volume).
#[derive(Clone, Copy, Debug)]
struct Mounted {
    directory: RawDirectory,
}

/// Open directories: the root (while mounting) and the logs'.
const DIRS: usize = 2;
/// Open files: the log written and the log read.
const FILES: usize = 2;

/// The file system over the card.
type Volumes<D, T> = VolumeManager<Recording<D>, T, DIRS, FILES, 1>;

/// The logs on a card.
pub struct SdLogs<D: BlockDevice, T: TimeSource>
where
    D::Error: Copy,
{
    /// The file system (`None` only for the moment it is rebuilt).
    volumes: Option<Volumes<D, T>>,
    mounted: Option<Mounted>,
    /// How many logs there are: one past the highest numbered file (found when mounted).
    count: u16,
    /// The file being written and the bytes written since its entry was updated.
    writing: Option<(RawFile, u32)>,
    /// A file open for reading: its log and handle (kept between the blocks of a download).
    reading: Option<(u16, RawFile)>,
}

impl<D, T> SdLogs<D, T>
where
    D: BlockDevice,
    D::Error: Copy,
    T: TimeSource,
{
    /// The logs on `card` (nothing is read until first used).
    pub fn new(card: D, time: T) -> Self {
        let card = Recording {
            card,
            error: Cell::new(None),
        };
        Self {
            volumes: Some(VolumeManager::new_with_limits(card, time, 1)),
            mounted: None,
            count: 0,
            writing: None,
            reading: None,
        }
    }

    /// The block device, for its owner (the firmware's glue, to ask after the card).
    pub fn with_card<R>(&self, f: impl FnOnce(&mut D) -> R) -> Option<R> {
        self.volumes.as_ref().map(|v| v.device(|c| f(&mut c.card)))
    }

    /// Whether the card is mounted (a FAT volume with the logs' directory was found).
    pub fn mounted(&self) -> bool {
        self.mounted.is_some()
    }

    fn volumes(&self) -> Result<&Volumes<D, T>, SdLogError<D::Error>> {
        self.volumes
            .as_ref()
            .ok_or(SdLogError::Filesystem("not open"))
    }

    /// Forgets the mount and every handle (after a device error: the card may be another
    /// one when it answers again).
    fn unmount(&mut self) {
        self.mounted = None;
        self.writing = None;
        self.reading = None;
        if let Some(volumes) = self.volumes.take() {
            let (card, time) = volumes.free();
            self.volumes = Some(VolumeManager::new_with_limits(card, time, 1));
        }
    }

    /// Forgets the card's last error (at the start of an operation).
    fn begin(&self) {
        if let Some(v) = &self.volumes {
            v.device(|c| c.error.set(None));
        }
    }

    /// The error for people; a device error unmounts the card.
    fn fail(&mut self, e: FsError<D::Error>) -> SdLogError<D::Error> {
        let device = self
            .volumes
            .as_ref()
            .and_then(|v| v.device(|c| c.error.take()));
        let error = match (device, e) {
            (Some(e), _) | (None, FsError::DeviceError(e)) => SdLogError::Device(e),
            (None, e) => Self::filesystem_error(e),
        };
        if matches!(error, SdLogError::Device(_)) {
            self.unmount();
        }
        error
    }

    /// What the file system's error means for the logs.
    fn filesystem_error(e: FsError<D::Error>) -> SdLogError<D::Error> {
        match e {
            FsError::DeviceError(e) => SdLogError::Device(e),
            FsError::NotEnoughSpace | FsError::DiskFull => SdLogError::Full,
            FsError::NotFound => SdLogError::NoSuchLog,
            FsError::FormatError(why) => SdLogError::Filesystem(why),
            FsError::NoSuchVolume => SdLogError::NoFilesystem,
            FsError::BadCluster | FsError::UnterminatedFatChain | FsError::AllocationError => {
                SdLogError::Filesystem("a damaged cluster chain")
            }
            FsError::FileAlreadyOpen => SdLogError::Writing,
            _ => SdLogError::Filesystem("an operation was refused"),
        }
    }

    /// Mounts the card if it is not: its first volume, the logs' directory (made if missing),
    /// and the logs counted.
    fn mount(&mut self) -> Result<Mounted, SdLogError<D::Error>> {
        if let Some(m) = self.mounted {
            return Ok(m);
        }
        let mounted = match self.mount_volume() {
            Ok(m) => m,
            Err(FsError::DeviceError(_)) => {
                self.unmount();
                return Err(SdLogError::NoCard);
            }
            Err(_) if self.card_failed() => {
                self.unmount();
                return Err(SdLogError::NoCard);
            }
            Err(
                FsError::NoSuchVolume
                | FsError::FormatError(_)
                | FsError::BadBlockSize(_)
                | FsError::Unsupported,
            ) => {
                self.unmount();
                return Err(SdLogError::NoFilesystem);
            }
            Err(e) => {
                let e = self.fail(e);
                self.unmount();
                return Err(e);
            }
        };
        let mut highest = None;
        let scanned = self.volumes()?.iterate_dir(mounted.directory, |entry| {
            if !entry.attributes.is_directory()
                && let Some(id) = log_id(&entry.name)
            {
                highest = highest.max(Some(id));
            }
            ControlFlow::Continue(())
        });
        if let Err(e) = scanned {
            let e = self.fail(e);
            self.unmount();
            return Err(e);
        }
        self.count = highest.map_or(0, |id| id + 1);
        self.mounted = Some(mounted);
        Ok(mounted)
    }

    /// Whether the card failed a read or write since [`Self::begin`].
    fn card_failed(&self) -> bool {
        self.volumes
            .as_ref()
            .is_some_and(|v| v.device(|c| c.error.get().is_some()))
    }

    fn mount_volume(&mut self) -> Result<Mounted, FsError<D::Error>> {
        let volumes = self.volumes.as_ref().ok_or(FsError::BadHandle)?;
        let volume = volumes.open_raw_volume(VolumeIdx(0))?;
        let root = volumes.open_root_dir(volume)?;
        let directory = match volumes.open_dir(root, DIRECTORY) {
            Ok(d) => Ok(d),
            Err(FsError::NotFound) => volumes
                .make_dir_in_dir(root, DIRECTORY)
                .and_then(|()| volumes.open_dir(root, DIRECTORY)),
            Err(e) => Err(e),
        };
        let _ = volumes.close_dir(root);
        Ok(Mounted {
            directory: directory?,
        })
    }

    fn drop_reader(&mut self) {
        if let (Some((_, file)), Some(volumes)) = (self.reading.take(), &self.volumes) {
            let _ = volumes.close_file(file);
        }
    }

    /// Log `id`'s file, open for reading.
    fn reader(&mut self, id: u16) -> Result<RawFile, SdLogError<D::Error>> {
        let mounted = self.mount()?;
        if let Some((open, file)) = self.reading {
            if open == id {
                return Ok(file);
            }
            self.drop_reader();
        }
        if id >= self.count {
            return Err(SdLogError::NoSuchLog);
        }
        let file = self
            .volumes()?
            .open_file_in_dir(mounted.directory, file_name(id), Mode::ReadOnly)
            .map_err(|e| self.fail(e))?;
        self.reading = Some((id, file));
        Ok(file)
    }

    /// How many logs are kept: their ids are `0..count` (the directory scanned when mounted;
    /// a number missing in between is a log that [`Self::size`] says does not exist).
    pub fn count(&mut self) -> Result<u16, SdLogError<D::Error>> {
        self.begin();
        self.mount()?;
        Ok(self.count)
    }

    /// The size of log `id`, bytes.
    pub fn size(&mut self, id: u16) -> Result<u32, SdLogError<D::Error>> {
        self.begin();
        if self.writing.is_some() && id + 1 == self.count {
            return Err(SdLogError::Writing);
        }
        let file = self.reader(id)?;
        self.volumes()?.file_length(file).map_err(|e| self.fail(e))
    }

    /// Starts a new log after the last: its id.
    pub fn create(&mut self) -> Result<u16, SdLogError<D::Error>> {
        self.begin();
        if self.writing.is_some() {
            // A log left open is closed first (the keeper closes each, this is a safety net).
            let _ = self.close();
        }
        let mounted = self.mount()?;
        let id = self.count;
        if id >= MAX_LOGS {
            return Err(SdLogError::TooManyLogs);
        }
        let file = self
            .volumes()?
            .open_file_in_dir(mounted.directory, file_name(id), Mode::ReadWriteCreate)
            .map_err(|e| self.fail(e))?;
        self.writing = Some((file, 0));
        self.count = id + 1;
        Ok(id)
    }

    /// Appends to the log being written.
    pub fn append(&mut self, bytes: &[u8]) -> Result<(), SdLogError<D::Error>> {
        self.begin();
        let (file, unflushed) = self.writing.ok_or(SdLogError::NotWriting)?;
        let volumes = self.volumes()?;
        let mut result = volumes.write(file, bytes);
        let unflushed = unflushed.saturating_add(bytes.len() as u32);
        let unflushed = if result.is_ok() && unflushed >= FLUSH_EVERY {
            result = volumes.flush_file(file);
            0
        } else {
            unflushed
        };
        match result {
            Ok(()) => {
                self.writing = Some((file, unflushed));
                Ok(())
            }
            Err(e) => Err(self.fail(e)),
        }
    }

    /// Ends the log being written: its directory entry written, the file closed.
    pub fn close(&mut self) -> Result<(), SdLogError<D::Error>> {
        self.begin();
        let Some((file, _)) = self.writing.take() else {
            return Ok(());
        };
        self.volumes()?.close_file(file).map_err(|e| self.fail(e))
    }

    /// Reads log `id` from `offset` into `buf`: the bytes read (0 at its end).
    pub fn read(
        &mut self,
        id: u16,
        offset: u32,
        buf: &mut [u8],
    ) -> Result<usize, SdLogError<D::Error>> {
        self.begin();
        if self.writing.is_some() && id + 1 == self.count {
            return Err(SdLogError::Writing);
        }
        let file = self.reader(id)?;
        let volumes = self.volumes()?;
        let len = volumes.file_length(file).map_err(|e| self.fail(e))?;
        if offset >= len || buf.is_empty() {
            return Ok(0);
        }
        let n = buf.len().min((len - offset) as usize);
        let volumes = self.volumes()?;
        let read = volumes
            .file_seek_from_start(file, offset)
            .and_then(|()| volumes.read(file, &mut buf[..n]));
        read.map_err(|e| self.fail(e))
    }

    /// Erases every log (their clusters freed, then their directory entries), refused while
    /// one is written.
    pub fn erase_all(&mut self) -> Result<(), SdLogError<D::Error>> {
        self.begin();
        if self.writing.is_some() {
            return Err(SdLogError::Writing);
        }
        self.drop_reader();
        let mounted = self.mount()?;
        for id in (0..self.count).rev() {
            let volumes = self.volumes()?;
            let name = file_name(id);
            // embedded-sdmmc's delete only marks the entry free: truncating first gives the
            // file's clusters back.
            let erased =
                match volumes.open_file_in_dir(mounted.directory, name, Mode::ReadWriteTruncate) {
                    Ok(file) => volumes
                        .close_file(file)
                        .and_then(|()| volumes.delete_entry_in_dir(mounted.directory, name)),
                    Err(FsError::NotFound) => Ok(()),
                    Err(e) => Err(e),
                };
            erased.map_err(|e| self.fail(e))?;
            // The logs above `id` are gone: a failure leaves the count right.
            self.count = id;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
