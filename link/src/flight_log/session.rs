//! A mission's log from its start to its end: the recorder and the writer together, run after
//! every control step by the firmware and the simulator alike. The log opens at the step that
//! leaves idle (the start accepted) and closes after the step that ends the mission (disarmed
//! or aborted); the records of the steps between go to the ring.

use super::recorder::Recorder;
use super::stream::{LogRing, LogWriter};
use shared::mission::{Mission, Phase, TickInput, TickOutput};

/// The recorder and the writer of the mission's log.
#[derive(Clone, Debug, Default)]
pub struct MissionLog {
    recorder: Recorder,
    writer: LogWriter,
}

impl MissionLog {
    /// No log open.
    pub fn new() -> Self {
        Self::default()
    }

    /// Whether a mission's log is open.
    pub fn is_open(&self) -> bool {
        self.writer.is_open()
    }

    /// Messages lost since the log opened (the ring was full).
    pub fn lost(&self) -> u32 {
        self.writer.lost()
    }

    /// Logs the step that took `input` and gave `out` (`mission` after it; `max_thrust` one
    /// rotor's maximum, N) into `ring`.
    pub fn step(
        &mut self,
        input: &TickInput,
        out: &TickOutput,
        mission: &Mission,
        max_thrust: f32,
        ring: &mut impl LogRing,
    ) {
        let running = !matches!(out.phase, Phase::Idle | Phase::Disarmed | Phase::Aborted);
        if running && !self.writer.is_open() && self.writer.start(ring, input.time_us) {
            self.recorder = Recorder::new();
        }
        if self.writer.is_open() {
            let Self { recorder, writer } = self;
            recorder.step(input, out, mission, max_thrust, &mut |entry| {
                writer.entry(ring, &entry, input.time_us)
            });
        }
        if !running {
            // Tried again at the next step when the ring has no room for the marker.
            self.writer.end(ring);
        }
    }
}
