//! A mission's log from its start to its end: the recorder and the writer together, run after
//! every control step by the firmware and the simulator alike. The log opens at the step that
//! leaves idle (the start accepted) and closes after the step that ends the mission (disarmed
//! or aborted); the records of the steps between go to the ring.

use super::recorder::{RecordSink, Recorder};
use super::stream::{LogRing, LogSpace, LogWriter, StepWindow};
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
        if !self.writer.is_open() && !running {
            return;
        }
        let mut window = StepWindow::new(ring.step_space());
        // The step that opens the log writes its start and the step's texts; the records
        // begin with the next step (the mission's start is already the firmware's costliest
        // step).
        let opening = running && !self.writer.is_open();
        if opening {
            if !self.writer.start(&mut window, input.time_us) {
                return;
            }
            self.recorder.restart();
        }
        let Self { recorder, writer } = self;
        let mut sink = Sink {
            writer,
            ring: &mut window,
            time_us: input.time_us,
        };
        if opening {
            recorder.texts(input.time_us, out, &mut sink);
        } else {
            recorder.step(input, out, mission, max_thrust, &mut sink);
        }
        also(&mut sink);
        if !running {
            // Tried again at the next step when the ring has no room for the marker.
            self.writer.end(&mut window);
        }
        let written = window.len();
        ring.commit_step(written, !self.writer.is_open());
    }
}

/// The most bytes one step logs (a step's usual records take about 230, a step that also
/// writes the slow topics about 430, each text at most 172 more): a ring's step space.
pub const STEP_BYTES: usize = 1024;

/// The recorder's sink: the writer into the step's buffer.
struct Sink<'a, R: LogSpace> {
    writer: &'a mut LogWriter,
    ring: &'a mut R,
    time_us: u64,
}

impl<R: LogSpace> RecordSink for Sink<'_, R> {
    fn record(&mut self, record: &Record) {
        self.writer.record(self.ring, record, self.time_us);
    }
    fn text(&mut self, level: LogLevel, timestamp_us: u64, text: core::fmt::Arguments<'_>) {
        self.writer.text(self.ring, level, timestamp_us, text);
    }
    fn text_str(&mut self, level: LogLevel, timestamp_us: u64, text: &str) {
        self.writer.text_str(self.ring, level, timestamp_us, text);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stream::{Piece, Splitter};
    use crate::topics::Topic;
    use shared::control::navigator::{ImuSample, MocapFix};
    use shared::control::trajectory::FlightPhase;
    use shared::control::vector::{Quat, Vec3};
    use shared::flight::CascadeSetpoints;
    use shared::mission::{HardwareFaults, MissionConfig, Supervision};
    use std::vec::Vec;

    /// A ring of `capacity` bytes whose steps the test reads out.
    struct TestRing {
        space: [u8; STEP_BYTES],
        capacity: usize,
        steps: Vec<Vec<u8>>,
    }

    impl LogRing for TestRing {
        fn step_space(&mut self) -> &mut [u8] {
            let end = self.capacity.min(STEP_BYTES);
            &mut self.space[..end]
        }
        fn commit_step(&mut self, n: usize, _: bool) {
            self.steps.push(self.space[..n].to_vec());
            self.capacity -= n;
        }
    }

    /// The data messages' topics and the dropouts of one step's bytes.
    fn topics(bytes: &[u8]) -> Vec<Option<Topic>> {
        let mut splitter = Splitter::new();
        let mut out = Vec::new();
        splitter.push(bytes, &mut |piece| {
            if let Piece::Message(m) = piece {
                match m[2] {
                    b'D' => {
                        let id = u16::from_le_bytes([m[3], m[4]]);
                        out.push(Topic::ALL.into_iter().find(|t| t.msg_id() == id));
                    }
                    b'O' => out.push(None),
                    _ => {}
                }
            }
        });
        out
    }

    /// Logs `steps` steps of a hover with a fix every fourth step into a ring of `capacity`.
    fn hover(steps: u64, capacity: usize) -> (TestRing, MissionLog) {
        hover_with(steps, capacity, true)
    }

    /// A step's input at `time_us`: the IMU at rest, nothing else.
    fn resting(time_us: u64) -> TickInput {
        TickInput {
            time_us,
            imu: ImuSample {
                gyro: Vec3::ZERO,
                accel: Vec3::new(0.0, 0.0, -9.8),
            },
            mocap: None,
            command: None,
            faults: HardwareFaults::NONE,
            esc_rpm: None,
            supervision: Supervision::NONE,
            manual: shared::manual::ManualSamples::NONE,
        }
    }

    /// [`hover`], with the cascade's setpoints or without them (the rotors stopped).
    fn hover_with(steps: u64, capacity: usize, setpoints: bool) -> (TestRing, MissionLog) {
        let scenario = shared::paper::checked(shared::paper::rect_sim1());
        let mut mission = Mission::new(&scenario, MissionConfig::default());
        let mut input = resting(0);
        let mut out = mission.step(&input);
        out.phase = Phase::Flying(FlightPhase::Hover);
        out.cascade = setpoints.then_some(CascadeSetpoints {
            attitude: Quat::IDENTITY,
            rate: Vec3::new(0.1, -0.2, 0.0),
            collective: 50.0,
        });
        let mut ring = TestRing {
            space: [0; STEP_BYTES],
            capacity,
            steps: Vec::new(),
        };
        let mut log = MissionLog::new();
        for k in 0..steps {
            input.time_us = 2_500 * (k + 1);
            input.mocap = (k % 4 == 2).then_some(MocapFix {
                position: Vec3::ZERO,
                attitude: Quat::IDENTITY,
                stamp_us: input.time_us,
            });
            log.step(&input, &out, &mission, 14.2, &mut ring, |_| {});
        }
        (ring, log)
    }

    #[test]
    fn each_topic_keeps_its_rate_and_the_slow_ones_take_turns() {
        let (ring, log) = hover(401, usize::MAX);
        assert!(log.is_open());
        let steps: Vec<Vec<Option<Topic>>> = ring.steps.iter().map(|s| topics(s)).collect();
        assert!(
            steps[0].is_empty(),
            "the opening step holds the start alone"
        );
        let steps = &steps[1..];
        let count = |topic| {
            steps
                .iter()
                .flatten()
                .filter(|t| **t == Some(topic))
                .count()
        };
        assert_eq!(count(Topic::SensorCombined), 400);
        assert_eq!(count(Topic::ActuatorOutputs), 400);
        assert_eq!(count(Topic::VehicleLocalPosition), 100);
        assert_eq!(count(Topic::VehicleAttitudeSetpoint), 100);
        assert_eq!(count(Topic::VehicleRatesSetpoint), 100);
        assert_eq!(count(Topic::VehicleMocapOdometry), 100);
        assert_eq!(count(Topic::BatteryStatus), 10);
        assert_eq!(count(Topic::RailPosition), 10);
        // Written at the start (a change from nothing) and once in the second.
        assert_eq!(count(Topic::VehicleStatus), 2);
        assert_eq!(count(Topic::Fault), 2);
        let slow = [
            Topic::VehicleLocalPosition,
            Topic::VehicleAttitudeSetpoint,
            Topic::VehicleRatesSetpoint,
            Topic::BatteryStatus,
            Topic::RailPosition,
            Topic::VehicleStatus,
            Topic::Fault,
        ];
        // The first step with records writes the status and the fault as they change from
        // nothing; from then on the slower topics take turns.
        for (k, step) in steps.iter().enumerate().skip(1) {
            let n = step
                .iter()
                .filter(|t| t.is_some_and(|t| slow.contains(&t)))
                .count();
            assert!(n <= 1, "step {k} wrote {n} of the slower topics");
        }
        // Each 100 Hz topic on its own step of every four.
        for (slot, topic) in [
            (0, Topic::VehicleLocalPosition),
            (1, Topic::VehicleAttitudeSetpoint),
            (3, Topic::VehicleRatesSetpoint),
        ] {
            for (k, step) in steps.iter().enumerate() {
                assert_eq!(
                    step.contains(&Some(topic)),
                    k % 4 == slot,
                    "{topic:?} step {k}"
                );
            }
        }
    }

    #[test]
    fn without_the_cascades_setpoints_no_setpoint_is_written() {
        let (ring, _) = hover_with(401, usize::MAX, false);
        let all: Vec<Option<Topic>> = ring.steps.iter().flat_map(|s| topics(s)).collect();
        assert!(all.contains(&Some(Topic::VehicleLocalPosition)));
        assert!(!all.contains(&Some(Topic::VehicleAttitudeSetpoint)));
        assert!(!all.contains(&Some(Topic::VehicleRatesSetpoint)));
    }

    #[test]
    fn the_setpoints_thrust_is_the_collective_over_the_rotors_total_maximum_negative_up() {
        let (ring, _) = hover(8, usize::MAX);
        let all: Vec<u8> = ring.steps.concat();
        let mut seen = 0;
        Splitter::new().push(&all, &mut |piece| {
            if let Piece::Message(m) = piece
                && m[2] == b'D'
            {
                let id = u16::from_le_bytes([m[3], m[4]]);
                let at = match id {
                    id if id == Topic::VehicleAttitudeSetpoint.msg_id() => 5 + 8 + 16,
                    id if id == Topic::VehicleRatesSetpoint.msg_id() => 5 + 8 + 12,
                    _ => return,
                };
                let f = |i: usize| f32::from_le_bytes([m[i], m[i + 1], m[i + 2], m[i + 3]]);
                // rect-sim1's 8 robots of 14.2 N, a collective of 50 N.
                let expect = -50.0 / (8.0 * 14.2);
                assert_eq!([f(at), f(at + 4)], [0.0, 0.0]);
                assert!((f(at + 8) - expect).abs() < 1e-6, "{}", f(at + 8));
                seen += 1;
            }
        });
        assert!(seen >= 3, "{seen} setpoints");
    }

    #[test]
    fn a_full_ring_loses_whole_steps_records_and_says_so_with_a_dropout() {
        // Room for about two steps and a half: later records are lost, none half written.
        let (ring, log) = hover(4, 2 * 240 + 150);
        assert!(log.writer.lost() > 0, "records were lost");
        let all: Vec<u8> = ring.steps.concat();
        let mut whole = 0;
        Splitter::new().push(&all, &mut |_| whole += 1);
        assert!(whole > 8, "the steps that fit are whole ({whole} pieces)");
        // The ring is emptied: the next record comes after a dropout.
        let (mut ring, mut log) = (ring, log);
        ring.capacity = usize::MAX;
        let scenario = shared::paper::checked(shared::paper::rect_sim1());
        let mut mission = Mission::new(&scenario, MissionConfig::default());
        let input = resting(20_000);
        let mut out = mission.step(&input);
        out.phase = Phase::Flying(FlightPhase::Hover);
        log.step(&input, &out, &mission, 14.2, &mut ring, |_| {});
        let last = topics(ring.steps.last().map_or(&[][..], |s| s));
        assert_eq!(last.first(), Some(&None), "a dropout first: {last:?}");
    }
}
