//! The simulator's flight log: the firmware's recorder and ULog encoder
//! (`link::flight_log`, docs/formats.md#flight-logs) writing to a file, so a simulated
//! mission's log opens in the same tools as a real flight's.

use anyhow::{Context, Result};
use link::flight_log::file::{LogInfo, entry_message, write_start};
use link::flight_log::recorder::{LogEntry, Recorder};
use shared::mission::{Mission, MissionConfig, TickInput, TickOutput};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// `sys_name` of the simulator's logs.
pub const SYS_NAME: &str = "rail-transport";
/// `ver_hw` of the simulator's logs.
pub const VER_HW: &str = "SITL host-sim";

/// A ULog file being written, with the recorder that fills it.
pub struct LogFile {
    path: PathBuf,
    out: BufWriter<File>,
    recorder: Recorder,
    max_thrust: f32,
    /// The first write error (the rest of the log is then lost; reported at the end).
    failed: Option<std::io::Error>,
}

impl LogFile {
    /// Creates `path` and writes the log's start: the definitions and `config`'s parameters.
    pub fn create(path: &Path, config: &MissionConfig, max_thrust: f32) -> Result<Self> {
        let file = File::create(path)
            .with_context(|| format!("cannot create the flight log {}", path.display()))?;
        let mut out = BufWriter::new(file);
        let info = LogInfo {
            sys_name: SYS_NAME,
            ver_sw: env!("CARGO_PKG_VERSION"),
            ver_hw: VER_HW,
            start_us: 0,
        };
        let mut failed = None;
        write_start(&info, config, &mut |bytes| {
            if failed.is_none()
                && let Err(e) = out.write_all(bytes)
            {
                failed = Some(e);
            }
        })
        .map_err(|e| anyhow::anyhow!("the flight log's definitions: {e}"))?;
        Ok(Self {
            path: path.to_path_buf(),
            out,
            recorder: Recorder::new(),
            max_thrust,
            failed,
        })
    }

    /// Records one control step.
    pub fn step(&mut self, input: &TickInput, out: &TickOutput, mission: &Mission) {
        let Self {
            out: file,
            recorder,
            failed,
            max_thrust,
            ..
        } = self;
        recorder.step(input, out, mission, *max_thrust, &mut |entry: LogEntry| {
            if failed.is_some() {
                return;
            }
            // Every entry fits a message (the recorder cuts its strings to fit).
            if let Ok(message) = entry_message(&entry)
                && let Err(e) = file.write_all(message.as_bytes())
            {
                *failed = Some(e);
            }
        });
    }

    /// Flushes the file; an error of any write is reported here, naming the file.
    pub fn finish(mut self) -> Result<PathBuf> {
        if let Some(e) = self.failed.take() {
            return Err(e)
                .with_context(|| format!("writing the flight log {}", self.path.display()));
        }
        self.out
            .flush()
            .with_context(|| format!("writing the flight log {}", self.path.display()))?;
        Ok(self.path)
    }
}
