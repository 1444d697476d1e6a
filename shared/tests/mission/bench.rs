//! The bring-up commands in the mission (docs/ground-link.md#bring-up-commands): the rails'
//! pre-arm check, the jog, the IMU's calibrations and the motor test, on the ground only.

use super::*;
use shared::mission::bringup::{CALIBRATION_SAMPLES, CalibrationKind, MotorTestRequest};

/// A flight controller's mission: unloaded, then given `s` (its rails unconfirmed).
fn on_the_bench(s: &Scenario) -> Mission {
    let mut mission = Mission::UNLOADED;
    mission.load(s, MissionConfig::default());
    mission
}

/// The reply to `command` sent at `tick`.
fn reply(
    mission: &mut Mission,
    world: &World,
    tick: u64,
    command: OperatorCommand,
) -> Result<(), CommandRefusal> {
    let out = mission.step(&world.input(tick, Some(command)));
    out.reply.expect("every command is answered").outcome
}

#[test]
fn the_start_waits_for_the_rails_and_each_robot_on_its_mark() {
    let s = straight_up_scenario(3.5);
    let world = World::new(&s);
    let mut mission = on_the_bench(&s);
    assert!(!mission.rails_confirmed());
    assert_eq!(
        reply(&mut mission, &world, 1, OperatorCommand::Start),
        Err(CommandRefusal::RailsUnconfirmed)
    );
    // Robot 2 jogged 30 mm: the move runs over some ticks, then the robot stands there.
    let before = s.robots.initial[1];
    let jog = OperatorCommand::Jog {
        robot: 2,
        micrometres: 30_000,
    };
    assert_eq!(reply(&mut mission, &world, 2, jog), Ok(()));
    let mut tick = 3;
    let mut last = None;
    while tick < 2_000 {
        let out = mission.step(&world.input(tick, None));
        assert!(!out.armed);
        last = Some(out.robots.clone());
        tick += 1;
    }
    let robots = last.expect("ticks ran");
    assert!((robots[1] - before - 0.03).abs() < 1e-5, "{robots:?}");
    assert_eq!(robots[0], s.robots.initial[0]);
    // Off its mark: not confirmed, not started.
    assert_eq!(
        reply(&mut mission, &world, tick, OperatorCommand::ConfirmRails),
        Err(CommandRefusal::RobotOffMark {
            robot: 2,
            millimetres: 30
        })
    );
    // Jogged back, confirmed, started.
    let back = OperatorCommand::Jog {
        robot: 2,
        micrometres: -30_000,
    };
    assert_eq!(reply(&mut mission, &world, tick + 1, back), Ok(()));
    for t in tick + 2..tick + 2_000 {
        mission.step(&world.input(t, None));
    }
    tick += 2_000;
    assert_eq!(
        reply(&mut mission, &world, tick, OperatorCommand::ConfirmRails),
        Ok(())
    );
    assert!(mission.rails_confirmed());
    assert_eq!(
        reply(&mut mission, &world, tick + 1, OperatorCommand::Start),
        Ok(())
    );
    // Running: every bring-up command is refused.
    for c in [
        OperatorCommand::ConfirmRails,
        jog,
        OperatorCommand::Calibrate(CalibrationKind::Gyro),
        OperatorCommand::MotorTest(MotorTestRequest {
            first: 1,
            count: 1,
            permille: 100,
            millis: 1000,
        }),
    ] {
        assert_eq!(
            reply(&mut mission, &world, tick + 2, c),
            Err(CommandRefusal::MissionRunning)
        );
    }
}

#[test]
fn a_jog_is_bounded_by_the_neighbours_and_the_robots_it_has() {
    let s = straight_up_scenario(3.5);
    let world = World::new(&s);
    let mut mission = on_the_bench(&s);
    let gap = s.robots.initial[1] - s.robots.initial[0];
    let into_neighbour = OperatorCommand::Jog {
        robot: 1,
        micrometres: (gap * 1e6) as i32,
    };
    assert_eq!(
        reply(&mut mission, &world, 1, into_neighbour),
        Err(CommandRefusal::JogTooFar { robot: 1 })
    );
    let n = s.robots.count() as u8;
    assert_eq!(
        reply(
            &mut mission,
            &world,
            2,
            OperatorCommand::Jog {
                robot: n + 1,
                micrometres: 1000
            }
        ),
        Err(CommandRefusal::NoSuchRobot {
            robot: n + 1,
            robots: n
        })
    );
    // Nothing moved.
    let out = mission.step(&world.input(3, None));
    assert_eq!(&out.robots[..], &s.robots.initial[..]);
}

#[test]
fn a_gyro_calibration_puts_its_offsets_in_force() {
    let s = straight_up_scenario(3.5);
    let world = World::new(&s);
    let mut mission = on_the_bench(&s);
    let calibrate = OperatorCommand::Calibrate(CalibrationKind::Gyro);
    assert_eq!(reply(&mut mission, &world, 1, calibrate), Ok(()));
    // Busy meanwhile.
    assert_eq!(
        reply(&mut mission, &world, 2, calibrate),
        Err(CommandRefusal::BenchBusy)
    );
    let mut found = None;
    for tick in 3..3 + u64::from(CALIBRATION_SAMPLES) {
        let mut input = world.input(tick, None);
        input.imu.gyro.x += 0.04;
        input.imu.gyro.y -= 0.02;
        if let Some(done) = mission.step(&input).calibrated {
            found = Some((tick, done));
        }
    }
    let (tick, (kind, result)) = found.expect("the calibration ends");
    // The command's own tick takes the first sample.
    assert_eq!(tick, u64::from(CALIBRATION_SAMPLES));
    assert_eq!(kind, CalibrationKind::Gyro);
    let offsets = result.expect("at rest");
    assert!((offsets[0] - 0.04).abs() < 1e-3 && (offsets[1] + 0.02).abs() < 1e-3);
    assert_eq!(mission.sensor_offsets().gyro, offsets);
}

#[test]
fn a_motor_test_spins_the_rotors_asked_for_until_its_time_or_another_command() {
    let s = straight_up_scenario(3.5);
    let world = World::new(&s);
    let mut mission = on_the_bench(&s);
    let test = OperatorCommand::MotorTest(MotorTestRequest {
        first: 2,
        count: 1,
        permille: 200,
        millis: 500,
    });
    let out = mission.step(&world.input(1, Some(test)));
    assert_eq!(out.reply.map(|r| r.outcome), Some(Ok(())));
    assert!(out.armed);
    // 20 % command on the square law: 4 % of full thrust, robot 2's rotor alone.
    let max = s.robots.max_thrust;
    assert!(
        (out.thrusts[1] - 0.04 * max).abs() < 1e-4,
        "{:?}",
        out.thrusts
    );
    assert!(
        out.thrusts
            .iter()
            .enumerate()
            .all(|(j, &t)| j == 1 || t == 0.0)
    );
    assert!(out.motor_test);
    // Stopped at 0.5 s; every tick that spins them says it is the motor test's, the last too.
    let mut spinning = 1;
    for tick in 2..400 {
        let out = mission.step(&world.input(tick, None));
        assert_eq!(out.armed, out.motor_test, "tick {tick}");
        if out.armed {
            spinning += 1;
        }
    }
    assert!((200..=201).contains(&spinning), "{spinning}");
    // Stopped by any other command, which is then taken as usual.
    assert_eq!(reply(&mut mission, &world, 400, test), Ok(()));
    let out = mission.step(&world.input(401, Some(OperatorCommand::Abort)));
    assert!(!out.armed && out.thrusts.iter().all(|&t| t == 0.0));
    // Switched off by COM_MOT_TEST_EN.
    let mut config = MissionConfig::default();
    config.hardware.motor_test_enabled = false;
    let mut off = Mission::UNLOADED;
    off.load(&s, config);
    assert_eq!(
        reply(&mut off, &world, 1, test),
        Err(CommandRefusal::MotorTestDisabled)
    );
    let n = s.robots.count() as u8;
    assert!(matches!(
        reply(
            &mut mission,
            &world,
            402,
            OperatorCommand::MotorTest(MotorTestRequest {
                first: n,
                count: 2,
                permille: 100,
                millis: 100
            })
        ),
        Err(CommandRefusal::NoSuchRobot { .. })
    ));
}

#[test]
fn a_robot_jogged_back_past_the_rails_start_is_off_its_mark_by_the_short_way() {
    let s = straight_up_scenario(3.5);
    let world = World::new(&s);
    let mut mission = on_the_bench(&s);
    let back = OperatorCommand::Jog {
        robot: 1,
        micrometres: -20_000,
    };
    assert_eq!(reply(&mut mission, &world, 1, back), Ok(()));
    for tick in 2..2_000 {
        mission.step(&world.input(tick, None));
    }
    assert_eq!(
        reply(&mut mission, &world, 2_000, OperatorCommand::ConfirmRails),
        Err(CommandRefusal::RobotOffMark {
            robot: 1,
            millimetres: -20
        })
    );
    let forward = OperatorCommand::Jog {
        robot: 1,
        micrometres: 20_000,
    };
    assert_eq!(reply(&mut mission, &world, 2_001, forward), Ok(()));
    for tick in 2_002..4_000 {
        mission.step(&world.input(tick, None));
    }
    assert_eq!(
        reply(&mut mission, &world, 4_000, OperatorCommand::ConfirmRails),
        Ok(())
    );
}
