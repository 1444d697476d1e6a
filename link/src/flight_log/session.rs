//! A mission's log from its start to its end: the recorder and the writer together, run after
//! every control step by the firmware and the simulator alike. The log opens at the step that
//! leaves idle (the start accepted) and closes after the step that ends the mission (disarmed
//! or aborted); the records of the steps between go to the ring.

use super::recorder::{RecordSink, Recorder};
use super::stream::{LogRing, LogWriter};
use super::topics::Record;
use crate::ulog::LogLevel;
use shared::mission::{Mission, Phase, TickInput, TickOutput};

/// The recorder and the writer of the mission's log.
#[derive(Clone, Debug, Default)]
pub struct MissionLog {
    recorder: Recorder,
    writer: LogWriter,
}

impl MissionLog {
    /// No log open; the recorder logs the step's texts ([`super::recorder::step_texts`]).
    pub fn new() -> Self {
        Self::default()
    }

    /// No log open; the caller logs the step's texts with [`Self::text`] (the firmware, which
    /// formats them once for the ground and the log).
    pub fn without_step_texts() -> Self {
        Self {
            recorder: Recorder::without_step_texts(),
            writer: LogWriter::new(),
        }
    }

    /// Whether a mission's log is open.
    pub fn is_open(&self) -> bool {
        self.writer.is_open()
    }

    /// Logs the step that took `input` and gave `out` (`mission` after it; `max_thrust` one
    /// rotor's maximum, N) into `ring`; `also` adds what the caller logs of the step itself
    /// (the firmware: the step's texts as the ground gets them), before the log closes.
    pub fn step(
        &mut self,
        input: &TickInput,
        out: &TickOutput,
        mission: &Mission,
        max_thrust: f32,
        ring: &mut impl LogRing,
        also: impl FnOnce(&mut dyn RecordSink),
    ) {
        let running = !matches!(out.phase, Phase::Idle | Phase::Disarmed | Phase::Aborted);
        if !self.writer.is_open() && (!running || ring.free() == 0) {
            return;
        }
        // The step's messages go to the ring in one write (one lock, one wake-up of the
        // storing task), gathered on the stack.
        let mut step = StepBuffer {
            bytes: [0; STEP_BYTES],
            len: 0,
            room: ring.free(),
        };
        if running && !self.writer.is_open() && self.writer.start(&mut step, input.time_us) {
            self.recorder.restart();
        }
        if self.writer.is_open() {
            let Self { recorder, writer } = self;
            let mut sink = Sink {
                writer,
                ring: &mut step,
                time_us: input.time_us,
            };
            recorder.step(input, out, mission, max_thrust, &mut sink);
            also(&mut sink);
        }
        if !running {
            // Tried again at the next step when the ring has no room for the marker.
            self.writer.end(&mut step);
        }
        if step.len > 0 {
            ring.put(&step.bytes[..step.len]);
        }
    }
}

/// The most bytes one step logs (a step's usual records take about 230).
const STEP_BYTES: usize = 1024;

/// A step's messages, gathered before they go to the ring: no more than the ring has room for.
struct StepBuffer {
    bytes: [u8; STEP_BYTES],
    len: usize,
    /// The ring's free bytes at the step's start (only the storing side changes it, upwards).
    room: usize,
}

impl LogRing for StepBuffer {
    fn free(&self) -> usize {
        (STEP_BYTES - self.len).min(self.room.saturating_sub(self.len))
    }
    fn put(&mut self, bytes: &[u8]) {
        let n = bytes.len().min(STEP_BYTES - self.len);
        self.bytes[self.len..self.len + n].copy_from_slice(&bytes[..n]);
        self.len += n;
    }
}

/// The recorder's sink: the writer into the step's buffer.
struct Sink<'a, R: LogRing> {
    writer: &'a mut LogWriter,
    ring: &'a mut R,
    time_us: u64,
}

impl<R: LogRing> RecordSink for Sink<'_, R> {
    fn record(&mut self, record: &Record) {
        self.writer.record(self.ring, record, self.time_us);
    }
    fn text(&mut self, level: LogLevel, timestamp_us: u64, text: core::fmt::Arguments<'_>) {
        self.writer.text(self.ring, level, timestamp_us, text);
    }
}
