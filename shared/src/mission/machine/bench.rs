//! The mission's bring-up side (docs/ground-link.md#bring-up-commands): the rail positions
//! confirmed, a robot jogged along the rail, the IMU's calibrations and the motor test, all on
//! the ground with the mission not running. The maths is [`crate::mission::bringup`]'s.

use super::Mission;
use crate::control::navigator::ImuSample;
use crate::control::thrust_map::ThrustMap;
use crate::math;
use crate::mission::bringup::{
    BenchConfig, CalibrationFailure, CalibrationKind, ImuCalibration, MotorTest, MotorTestRequest,
    SensorOffsets,
};
use crate::mission::interface::{CommandRefusal, OperatorCommand};
use crate::rail::moves::{Positions, RailMove};
use crate::scenario::MAX_ROBOTS;

/// How far a robot may stand from its start position and still count as on it, m.
pub const MARK_TOLERANCE: f32 = 0.001;

/// A robot's move along the rail asked for by a jog: the move, where it ends, the time since
/// it began (s).
#[derive(Clone, Debug)]
pub(super) struct Jog {
    rail_move: RailMove,
    target: Positions,
    elapsed: f32,
}

/// What is under way on the bench.
#[derive(Clone, Debug, Default)]
pub(super) struct Bench {
    /// The rail positions are known: confirmed by the operator since power-up, and no robot
    /// stalled since.
    pub(super) rails_confirmed: bool,
    pub(super) jog: Option<Jog>,
    pub(super) calibration: Option<ImuCalibration>,
    pub(super) motor_test: Option<MotorTest>,
}

impl Bench {
    /// Nothing under way, the rails unconfirmed (a constant for [`Mission::unloaded`]).
    pub(super) const IDLE: Self = Self {
        rails_confirmed: false,
        jog: None,
        calibration: None,
        motor_test: None,
    };

    #[inline]
    pub(super) fn busy(&self) -> bool {
        self.jog.is_some() || self.calibration.is_some() || self.motor_test.is_some()
    }
}

impl Mission {
    /// Whether the rail positions are known (confirmed since power-up, no stall since).
    pub fn rails_confirmed(&self) -> bool {
        self.bench.rails_confirmed
    }

    /// A jog, a calibration or a motor test is under way.
    #[inline]
    pub(super) fn bench_busy(&self) -> bool {
        self.bench.busy()
    }

    /// A motor test spins rotors now.
    pub fn motor_testing(&self) -> bool {
        self.bench.motor_test.is_some()
    }

    /// The IMU's offsets in force.
    pub fn sensor_offsets(&self) -> SensorOffsets {
        self.config.sensors
    }

    /// Puts the parameters' IMU offsets and hardware settings in force without a payload
    /// description (the rest of `config` is taken when one is loaded). Not while the mission
    /// runs: a new offset in flight would step the attitude.
    pub fn configure_bench(&mut self, config: &BenchConfig) {
        if self.not_running() {
            self.config.sensors = config.sensors;
            self.config.hardware = config.hardware;
        }
    }

    /// The pre-arm check of the rails: confirmed, and each robot at its start position.
    pub(super) fn rails_ready(&self) -> Result<(), CommandRefusal> {
        if !self.bench.rails_confirmed {
            return Err(CommandRefusal::RailsUnconfirmed);
        }
        self.robots_on_marks()
    }

    /// Each robot at its start position, or the first that is not.
    fn robots_on_marks(&self) -> Result<(), CommandRefusal> {
        let initial = &self.scenario.robots.initial;
        let rail = &self.scenario.payload.rail;
        let half = 0.5 * rail.perimeter();
        for (j, (&at, &mark)) in self.robots.iter().zip(initial.iter()).enumerate() {
            // The shorter way round: a robot at 0 jogged back stands at the perimeter's end.
            let ahead = rail.forward_gap(mark, at);
            let off = if ahead > half {
                ahead - 2.0 * half
            } else {
                ahead
            };
            if off.abs() > MARK_TOLERANCE {
                return Err(CommandRefusal::RobotOffMark {
                    robot: j as u8 + 1,
                    millimetres: math::round(off * 1000.0) as i32,
                });
            }
        }
        Ok(())
    }

    /// A bring-up command: taken only on the ground with the mission not running.
    pub(super) fn bench_command(&mut self, command: OperatorCommand) -> Result<(), CommandRefusal> {
        if !self.not_running() {
            return Err(CommandRefusal::MissionRunning);
        }
        let robots = self.scenario.robots.count();
        let needs_payload = !matches!(command, OperatorCommand::Calibrate(_));
        if needs_payload && robots == 0 {
            return Err(CommandRefusal::NoPayload);
        }
        // A new motor test replaces one under way; anything else waits for the bench.
        if self.bench.busy() && !matches!(command, OperatorCommand::MotorTest(_)) {
            return Err(CommandRefusal::BenchBusy);
        }
        match command {
            OperatorCommand::ConfirmRails => {
                self.robots_on_marks()?;
                self.bench.rails_confirmed = true;
            }
            OperatorCommand::Jog { robot, micrometres } => {
                self.jog(robot, micrometres as f32 * 1e-6)?;
            }
            OperatorCommand::Calibrate(kind) => {
                self.bench.calibration = Some(ImuCalibration::new(kind));
            }
            OperatorCommand::MotorTest(MotorTestRequest {
                first,
                count,
                permille,
                millis,
            }) => {
                if !self.config.hardware.motor_test_enabled {
                    return Err(CommandRefusal::MotorTestDisabled);
                }
                let count_ok = usize::from(first) + usize::from(count.max(1)) <= robots + 1;
                if first == 0 || !count_ok {
                    return Err(CommandRefusal::NoSuchRobot {
                        robot: first.saturating_add(count.max(1)).saturating_sub(1),
                        robots: robots as u8,
                    });
                }
                self.bench.motor_test = Some(MotorTest::new(
                    first - 1,
                    count.max(1),
                    f32::from(permille) * 1e-3,
                    f32::from(millis) * 1e-3,
                ));
            }
            _ => {}
        }
        Ok(())
    }

    /// Plans robot `robot`'s (from 1) move by `metres` along the rail.
    fn jog(&mut self, robot: u8, metres: f32) -> Result<(), CommandRefusal> {
        let robots = self.robots.len();
        let j = usize::from(robot).wrapping_sub(1);
        if j >= robots {
            return Err(CommandRefusal::NoSuchRobot {
                robot,
                robots: robots as u8,
            });
        }
        let rail = &self.scenario.payload.rail;
        let mut target = self.robots.clone();
        target[j] = rail.wrap(target[j] + metres);
        let spacing = self.scenario.robots.min_spacing;
        let rail_move = RailMove::plan(
            rail,
            &self.robots,
            &target,
            spacing,
            self.config.rail_limits,
        )
        .map_err(|_| CommandRefusal::JogTooFar { robot })?;
        self.bench.jog = Some(Jog {
            rail_move,
            target,
            elapsed: 0.0,
        });
        Ok(())
    }

    /// A command stops a motor test under way (the test's own command starts a new one).
    pub(super) fn stop_motor_test_for(&mut self, command: OperatorCommand) {
        if !matches!(command, OperatorCommand::MotorTest(_)) {
            self.bench.motor_test = None;
        }
    }

    /// The bench's part of a tick: the jog's move, a calibration's sample (`raw`, before the
    /// offsets), the motor test's rotors (thrust in N into `thrusts`). Returns whether a
    /// motor test spins rotors, and a calibration that ended.
    #[allow(clippy::type_complexity)]
    pub(super) fn bench_step(
        &mut self,
        raw: &ImuSample,
        dt: f32,
        stalled: bool,
        thrusts: &mut [f32; MAX_ROBOTS],
    ) -> (
        bool,
        Option<(CalibrationKind, Result<[f32; 3], CalibrationFailure>)>,
    ) {
        if stalled {
            // A stalled robot lost steps: where the robots are is not known any more.
            self.bench.rails_confirmed = false;
            self.bench.jog = None;
        }
        if !self.not_running() {
            return (false, None);
        }
        if let Some(jog) = self.bench.jog.as_mut() {
            jog.elapsed += dt;
            if jog.elapsed < jog.rail_move.duration() {
                self.robots = jog
                    .rail_move
                    .positions_at(&self.scenario.payload.rail, jog.elapsed);
            } else {
                self.robots.clone_from(&jog.target);
                self.bench.jog = None;
            }
        }
        let mut calibrated = None;
        if let Some(calibration) = self.bench.calibration.as_mut()
            && let Some(result) = calibration.add(raw)
        {
            let kind = calibration.kind();
            self.bench.calibration = None;
            if let Ok(offsets) = result {
                match kind {
                    CalibrationKind::Gyro => self.config.sensors.gyro = offsets,
                    CalibrationKind::Level => self.config.sensors.accel = offsets,
                }
            }
            calibrated = Some((kind, result));
        }
        let mut spinning = false;
        if let Some(test) = self.bench.motor_test.as_mut() {
            let map = ThrustMap::new(self.config.hardware.thrust_map).unwrap_or_default();
            let max = self.scenario.robots.max_thrust;
            for (j, thrust) in thrusts
                .iter_mut()
                .enumerate()
                .take(self.robots.len().min(MAX_ROBOTS))
            {
                *thrust = map.thrust(test.command(j)) * max;
            }
            spinning = true;
            if !test.step(dt) {
                self.bench.motor_test = None;
            }
        }
        (spinning, calibrated)
    }
}
