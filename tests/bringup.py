#!/usr/bin/env python3
"""The bring-up commands against the firmware under QEMU, with pymavlink, through
`host-sim hil --gcs` (docs/ground-link.md#bring-up-commands).

Run by tests/hil/ground/bringup.rs (cargo test); by hand:

    python3 tests/bringup.py --host-sim target/debug/host-sim \
        --elf target/thumbv7em-none-eabihf/release/firmware-qemu \
        --scenario tests/scenarios/rect-ex1.toml

The plant runs with `--unconfirmed-rails` (the rails are this script's to confirm) and
`--gyro-bias 0.02,-0.015,0.01` (what the gyro calibration must find), paced at real time so
the vehicle's seconds (a calibration's 2 s, a motor test's timeout, a jog's move) are the
script's. What it checks, in order, on one run of the firmware:

1. unconfirmed rails: MAV_CMD_MISSION_START refused DENIED, a STATUSTEXT saying `refused:
   rail: ...`; the rail positions (DEBUG_FLOAT_ARRAY `rail`) not a number;
2. MAV_CMD_USER_1 (31010) with param1 = 0 DENIED, with param1 = 1 ACCEPTED; the rail
   positions then the scenario's start positions;
3. MAV_CMD_USER_2 (31011): robot 1 jogged 20 mm (ACCEPTED, the rail stream shows it there),
   a start refused naming robot 1 20 mm from its start position, jogged back; a jog that
   would bring robot 1 within min_spacing of robot 2 DENIED with its text, robot 99 DENIED;
4. MAV_CMD_PREFLIGHT_CALIBRATION: the gyro (IN_PROGRESS, a jog meanwhile TEMPORARILY_REJECTED,
   then ACCEPTED), CAL_GYRO0_XOFF/YOFF/ZOFF within 10 % of the plant's bias (read with
   PARAM_REQUEST_READ); the level (param5 = 2: IN_PROGRESS, then ACCEPTED), CAL_ACC0_* small;
5. MAV_CMD_DO_MOTOR_TEST: motor 2 at 15 % for 1 s (ACTUATOR_OUTPUT_STATUS actuator[1] 0.15,
   the others 0; SERVO_OUTPUT_RAW servo2_raw 1150, the others 1000), all stopped after the
   timeout; a 3 s test stopped early by another command (31010 again); with COM_MOT_TEST_EN = 0
   a test DENIED, then the parameter set back to 1;
6. MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN (param1 = 1) on the ground: ACCEPTED; the firmware comes
   back with the payload description restored from storage (the rail positions unconfirmed
   again, not a number), CAL_GYRO0_XOFF kept; confirmed again;
7. the mission started (ACCEPTED); while it runs a jog, a calibration, a motor test and a
   reboot refused (DENIED or TEMPORARILY_REJECTED), each with a STATUSTEXT; then aborted
   (MAV_CMD_COMPONENT_ARM_DISARM, param1 = 0), and the plant's report shows the mission
   aborted on the ground, the one restart of the firmware, and its texts saying `rebooting`
   and `payload description restored from storage`.

It waits for the vehicle's state (the rail positions, the outputs, the HEARTBEAT), never for a
progress text that may pass by before it listens.

Exit status 0 when everything holds; 2 with one line on stderr when pymavlink is missing.
"""

import argparse
import json
import math
import os
import sys
import time
import tomllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ground_station as gs  # noqa: E402  (pymavlink's absence exits 2 there)
from ground_station import Failure, mavlink  # noqa: E402

GYRO_BIAS = (0.02, -0.015, 0.01)
CONFIRM_RAILS = 31010  # MAV_CMD_USER_1
JOG = 31011  # MAV_CMD_USER_2
IN_PROGRESS = getattr(mavlink, "MAV_RESULT_IN_PROGRESS", 5)
ACCEPTED = mavlink.MAV_RESULT_ACCEPTED
DENIED = mavlink.MAV_RESULT_DENIED
TEMPORARILY_REJECTED = mavlink.MAV_RESULT_TEMPORARILY_REJECTED
REFUSED = (DENIED, TEMPORARILY_REJECTED)
CALIBRATION = mavlink.MAV_CMD_PREFLIGHT_CALIBRATION
MOTOR_TEST = mavlink.MAV_CMD_DO_MOTOR_TEST
REBOOT = mavlink.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN
# How close a robot must come to where it was sent, m (the firmware's mark tolerance).
MARK_TOLERANCE = 0.001


class Scenario:
    """What the checks need of the scenario file: the robots' start positions along the rail
    and their least spacing."""

    def __init__(self, path):
        with open(path, "rb") as f:
            s = tomllib.load(f)
        robots = s["robots"]
        self.count = robots["count"]
        self.min_spacing = robots["min_spacing"]
        rail = s["payload"]["rail"]
        self.perimeter = sum(math.dist(a, b) for a, b in zip(rail, rail[1:] + rail[:1]))
        self.initial = robots.get(
            "initial", [j * self.perimeter / self.count for j in range(self.count)])


def result_name(result):
    names = mavlink.enums["MAV_RESULT"]
    return names[result].name.removeprefix("MAV_RESULT_") if result in names else str(result)


def expect_result(ack, wanted, what):
    wanted = wanted if isinstance(wanted, tuple) else (wanted,)
    if ack.result not in wanted:
        names = " or ".join(result_name(w) for w in wanted)
        raise Failure(f"{what}: COMMAND_ACK {result_name(ack.result)}, expected {names}")
    return ack.result


def refused_with(v, ack, wanted, says, what):
    """`ack` is one of `wanted` and a STATUSTEXT containing `says` comes (or came)."""
    result = expect_result(ack, wanted, what)
    v.text_matching(says, 10)
    return result


def start(v):
    """MAV_CMD_MISSION_START, tried again while the vehicle loads its planner (the payload
    description, new parameters: TEMPORARILY_REJECTED with a STATUSTEXT saying so)."""
    deadline = time.monotonic() + 20
    while True:
        ack = v.command(mavlink.MAV_CMD_MISSION_START)
        loading = ack.result == TEMPORARILY_REJECTED and v.has_text("being loaded")
        if not loading or time.monotonic() > deadline:
            return ack
        v.texts.clear()
        time.sleep(0.2)


def rail(v, what, condition=None, timeout=10):
    """The robots' rail positions from the next DEBUG_FLOAT_ARRAY `rail` meeting `condition`."""
    n = v.robots
    m = v.expect(["DEBUG_FLOAT_ARRAY"], timeout, f"rail positions {what}",
                 lambda m: m.name == "rail" and (condition is None or condition(m.data[:n])))
    return list(m.data[:n])


def near(positions, wanted, tolerance=MARK_TOLERANCE):
    return all(abs(p - w) <= tolerance for p, w in zip(positions, wanted))


def unknown(positions):
    return all(math.isnan(p) for p in positions)


def jog(v, robot, metres):
    return v.command(JOG, robot, metres)


def jog_and_wait(v, robot, metres, wanted):
    expect_result(jog(v, robot, metres), ACCEPTED, f"jog of robot {robot} by {metres} m")
    return rail(v, f"with robot {robot} jogged to {wanted[robot - 1]:.3f} m",
                lambda p: near(p, wanted))


def second_ack(v, cmd, timeout, what):
    """The COMMAND_ACK that ends a command acknowledged IN_PROGRESS."""
    return v.expect(["COMMAND_ACK"], timeout, what,
                    lambda m: m.command == cmd and m.result != IN_PROGRESS)


def calibrate(v, what, *params):
    ack = v.command(CALIBRATION, *params)
    expect_result(ack, IN_PROGRESS, f"{what} calibration's first acknowledgement")
    return ack


def outputs(v, what, condition, timeout=5):
    """The next ACTUATOR_OUTPUT_STATUS and SERVO_OUTPUT_RAW that meet `condition(commands,
    pulses)` (each robot's ESC command, fraction; the first eight's pulses, us)."""
    n = v.robots
    end = time.monotonic() + timeout
    status = servo = None
    while time.monotonic() < end:
        m = v.recv(["ACTUATOR_OUTPUT_STATUS", "SERVO_OUTPUT_RAW"], end - time.monotonic())
        if m is None:
            break
        if m.get_type() == "ACTUATOR_OUTPUT_STATUS":
            status = m
        else:
            servo = m
        if status is not None and servo is not None:
            commands = list(status.actuator[:n])
            pulses = [getattr(servo, f"servo{j + 1}_raw") for j in range(min(n, 8))]
            if condition(commands, pulses):
                return commands, pulses, status.active
    raise Failure(f"no ACTUATOR_OUTPUT_STATUS and SERVO_OUTPUT_RAW {what} within {timeout} s "
                  f"(last: {status and list(status.actuator[:n])}, {servo})")


def spinning_alone(motor, fraction):
    """Only `motor` (from 1) at `fraction` of full: its ESC command and pulse, the others' 0
    and 1000 us."""
    def wanted(j):
        return fraction if j == motor - 1 else 0.0

    def condition(commands, pulses):
        return (all(abs(c - wanted(j)) < 0.01 for j, c in enumerate(commands))
                and all(abs(p - (1000 + 1000 * wanted(j))) <= 10 for j, p in enumerate(pulses)))
    return condition


def stopped(commands, pulses):
    return all(c == 0.0 for c in commands) and all(p == 1000 for p in pulses)


def motor_test(v, motor, percent, seconds, count=1):
    return v.command(MOTOR_TEST, motor, 0, percent, seconds, count)


# The checks, in order.

def unconfirmed_checks(v):
    v.payload_loaded(unconfirmed=True)  # the description the plant uploaded
    refused_with(v, start(v), DENIED, "refused: rail: ", "a start with the rails unconfirmed")
    rail(v, "not a number before the confirmation", unknown)
    print("rails unconfirmed: MISSION_START DENIED (STATUSTEXT 'refused: rail: ...'), "
          "the rail positions not a number")


def confirm_checks(v, scenario):
    refused_with(v, v.command(CONFIRM_RAILS, 0), DENIED, "param1 = 1",
                 "31010 with param1 = 0")
    expect_result(v.command(CONFIRM_RAILS, 1), ACCEPTED, "31010 with param1 = 1")
    shown = rail(v, "the start positions once confirmed", lambda p: not unknown(p))
    if not near(shown, scenario.initial):
        raise Failure(f"confirmed rail positions {shown}, the scenario's {scenario.initial}")
    print(f"31010: param1 = 0 DENIED, param1 = 1 ACCEPTED; the rail positions the start "
          f"positions {[round(p, 3) for p in shown]}")


def jog_checks(v, scenario):
    home = list(scenario.initial)
    moved = list(home)
    moved[0] += 0.02
    started = time.monotonic()
    jog_and_wait(v, 1, 0.02, moved)
    took = time.monotonic() - started
    refused_with(v, start(v), DENIED, "rail: robot 1 stands 20 mm from its start position",
                 "a start with robot 1 off its mark")
    jog_and_wait(v, 1, -0.02, home)
    print(f"robot 1 jogged 20 mm (there {took:.1f} s after the command) and back; a start "
          f"meanwhile DENIED: robot 1 stands 20 mm from its start position")

    gap = (home[1] - home[0]) % scenario.perimeter
    too_far = round(gap - scenario.min_spacing + 0.01, 3)
    refused_with(v, jog(v, 1, too_far), DENIED,
                 "rail: robot 1 would come closer than min_spacing",
                 f"a jog of robot 1 by {too_far} m toward robot 2")
    refused_with(v, jog(v, 99, 0.01), DENIED, "no robot 99", "a jog of robot 99")
    rail(v, "unchanged by the refused jogs", lambda p: near(p, home))
    print(f"a jog of {too_far} m (within min_spacing of robot 2) DENIED with its text; "
          f"robot 99 DENIED; the robots where they were")


def calibration_checks(v):
    started = time.monotonic()
    calibrate(v, "the gyro", 1)
    ack = jog(v, 1, 0.01)
    refused_with(v, ack, TEMPORARILY_REJECTED, "under way", "a jog during the calibration")
    ack = second_ack(v, CALIBRATION, 15, "the gyro calibration's end")
    expect_result(ack, ACCEPTED, "the gyro calibration's end")
    took = time.monotonic() - started
    offsets = [v.param_read(f"CAL_GYRO0_{axis}OFF").param_value for axis in "XYZ"]
    for axis, got, bias in zip("XYZ", offsets, GYRO_BIAS):
        if abs(got - bias) > 0.1 * abs(bias):
            raise Failure(f"CAL_GYRO0_{axis}OFF {got:.5f} rad/s, the plant's bias {bias}")
    print(f"gyro calibration: IN_PROGRESS (a jog meanwhile TEMPORARILY_REJECTED), ACCEPTED "
          f"{took:.1f} s later; CAL_GYRO0_*OFF {[round(o, 4) for o in offsets]} rad/s "
          f"(bias {list(GYRO_BIAS)})")

    started = time.monotonic()
    calibrate(v, "the level", 0, 0, 0, 0, 2)
    ack = second_ack(v, CALIBRATION, 15, "the level calibration's end")
    expect_result(ack, ACCEPTED, "the level calibration's end")
    took = time.monotonic() - started
    offsets = [v.param_read(f"CAL_ACC0_{axis}OFF").param_value for axis in "XYZ"]
    if any(abs(o) >= 0.3 for o in offsets):
        raise Failure(f"CAL_ACC0_*OFF {offsets} m/s^2 on a level vehicle at rest")
    print(f"level calibration: IN_PROGRESS, ACCEPTED {took:.1f} s later; CAL_ACC0_*OFF "
          f"{[round(o, 3) for o in offsets]} m/s^2")


def motor_test_checks(v):
    outputs(v, "at rest", stopped)
    expect_result(motor_test(v, 2, 15, 1), ACCEPTED, "a motor test of motor 2 at 15 % for 1 s")
    started = time.monotonic()
    commands, pulses, active = outputs(v, "with motor 2 alone at 15 %", spinning_alone(2, 0.15))
    outputs(v, "stopped after the 1 s timeout", stopped, timeout=5)
    took = time.monotonic() - started
    if took > 2.5:
        raise Failure(f"a 1 s motor test stopped {took:.1f} s after it was seen spinning")
    shown = [round(c, 3) for c in commands]
    print(f"motor test 2 at 15 % for 1 s: ACTUATOR_OUTPUT_STATUS {shown} (active {active:#x}), "
          f"SERVO_OUTPUT_RAW {pulses}; all stopped {took:.1f} s after the ACK")

    expect_result(motor_test(v, 2, 15, 3), ACCEPTED, "a motor test of 3 s")
    outputs(v, "with motor 2 spinning", spinning_alone(2, 0.15))
    expect_result(v.command(CONFIRM_RAILS, 1), ACCEPTED, "31010 during a motor test")
    asked = time.monotonic()
    outputs(v, "stopped by another command", stopped, timeout=5)
    took = time.monotonic() - asked
    if took > 1.5:
        raise Failure(f"the motor test stopped {took:.1f} s after another command")
    print(f"a 3 s motor test stopped {took:.1f} s after another command (31010)")

    if v.param_set("COM_MOT_TEST_EN", 0).param_value != 0:
        raise Failure("COM_MOT_TEST_EN = 0 not taken")
    refused_with(v, motor_test(v, 1, 10, 1), DENIED, "COM_MOT_TEST_EN",
                 "a motor test with COM_MOT_TEST_EN = 0")
    if v.param_set("COM_MOT_TEST_EN", 1).param_value != 1:
        raise Failure("COM_MOT_TEST_EN = 1 not taken")
    outputs(v, "at rest after the refused test", stopped)
    print("COM_MOT_TEST_EN = 0: a motor test DENIED with a STATUSTEXT; set back to 1")


def reboot_checks(v):
    gyro_x = v.param_read("CAL_GYRO0_XOFF").param_value
    started = time.monotonic()
    v.texts.clear()
    expect_result(v.command(REBOOT, 1), ACCEPTED, "a reboot on the ground")
    # The rails were confirmed before: positions not known again mean the new boot runs with
    # the description restored from its storage (the texts saying so are checked in the
    # plant's report, which loses none).
    v.payload_loaded(unconfirmed=True)
    took = time.monotonic() - started
    kept = v.param_read("CAL_GYRO0_XOFF").param_value
    if kept != gyro_x:
        raise Failure(f"CAL_GYRO0_XOFF {kept} after the reboot, {gyro_x} before")
    expect_result(v.command(CONFIRM_RAILS, 1), ACCEPTED, "31010 after the reboot")
    rail(v, "known again once confirmed", lambda p: not unknown(p))
    print(f"reboot: ACCEPTED, the firmware back {took:.1f} s later with the payload "
          f"description restored, the rails unconfirmed again, CAL_GYRO0_XOFF kept; confirmed")


def running_checks(v):
    expect_result(start(v), ACCEPTED, "MISSION_START with the rails confirmed")
    v.mission_state([gs.RUNNING], "started", 20)
    refusals = [
        ("a jog", lambda: jog(v, 1, 0.01)),
        ("a gyro calibration", lambda: v.command(CALIBRATION, 1)),
        ("a motor test", lambda: motor_test(v, 1, 10, 1)),
        ("a reboot", lambda: v.command(REBOOT, 1)),
    ]
    results = []
    for what, send in refusals:
        v.texts.clear()
        result = refused_with(v, send(), REFUSED, "running", f"{what} while the mission runs")
        results.append(f"{what} {result_name(result)}")
    print(f"mission started; while it runs {', '.join(results)}, each with a STATUSTEXT")
    expect_result(v.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0), ACCEPTED, "an abort")


def report_checks(plant):
    out, err = plant.communicate(timeout=120)
    try:
        report = json.loads(out)
    except json.JSONDecodeError:
        raise Failure(f"host-sim printed no JSON (exit {plant.returncode}): {err[-500:]}")
    if report["mission_state"] != "aborted" or report["dropped"]:
        raise Failure(f"the mission ended {report['mission_state']}, dropped "
                      f"{report['dropped']} (exit {plant.returncode})")
    if len(report["restarts"]) != 1:
        raise Failure(f"the plant saw {len(report['restarts'])} restarts: {report['restarts']}")
    texts = [t["text"] for t in report["statustexts"]]
    for says in ("rebooting", "payload description restored from storage"):
        if not any(says in t for t in texts):
            raise Failure(f"the vehicle never said {says!r}: {texts[-5:]}")
    print(f"aborted on the ground (host-sim exit {plant.returncode}); the plant saw the "
          f"firmware restart once: {report['restarts'][0]}")


def main():
    # run_against_plant reads the arguments itself; the scenario file is needed here too.
    known = argparse.ArgumentParser(add_help=False)
    known.add_argument("--scenario", required=True)
    scenario = Scenario(known.parse_known_args()[0].scenario)

    def checks(plant):
        v = gs.connect(plant)
        v.robots = scenario.count  # how many of each stream's entries are robots
        sections = [
            ("unconfirmed rails", lambda: unconfirmed_checks(v)),
            ("confirmation", lambda: confirm_checks(v, scenario)),
            ("jogs", lambda: jog_checks(v, scenario)),
            ("calibrations", lambda: calibration_checks(v)),
            ("motor tests", lambda: motor_test_checks(v)),
            ("reboot", lambda: reboot_checks(v)),
            ("while running", lambda: running_checks(v)),
            ("the plant's report", lambda: report_checks(plant)),
        ]
        for name, section in sections:
            started = time.monotonic()
            section()
            print(f"  ({name}: {time.monotonic() - started:.1f} s)")

    bias = ",".join(str(b) for b in GYRO_BIAS)
    return gs.run_against_plant("bring-up", __doc__.splitlines()[0], checks,
                                ["--speed", "1", "--unconfirmed-rails", f"--gyro-bias={bias}"])


if __name__ == "__main__":
    sys.exit(main())
