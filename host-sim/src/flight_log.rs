//! The simulator's flight log: the firmware's mission log (the `flight-log` crate,
//! docs/formats.md#flight-logs) run after each step, its ring emptied into the same keeper
//! the firmware stores with, the keeper's storage one file. So a simulated mission's log holds
//! what the firmware's would, and opens in the same tools.

use anyhow::{Context, Result, anyhow};
use flight_log::file::{LogInfo, SYS_NAME};
use flight_log::keeper::{LogKeeper, LogStorage};
use flight_log::session::{MissionLog, STEP_BYTES};
use flight_log::stream::{LogRing, Splitter};
use shared::mission::{Mission, MissionConfig, TickInput, TickOutput};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// `ver_hw` of the simulator's logs.
pub const VER_HW: &str = "SITL host-sim";

/// The ring between the mission log and the keeper: emptied after every step, so never full.
#[derive(Default)]
struct StepBytes {
    bytes: Vec<u8>,
    len: usize,
}

impl StepBytes {
    /// The step's messages.
    fn written(&self) -> &[u8] {
        &self.bytes[..self.len]
    }
}

impl LogRing for StepBytes {
    fn step_space(&mut self) -> &mut [u8] {
        self.bytes.resize(self.len + STEP_BYTES, 0);
        &mut self.bytes[self.len..]
    }
    fn commit_step(&mut self, n: usize, _: bool) {
        self.len += n;
    }
}

/// The keeper's storage: the one file of `--log`.
struct OneFile {
    path: PathBuf,
    out: Option<BufWriter<File>>,
    size: u32,
}

impl LogStorage for OneFile {
    type Error = std::io::Error;
    fn count(&mut self) -> std::io::Result<u16> {
        Ok(u16::from(self.out.is_some()))
    }
    fn size(&mut self, _: u16) -> std::io::Result<u32> {
        Ok(self.size)
    }
    fn create(&mut self) -> std::io::Result<u16> {
        self.out = Some(BufWriter::new(File::create(&self.path)?));
        self.size = 0;
        Ok(0)
    }
    fn append(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        let out = self.out.as_mut().ok_or(std::io::ErrorKind::NotConnected)?;
        out.write_all(bytes)?;
        self.size += bytes.len() as u32;
        Ok(())
    }
    fn close(&mut self) -> std::io::Result<()> {
        match self.out.as_mut() {
            Some(out) => out.flush(),
            None => Ok(()),
        }
    }
    fn read(&mut self, _: u16, _: u32, _: &mut [u8]) -> std::io::Result<usize> {
        Ok(0)
    }
    fn erase_all(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// A mission's flight log being written to a file.
pub struct LogFile {
    log: MissionLog,
    ring: StepBytes,
    splitter: Splitter,
    keeper: LogKeeper,
    storage: OneFile,
    config: MissionConfig,
    max_thrust: f32,
    /// The first storage error (the rest of the log is then lost; reported at the end).
    failed: Option<std::io::Error>,
}

impl LogFile {
    /// A log to `path`, its parameters `config`'s; the file is created when the mission
    /// starts. Checks now that the file can be created.
    pub fn create(path: &Path, config: &MissionConfig, max_thrust: f32) -> Result<Self> {
        File::create(path)
            .with_context(|| format!("cannot create the flight log {}", path.display()))?;
        Ok(Self {
            log: MissionLog::new(),
            ring: StepBytes::default(),
            splitter: Splitter::new(),
            keeper: LogKeeper::new(),
            storage: OneFile {
                path: path.to_path_buf(),
                out: None,
                size: 0,
            },
            config: *config,
            max_thrust,
            failed: None,
        })
    }

    /// Logs one control step.
    pub fn step(&mut self, input: &TickInput, out: &TickOutput, mission: &Mission) {
        self.log
            .step(input, out, mission, self.max_thrust, &mut self.ring, |_| {});
        let info = LogInfo {
            sys_name: SYS_NAME,
            ver_sw: env!("CARGO_PKG_VERSION"),
            ver_hw: VER_HW,
            start_us: 0,
        };
        let Self {
            ring,
            splitter,
            keeper,
            storage,
            config,
            failed,
            ..
        } = self;
        splitter.push(ring.written(), &mut |piece| {
            if let Err(e) = keeper.take(storage, piece, &info, config)
                && failed.is_none()
            {
                *failed = Some(e);
            }
        });
        ring.len = 0;
    }

    /// Ends the log (closing it when the run ended before the mission did); an error of any
    /// write is reported here, naming the file.
    pub fn finish(mut self) -> Result<PathBuf> {
        let path = self.storage.path.clone();
        if let Some(e) = self.failed.take() {
            return Err(e).with_context(|| format!("writing the flight log {}", path.display()));
        }
        if self.storage.out.is_none() {
            return Err(anyhow!(
                "the flight log {} is empty: the mission never started",
                path.display()
            ));
        }
        self.storage
            .close()
            .with_context(|| format!("writing the flight log {}", path.display()))?;
        Ok(path)
    }
}
