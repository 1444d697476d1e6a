//! What one control step records: from the mission's input and output (and the mission's
//! state after the step) to the log's records and strings. The firmware's control step and
//! the simulator's harness call [`Recorder::step`] after each `Mission::step`, so both logs
//! hold the same records at the same times.
//!
//! Rates: at every step (400 Hz) `sensor_combined`, `vehicle_attitude`,
//! `vehicle_angular_velocity` and `actuator_outputs`; `vehicle_local_position` at 100 Hz, and
//! while flying `vehicle_attitude_setpoint` and `vehicle_rates_setpoint` at 100 Hz each;
//! `vehicle_mocap_odometry` with each fix; `battery_status`, `rail_position`,
//! `manual_control_setpoint` and `manual_control_switches` at 10 Hz;
//! `vehicle_status` and `fault` when they change and once a second; `lift`, `formation` and
//! `adaptation` when they happen. What the step says to people ([`step_texts`], the
//! firmware's `STATUSTEXT`s) is each a logged string.

use super::topics::{Record, per_robot};
use crate::ulog::LogLevel;
use shared::control::trajectory::FlightPhase;
use shared::estimation::Measurement;
use shared::flight::adapt::AdaptEvent;
use shared::mission::supervision::BatteryLevel;
use shared::mission::{AbortReason, Mission, Notice, Phase, Reason, TickInput, TickOutput};

/// The longest logged string, bytes (a longer text is cut at a character boundary).
pub const TEXT_CAPACITY: usize = 160;

/// Steps between two records of a 100 Hz topic.
const EVERY_100_HZ: u32 = 4;
/// Steps between two records of a 10 Hz topic.
const EVERY_10_HZ: u32 = 40;
/// Steps between two records of a topic written when it changes, at least.
const EVERY_SECOND: u32 = 400;

/// Where the recorder's records and texts go.
pub trait RecordSink {
    /// A topic's record.
    fn record(&mut self, record: &Record);
    /// A logged string of `level` at `timestamp_us` (cut to [`TEXT_CAPACITY`] bytes).
    fn text(&mut self, level: LogLevel, timestamp_us: u64, text: core::fmt::Arguments<'_>);
    /// A logged string already formatted (the firmware's texts for the ground): copied as it
    /// is.
    fn text_str(&mut self, level: LogLevel, timestamp_us: u64, text: &str) {
        self.text(level, timestamp_us, format_args!("{text}"));
    }
}

/// The mission's phase as the log's `mission_phase` number: 0 idle, 1 pre-flight checks,
/// 2 selecting a pair, 3 moving robots, 4 lifting, 5 relaxing, 6 deciding the formation,
/// 7 rearranging, 8 arming, 9 take-off, 10 trajectory, 11 hover, 12 landing, 13 touchdown,
/// 14 disarmed, 15 aborted.
pub fn phase_code(phase: Phase) -> u8 {
    match phase {
        Phase::Idle => 0,
        Phase::PreflightChecks => 1,
        Phase::SelectingPair => 2,
        Phase::MovingRobots => 3,
        Phase::Lifting => 4,
        Phase::Relaxing => 5,
        Phase::DecidingFormation => 6,
        Phase::Rearranging => 7,
        Phase::Arming => 8,
        Phase::Flying(FlightPhase::Takeoff) => 9,
        Phase::Flying(FlightPhase::Transit) => 10,
        Phase::Flying(FlightPhase::Hover) => 11,
        Phase::Flying(FlightPhase::Land) => 12,
        Phase::Flying(FlightPhase::Done) => 13,
        Phase::Disarmed => 14,
        Phase::Aborted => 15,
    }
}

/// The phase a logged `mission_phase` number stands for ([`phase_code`]'s inverse; `None` for
/// a number this firmware does not write).
pub fn phase_from_code(code: u8) -> Option<Phase> {
    Some(match code {
        0 => Phase::Idle,
        1 => Phase::PreflightChecks,
        2 => Phase::SelectingPair,
        3 => Phase::MovingRobots,
        4 => Phase::Lifting,
        5 => Phase::Relaxing,
        6 => Phase::DecidingFormation,
        7 => Phase::Rearranging,
        8 => Phase::Arming,
        9 => Phase::Flying(FlightPhase::Takeoff),
        10 => Phase::Flying(FlightPhase::Transit),
        11 => Phase::Flying(FlightPhase::Hover),
        12 => Phase::Flying(FlightPhase::Land),
        13 => Phase::Flying(FlightPhase::Done),
        14 => Phase::Disarmed,
        15 => Phase::Aborted,
        _ => return None,
    })
}

/// PX4's `nav_state` nearest a phase: take-off 17 (`AUTO_TAKEOFF`), hover 4 (`AUTO_LOITER`),
/// landing and touchdown 18 (`AUTO_LAND`), every other phase 3 (`AUTO_MISSION`).
pub fn nav_state(phase: Phase) -> u8 {
    match phase {
        Phase::Flying(FlightPhase::Takeoff) => 17,
        Phase::Flying(FlightPhase::Hover) => 4,
        Phase::Flying(FlightPhase::Land | FlightPhase::Done) => 18,
        _ => 3,
    }
}

/// PX4's battery warning: 0 none, 1 low, 2 critical.
fn battery_warning(level: BatteryLevel) -> u8 {
    match level {
        BatteryLevel::Ok => 0,
        BatteryLevel::Low => 1,
        BatteryLevel::Critical => 2,
    }
}

/// The state the recorder keeps between steps.
#[derive(Clone, Debug, Default)]
pub struct Recorder {
    /// Steps since the log started, modulo a second's (every rate divides it; a `u32` and a
    /// constant modulus, so no 64-bit division on the target).
    step_in_second: u32,
    /// The last `vehicle_status` written: armed, navigation state, phase.
    status: Option<(bool, u8, u8)>,
    /// The last `fault` written: its fields after the timestamp.
    fault: Option<(u16, u16, bool, bool, bool, u8)>,
    /// The pair chosen for the lift under way and its information.
    pair: Option<(u8, f32)>,
    /// A lift read whose estimate has not come back yet.
    reading: Option<(u64, Option<f32>)>,
    /// Lifts whose update has come back (at the last `lift` record).
    lifts: u32,
    /// The step's texts are logged by the caller, formatted once for the ground and the log
    /// (the firmware); otherwise the recorder logs [`step_texts`] itself (the simulator).
    texts_elsewhere: bool,
}

impl Recorder {
    /// A recorder at the mission's start.
    pub fn new() -> Self {
        Self::default()
    }

    /// Back to the mission's start (the texts left where they were).
    pub fn restart(&mut self) {
        *self = Self {
            texts_elsewhere: self.texts_elsewhere,
            ..Self::default()
        };
    }

    /// A recorder at the mission's start that leaves the step's texts to its caller.
    pub fn without_step_texts() -> Self {
        Self {
            texts_elsewhere: true,
            ..Self::default()
        }
    }

    /// Records the step that took `input` and gave `out`; `mission` is the mission after the
    /// step, `max_thrust` one rotor's maximum thrust, N. What it records goes to `sink`.
    pub fn step(
        &mut self,
        input: &TickInput,
        out: &TickOutput,
        mission: &Mission,
        max_thrust: f32,
        sink: &mut impl RecordSink,
    ) {
        let t = input.time_us;
        // The slower topics take turns on different steps of their period, so no step
        // writes more than the 400 Hz records, a fix and one slower record: of every four
        // steps the first writes the local position, the second the attitude setpoint, the
        // fourth the rates setpoint, and the third is shared by the 10 Hz and 1 Hz topics,
        // each on a step of its own.
        let s = self.step_in_second;
        let turn = |period: u32, slot: u32| s % period == slot;
        let at_100_hz = turn(EVERY_100_HZ, 0);
        let (attitude_sp_turn, rates_sp_turn) = (turn(EVERY_100_HZ, 1), turn(EVERY_100_HZ, 3));
        let (battery_turn, rail_turn) = (turn(EVERY_10_HZ, 2), turn(EVERY_10_HZ, 6));
        let (status_turn, fault_turn) = (turn(EVERY_SECOND, 10), turn(EVERY_SECOND, 14));
        // Manual control at 10 Hz, on steps of their own (of the third of every four).
        let (sticks_turn, switches_turn) = (turn(EVERY_10_HZ, 18), turn(EVERY_10_HZ, 26));
        self.step_in_second = (s + 1) % EVERY_SECOND;
        let mut put = |r: Record| sink.record(&r);

        let imu = input.imu;
        put(Record::SensorCombined {
            timestamp: t,
            gyro_rad: [imu.gyro.x, imu.gyro.y, imu.gyro.z],
            accelerometer_m_s2: [imu.accel.x, imu.accel.y, imu.accel.z],
            integral_dt: 2500,
        });
        let att = out.nav.attitude;
        let q = att.attitude;
        put(Record::VehicleAttitude {
            timestamp: t,
            q: [q.w, q.x, q.y, q.z],
        });
        put(Record::VehicleAngularVelocity {
            timestamp: t,
            xyz: [att.rate.x, att.rate.y, att.rate.z],
        });
        let n = out.robots.len();
        let mut output = [0.0; shared::scenario::MAX_ROBOTS];
        if max_thrust > 0.0 {
            for (o, thrust) in output.iter_mut().zip(&out.thrusts[..n]) {
                *o = (thrust / max_thrust).clamp(0.0, 1.0);
            }
        }
        put(Record::ActuatorOutputs {
            timestamp: t,
            noutputs: n as u32,
            output,
        });
        if at_100_hz {
            let pos = out.nav.position;
            put(Record::VehicleLocalPosition {
                timestamp: t,
                valid: pos.valid,
                position: [pos.position.x, pos.position.y, pos.position.z],
                velocity: [pos.velocity.x, pos.velocity.y, pos.velocity.z],
            });
        }
        if (attitude_sp_turn || rates_sp_turn)
            && let Some(c) = &out.cascade
        {
            // PX4's normalised body thrust: the collective over the rotors' total maximum,
            // on body z, negative up.
            let total = max_thrust * n as f32;
            let up = if total > 0.0 {
                -c.collective / total
            } else {
                f32::NAN
            };
            let thrust_body = [0.0, 0.0, up];
            if attitude_sp_turn {
                let q = c.attitude;
                put(Record::VehicleAttitudeSetpoint {
                    timestamp: t,
                    q_d: [q.w, q.x, q.y, q.z],
                    thrust_body,
                });
            } else {
                put(Record::VehicleRatesSetpoint {
                    timestamp: t,
                    rate: [c.rate.x, c.rate.y, c.rate.z],
                    thrust_body,
                });
            }
        }
        if let Some(fix) = input.mocap {
            let q = fix.attitude;
            put(Record::VehicleMocapOdometry {
                timestamp: t,
                timestamp_sample: fix.stamp_us,
                position: [fix.position.x, fix.position.y, fix.position.z],
                q: [q.w, q.x, q.y, q.z],
            });
        }
        let warning = battery_warning(mission.battery_level());
        if battery_turn {
            put(Record::BatteryStatus {
                timestamp: t,
                voltage_v: mission.battery_volts(),
                warning,
            });
        }
        if rail_turn {
            put(Record::RailPosition {
                timestamp: t,
                robots: n as u8,
                commanded_m: per_robot(&out.robots),
            });
        }
        let status = (out.armed, nav_state(out.phase), phase_code(out.phase));
        if status_turn || self.status != Some(status) {
            put(Record::VehicleStatus {
                timestamp: t,
                armed: status.0,
                nav_state: status.1,
                mission_phase: status.2,
            });
            self.status = Some(status);
        }
        let f = input.faults;
        let fault = (
            f.rotors_out,
            f.stalled_robots,
            f.imu,
            mission.imu_dropped(),
            mission.link_up(),
            warning,
        );
        if fault_turn || self.fault != Some(fault) {
            put(Record::Fault {
                timestamp: t,
                rotors_out: fault.0,
                stalled_robots: fault.1,
                imu: fault.2,
                imu_dropped: fault.3,
                gcs_link: fault.4,
                battery_warning: fault.5,
            });
            self.fault = Some(fault);
        }
        if sticks_turn || switches_turn {
            manual_records(t, mission, sticks_turn, &mut put);
        }
        self.estimation(t, out, mission, &mut put);
        if let Some(a) = out.adaptation {
            let (event, com_mass, duration_s) = match a {
                AdaptEvent::Shifted { com, mass } => (0, [com.x, com.y, mass], f32::NAN),
                AdaptEvent::Moving { duration } => (1, [f32::NAN; 3], duration),
                AdaptEvent::Rebalanced => (2, [f32::NAN; 3], f32::NAN),
                AdaptEvent::GaveUp => (3, [f32::NAN; 3], f32::NAN),
            };
            put(Record::Adaptation {
                timestamp: t,
                event,
                com_mass,
                duration_s,
            });
            if a == AdaptEvent::Rebalanced {
                put(Record::Formation {
                    timestamp: t,
                    robots: n as u8,
                    position_m: per_robot(&out.robots),
                    det_bbt: f32::NAN,
                    in_flight: true,
                });
            }
        }
        self.texts(t, out, sink);
    }

    /// Records what the step at `t` (us) says to people (unless its caller logs that itself).
    pub fn texts(&self, t: u64, out: &TickOutput, sink: &mut impl RecordSink) {
        if !self.texts_elsewhere {
            step_texts(out, &mut |level, text| sink.text(level, t, text));
        }
    }

    /// The estimation's records: a lift once its reading's update has come back, the
    /// formation once decided.
    fn estimation(
        &mut self,
        t: u64,
        out: &TickOutput,
        mission: &Mission,
        put: &mut impl FnMut(Record),
    ) {
        if let Some(tr) = out.transition {
            match tr.reason {
                Reason::PairChosen { group, information } => {
                    self.pair = Some((group as u8, information));
                }
                Reason::LiftRead(m) => {
                    let thrust = match m {
                        Measurement::Lifted { thrust } => Some(thrust),
                        Measurement::CouldNotLift => None,
                    };
                    self.reading = Some((t, thrust));
                }
                Reason::FormationChosen(det) => {
                    if let Some(positions) = mission.formation() {
                        put(Record::Formation {
                            timestamp: t,
                            robots: positions.len() as u8,
                            position_m: per_robot(positions),
                            det_bbt: det,
                            in_flight: false,
                        });
                    }
                }
                _ => {}
            }
        }
        // The update of a reading comes back some steps after it (a job): the lift is
        // recorded with the estimate after it (nothing of it read while no reading waits).
        let Some((_, thrust)) = self.reading else {
            return;
        };
        let lifts = mission.measurements();
        if lifts > self.lifts {
            let estimate = mission.latest_estimate();
            let (pair, information) = self.pair.unwrap_or((u8::MAX, f32::NAN));
            put(Record::Lift {
                timestamp: t,
                pair,
                information_nats: information,
                thrust_n: thrust,
                lifts,
                theta: estimate.map_or([f32::NAN; 3], |e| e.theta),
                confidence: estimate.map_or(f32::NAN, |e| e.confidence),
                spread: estimate.map_or([f32::NAN; 3], |e| e.spread),
                model_n: estimate.and_then(|e| e.model_lift).unwrap_or(f32::NAN),
            });
            self.lifts = lifts;
            self.reading = None;
        }
    }
}

/// The texts a step says to people, each with its level: what the firmware sends as
/// `STATUSTEXT` and the log keeps as logged strings. Each transition as `phase: NAME: reason`
/// (critical for a kill, a failed take-off or a critical battery, a warning for another
/// abort), each step of the in-flight adaptation as `adapt: ...` (notice), each notice of the
/// supervision (critical for a critical battery, notice for a link regained, else a warning)
/// and a refused command as `command NAME refused: why` (error).
pub fn step_texts(out: &TickOutput, each: &mut impl FnMut(LogLevel, core::fmt::Arguments<'_>)) {
    if let Some(reply) = out.reply
        && let Err(why) = reply.outcome
    {
        each(
            LogLevel::Error,
            format_args!("command {} refused: {why}", reply.command.name()),
        );
    }
    if let Some(t) = out.transition {
        let level = match t.reason {
            Reason::Abort(
                AbortReason::Killed
                | AbortReason::TakeoffFailed { .. }
                | AbortReason::BatteryCritical { .. },
            ) => LogLevel::Critical,
            Reason::Abort(_) => LogLevel::Warning,
            _ => LogLevel::Info,
        };
        each(level, format_args!("phase: {}: {}", t.to.name(), t.reason));
    }
    if let Some(event) = out.adaptation {
        each(LogLevel::Notice, format_args!("adapt: {event}"));
    }
    if let Some(notice) = out.notice {
        let level = match notice {
            Notice::BatteryCritical { .. } | Notice::RotorsOut { .. } => LogLevel::Critical,
            Notice::LinkRegained { .. } | Notice::LiftDelayed { .. } => LogLevel::Notice,
            _ => LogLevel::Warning,
        };
        each(level, format_args!("{notice}"));
    }
}

/// The manual control in force as PX4's `manual_control_setpoint` (`sticks`) or
/// `manual_control_switches`.
fn manual_records(t: u64, mission: &Mission, sticks: bool, put: &mut impl FnMut(Record)) {
    use shared::manual::source::{Manual, Source};
    let (valid, source, input) = match mission.manual() {
        Manual::Valid(source, input) => (true, Some(source), input),
        Manual::Lost(source) => (false, Some(source), shared::manual::ManualInput::NONE),
        Manual::Never => (false, None, shared::manual::ManualInput::NONE),
    };
    if sticks {
        let s = input.sticks;
        put(Record::ManualControlSetpoint {
            timestamp: t,
            valid,
            data_source: match source {
                Some(Source::Rc) => 0,
                Some(Source::Mavlink) => 1,
                None => 255,
            },
            sticks: [s.roll, s.pitch, s.yaw, 2.0 * s.throttle - 1.0],
        });
    } else {
        put(Record::ManualControlSwitches {
            timestamp: t,
            mode_slot: input.mode_slot.map_or(0, |slot| slot + 1),
            kill_switch: if mission.kill_switch() { 1 } else { 3 },
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_phase_number_reads_back_as_its_phase() {
        for code in 0..=u8::MAX {
            match phase_from_code(code) {
                Some(phase) => assert_eq!(phase_code(phase), code),
                None => assert!(code > 15, "{code} names no phase"),
            }
        }
    }
}
