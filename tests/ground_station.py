#!/usr/bin/env python3
"""A real ground station against the firmware under QEMU: pymavlink, as
QGroundControl and MAVProxy talk to a vehicle, through `host-sim hil --gcs`.

Run by tests/hil/ground/ground_station.rs (cargo test); by hand:

    python3 tests/ground_station.py --host-sim target/debug/host-sim \
        --elf target/thumbv7em-none-eabihf/release/firmware-qemu \
        --scenario tests/scenarios/rect-ex1.toml

Two runs of the firmware share one parameter flash (`--storage DIR`):

1. connect (HEARTBEAT from component 1, MAV_AUTOPILOT_GENERIC), AUTOPILOT_VERSION through
   MAV_CMD_REQUEST_MESSAGE as COMMAND_LONG and COMMAND_INT (capabilities MAVLink 2, COMMAND_INT,
   FTP, byte-wise parameter encoding, MISSION_INT), MISSION_COUNT 0 (no mission stored yet),
   telemetry (SYS_STATUS, ATTITUDE_QUATERNION, LOCAL_POSITION_NED and the robots' rail positions
   as DEBUG_FLOAT_ARRAY streamed; a stream stopped
   and restarted by MAV_CMD_SET_MESSAGE_INTERVAL, a bad interval and an unstreamed message
   refused, SYS_STATUS sent once on MAV_CMD_REQUEST_MESSAGE), the map origin (GPS_GLOBAL_ORIGIN
   the default, then set with SET_GPS_GLOBAL_ORIGIN and read back, set with
   MAV_CMD_DO_SET_GLOBAL_ORIGIN as COMMAND_INT and read back, a bad frame and latitude refused,
   NAV_TAKEOFF as COMMAND_INT UNSUPPORTED; HOME_POSITION on request
   and on MAV_CMD_GET_HOME_POSITION; GLOBAL_POSITION_INT the local position through it),
   TIMESYNC answered and asked,
   every parameter (count and indices consistent, read back by name and by index), the
   parameter metadata read over MAVLink FTP as QGroundControl reads it (the general file, the
   parameter file of its CRC-32, xz-compressed, naming every parameter), arming
   refused with its COMMAND_ACK and a STATUSTEXT, bad values refused (PARAM_VALUE with the old
   value and a STATUSTEXT), MAVLink 2 signing set up (SETUP_SIGNING): the vehicle's frames
   signed, an unsigned start and an unsigned parameter write refused, one good value set
   signed; then the power is cut (host-sim and QEMU killed). MAVProxy (headless, when
   installed; required with HIL_REQUIRED=1) then connects and fetches every parameter, with
   no FTP request left unanswered and no fence breach.
2. restart (the plant signing its upload with the key): the key, the value and the payload
   description are still there (an unsigned write is refused; the rail positions show the
   description back in the mission; `payload description restored from storage` in the
   plant's report); the ground station confirms the rails and starts the mission, a PARAM_SET
   in flight is refused, the HEARTBEAT's mission state is followed to the end, and the
   plant's report shows the phases in order and that the parameter changed the mission (the
   pre-flight checks lasted MIS_CHECKS_T); the origin is still the one set, and
   GLOBAL_POSITION_INT shows the vehicle in the air above it.

The ground station listens before the plant starts and waits for the vehicle's state (the
HEARTBEAT, the rail positions, a requested message), never for a progress text that may pass
by before it listens; a wait that fails says what it waited for, what came instead, and the
vehicle's last texts.

Exit status 0 when everything holds; 2 with one line on stderr when pymavlink is missing
(the Rust test turns that into a skip or, in CI, a failure); 1 for any failure, saying which.
"""

import argparse
import json
import lzma
import math
import os
import shutil
import threading
import socket
import struct
import subprocess
import sys
import tempfile
import time
import tomllib
import zlib

os.environ.setdefault("MAVLINK20", "1")
try:
    from pymavlink import mavutil
except ImportError:
    print("pymavlink is not installed (pip install pymavlink)", file=sys.stderr)
    sys.exit(2)

mavlink = mavutil.mavlink
CHECKS_PARAM = "MIS_CHECKS_T"
CHECKS_VALUE = 2.0
# The MAVLink 2 signing key the ground station sets up (test only).
# MAV_CMD_USER_1 with param1 = 1: the robots stand at their marks (docs/ground-link.md).
CONFIRM_RAILS = 31010
SIGNING_KEY = bytes(range(1, 33))
# The map origin the ground station sets (SET_GPS_GLOBAL_ORIGIN): 1e-7 degrees, mm.
ORIGIN = (-338688123, 1512093456, 58250)
# MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME (pymavlink 2.4.50 does not list it yet).
UNSUPPORTED_MAV_FRAME = getattr(mavlink, "MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME", 9)
# The one set with MAV_CMD_DO_SET_GLOBAL_ORIGIN (COMMAND_INT) in between.
ORIGIN_INT = (515007123, -1275456, 12250)
# The default until one is set: PX4's simulation home.
DEFAULT_ORIGIN = (473977420, 85455940, 488000)
# How long MAVProxy is watched after its parameters came, s.
MAVPROXY_WATCH_S = 8
# The ground station's socket receive buffer, bytes. Unpaced, the vehicle's telemetry comes at
# 15 to 20 times real time, and a script descheduled for a moment on a loaded machine must
# find what came meanwhile, not have the kernel drop it (the default holds about 200 KB).
RECEIVE_BUFFER = 4 * 1024 * 1024
# The vehicle's mission states, the HEARTBEAT's custom_mode low byte (link::status).
IDLE, RUNNING, COMPLETED, ABORTED = 0, 1, 2, 3
STATE_NAMES = {IDLE: "idle", RUNNING: "running", COMPLETED: "completed", ABORTED: "aborted"}
# Phases a delivered mission goes through, in order (a phase may come more than once).
FLOWN_PHASES = ("preflight-checks", "select-pair", "lift", "decide-formation", "takeoff",
                "landing", "disarmed")
# MAVLink's id of DEBUG_FLOAT_ARRAY (the robots' rail positions, named `rail`).
DEBUG_FLOAT_ARRAY_ID = 350
BAD_VALUES = [("MAX_TILT", 5.0, "outside"), ("MAX_TILT", float("nan"), "finite"),
              ("MIS_CONFIRM", 1.5, "whole")]


class Failure(Exception):
    """What did not hold."""


def describe(m):
    """A message for a failure's text: its type and fields (arrays without their trailing
    zeros)."""
    def value(v):
        if isinstance(v, list):
            while v and v[-1] == 0:
                v = v[:-1]
        return v
    fields = ", ".join(f"{k} {value(v)}" for k, v in m.to_dict().items()
                       if k != "mavpackettype")
    return f"{m.get_type()} ({fields})"


def scenario_robots(path):
    """The robots' count of a scenario file."""
    with open(path, "rb") as f:
        return tomllib.load(f)["robots"]["count"]


def free_udp_port():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Vehicle:
    """The firmware as a ground station sees it, with every STATUSTEXT kept."""

    def __init__(self, port, dialect="common", system=255):
        """Listens on local UDP `port` (0: a free one, then in `.port`)."""
        self.conn = mavutil.mavlink_connection(
            f"udpin:127.0.0.1:{port}", source_system=system, source_component=190,
            dialect=dialect)
        self.port = self.conn.port.getsockname()[1]
        # Robots of the payload the plant flies (set by `connect`).
        self.robots = 0
        try:
            self.conn.port.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RECEIVE_BUFFER)
        except OSError:
            pass  # the system's default: enough on an idle machine
        self.texts = []
        self.last_beat = 0.0
        # Message types kept whenever they come (by type, in order), whatever is awaited.
        self.keep = set()
        self.kept = {}

    def beat(self):
        """A ground station's HEARTBEAT once a second, as QGroundControl sends it: the
        vehicle refuses to start without one and, in flight, counts the link lost when they
        stop (FS_GCS_LOSS_T)."""
        now = time.monotonic()
        if now - self.last_beat >= 1.0:
            self.last_beat = now
            self.conn.mav.heartbeat_send(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID,
                                         0, 0, 0)

    def recv(self, types, timeout, condition=None):
        """The next message of one of `types` meeting `condition`, or None after `timeout`;
        every STATUSTEXT on the way is kept."""
        end = time.monotonic() + timeout
        listen = list(set(types) | {"STATUSTEXT"} | self.keep)
        while time.monotonic() < end:
            self.beat()
            m = self.conn.recv_match(type=listen, blocking=True, timeout=0.2)
            if m is None:
                continue
            if m.get_type() == "STATUSTEXT":
                self.texts.append(m.text)
            if m.get_type() in self.keep:
                self.kept.setdefault(m.get_type(), []).append(m)
            if m.get_type() in types and (condition is None or condition(m)):
                return m
        return None

    def wait_for(self, what, types, condition, timeout, ask=None, every=2.0):
        """Waits for the vehicle to show `what`: the next message of `types` meeting
        `condition`, asking for it with `ask()` first and again every `every` s when `ask` is
        given (a lost request or answer costs one retry, not the test). Fails saying what it
        waited for, the last message of `types` that came instead, and the vehicle's last
        texts."""
        end = time.monotonic() + timeout
        last = None
        while time.monotonic() < end:
            if ask is not None:
                ask()
            round_end = min(end, time.monotonic() + every) if ask is not None else end
            while time.monotonic() < round_end:
                m = self.recv(types, round_end - time.monotonic())
                if m is None:
                    break
                if condition(m):
                    return m
                last = m
        came = f"the last that came: {describe(last)}" if last is not None else \
            f"no {' or '.join(types)} came"
        raise Failure(f"waited {timeout} s for {what}; {came}; the vehicle's last texts: "
                      f"{self.texts[-5:]}")

    def request(self, message_id):
        """Asks for one message (MAV_CMD_REQUEST_MESSAGE), not waiting for the answer."""
        self.conn.mav.command_long_send(1, 1, mavlink.MAV_CMD_REQUEST_MESSAGE, 0, message_id,
                                        0, 0, 0, 0, 0, 0)

    def mission_state(self, states, what, timeout=60):
        """Waits until the vehicle's HEARTBEAT says its mission is in one of `states` (the
        custom_mode's low byte); returns that HEARTBEAT."""
        return self.wait_for(
            f"the mission {what} (HEARTBEAT state {' or '.join(STATE_NAMES[s] for s in states)})",
            ["HEARTBEAT"],
            lambda m: m.get_srcComponent() == 1 and m.custom_mode & 0xFF in states, timeout)

    def payload_loaded(self, unconfirmed=False, timeout=60):
        """Waits until the vehicle's mission holds a payload description of `self.robots`
        robots: its `rail` DEBUG_FLOAT_ARRAY, asked for, has an entry for each (with no
        description it has none: all zero); with `unconfirmed`, a not-a-number for each (the
        rail positions not confirmed since the vehicle started). What a ground station waits
        for after a restart before it confirms the rails: the description restored and handed
        to the mission, not only accepted."""
        robots = self.robots
        if unconfirmed:
            what = "not a number for each robot: the rails unconfirmed"
            shown = lambda data: all(math.isnan(x) for x in data)  # noqa: E731
        else:
            what = "an entry for each robot"
            shown = lambda data: any(x != 0.0 for x in data)  # noqa: E731 (NaN too)
        return self.wait_for(
            f"the payload description of {robots} robots in the mission (DEBUG_FLOAT_ARRAY "
            f"rail: {what})",
            ["DEBUG_FLOAT_ARRAY"], lambda m: m.name == "rail" and shown(m.data[:robots]),
            timeout, ask=lambda: self.request(DEBUG_FLOAT_ARRAY_ID))

    def has_text(self, needle):
        # Long texts come in 50-byte chunks: look across them too.
        return any(needle in t for t in self.texts) or needle in "".join(self.texts)

    def expect(self, types, timeout, what, condition=None):
        m = self.recv(types, timeout, condition)
        if m is None:
            raise Failure(f"no {what} within {timeout} s")
        return m

    def text_matching(self, needle, timeout):
        """Waits for a STATUSTEXT containing `needle` (or finds one already received)."""
        if self.has_text(needle):
            return
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            self.recv(["STATUSTEXT"], 0.5)
            if self.has_text(needle):
                return
        params = [t for t in self.texts if t.startswith("param") or "sign" in t]
        raise Failure(f"no STATUSTEXT containing {needle!r} within {timeout} s "
                      f"(last: {self.texts[-5:]}; about parameters and signing: {params[-5:]})")

    def command(self, cmd, *params):
        p = list(params) + [0.0] * (7 - len(params))
        self.conn.mav.command_long_send(1, 1, cmd, 0, *p)
        return self.expect(["COMMAND_ACK"], 10, f"COMMAND_ACK of command {cmd}",
                           lambda m: m.command == cmd)

    def command_int(self, cmd, frame=mavlink.MAV_FRAME_GLOBAL, params=(), x=0, y=0, z=0.0):
        """A COMMAND_INT (as MAVSDK sends position commands) and its COMMAND_ACK."""
        p = list(params) + [0.0] * (4 - len(params))
        self.conn.mav.command_int_send(1, 1, frame, cmd, 0, 0, *p, x, y, z)
        return self.expect(["COMMAND_ACK"], 10, f"COMMAND_ACK of COMMAND_INT {cmd}",
                           lambda m: m.command == cmd)

    def param_set(self, name, value):
        self.conn.mav.param_set_send(1, 1, name.encode(), value,
                                     mavlink.MAV_PARAM_TYPE_REAL32)
        return self.expect(["PARAM_VALUE"], 10, f"PARAM_VALUE answering PARAM_SET {name}",
                           lambda m: m.param_id == name)

    def param_read(self, name=None, index=-1):
        self.conn.mav.param_request_read_send(1, 1, (name or "").encode(), index)
        return self.expect(["PARAM_VALUE"], 10, f"PARAM_VALUE of {name or index}",
                           lambda m: (name is None and m.param_index == index)
                           or (name is not None and m.param_id == name))

    def all_params(self):
        self.conn.mav.param_request_list_send(1, 1)
        values, count = {}, None
        end = time.monotonic() + 30
        while time.monotonic() < end and (count is None or len(values) < count):
            m = self.recv(["PARAM_VALUE"], 1)
            if m is None:
                continue
            if count is None:
                count = m.param_count
            if m.param_count != count:
                raise Failure(f"param_count changed from {count} to {m.param_count}")
            if not 0 <= m.param_index < count:
                raise Failure(f"param_index {m.param_index} outside 0..{count}")
            values[m.param_index] = (m.param_id, m.param_value, m.param_type)
        if count is None or len(values) != count:
            raise Failure(f"PARAM_REQUEST_LIST: {len(values)} of {count} parameters came")
        names = [values[i][0] for i in range(count)]
        if len(set(names)) != count:
            raise Failure("two parameters share a name")
        if any(v[2] != mavlink.MAV_PARAM_TYPE_REAL32 for v in values.values()):
            raise Failure("a parameter is not MAV_PARAM_TYPE_REAL32")
        return {values[i][0]: (i, values[i][1]) for i in range(count)}


def telemetry_checks(v):
    """The streams, and their rates set as MAVLink's message interval protocol has it."""
    status = v.expect(["SYS_STATUS"], 10, "SYS_STATUS")
    imu = mavlink.MAV_SYS_STATUS_SENSOR_3D_GYRO | mavlink.MAV_SYS_STATUS_SENSOR_3D_ACCEL
    if status.onboard_control_sensors_present & imu != imu:
        raise Failure(f"SYS_STATUS sensors present {status.onboard_control_sensors_present:#x}")
    if status.onboard_control_sensors_health & imu != imu:
        raise Failure(f"SYS_STATUS: the IMU is not healthy "
                      f"({status.onboard_control_sensors_health:#x})")
    q = v.expect(["ATTITUDE_QUATERNION"], 10, "ATTITUDE_QUATERNION")
    norm = (q.q1 ** 2 + q.q2 ** 2 + q.q3 ** 2 + q.q4 ** 2) ** 0.5
    if abs(norm - 1.0) > 1e-3:
        raise Failure(f"ATTITUDE_QUATERNION of norm {norm}")
    v.expect(["LOCAL_POSITION_NED"], 10, "LOCAL_POSITION_NED")
    v.expect(["DEBUG_FLOAT_ARRAY"], 10, "DEBUG_FLOAT_ARRAY rail (the robots' rail positions)",
             lambda m: m.name == "rail" and m.array_id == 1)
    print("telemetry: SYS_STATUS (IMU present and healthy), ATTITUDE_QUATERNION (unit), "
          "LOCAL_POSITION_NED, DEBUG_FLOAT_ARRAY rail")

    attitude = mavlink.MAVLINK_MSG_ID_ATTITUDE_QUATERNION
    ack = v.command(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, attitude, -1)
    if ack.result != mavlink.MAV_RESULT_ACCEPTED:
        raise Failure(f"SET_MESSAGE_INTERVAL(ATTITUDE_QUATERNION, off) acknowledged {ack.result}")
    # What was already on its way may still come; after that, nothing for 3 s.
    v.recv(["NONE"], 1.0)
    if v.recv(["ATTITUDE_QUATERNION"], 3.0) is not None:
        raise Failure("ATTITUDE_QUATERNION still streamed after its interval was set to -1")
    if v.recv(["LOCAL_POSITION_NED"], 3.0) is None:
        raise Failure("LOCAL_POSITION_NED stopped with ATTITUDE_QUATERNION")
    ack = v.command(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, attitude, 20000)
    if ack.result != mavlink.MAV_RESULT_ACCEPTED:
        raise Failure(f"SET_MESSAGE_INTERVAL(ATTITUDE_QUATERNION, 20 ms) acknowledged {ack.result}")
    v.expect(["ATTITUDE_QUATERNION"], 10, "ATTITUDE_QUATERNION after its interval was set")
    ack = v.command(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, attitude, 10)
    if ack.result != mavlink.MAV_RESULT_DENIED:
        raise Failure(f"a 10 us interval acknowledged {ack.result}, expected DENIED")
    v.text_matching("interval must be", 10)
    ack = v.command(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, mavlink.MAVLINK_MSG_ID_GPS_RAW_INT, 0)
    if ack.result != mavlink.MAV_RESULT_UNSUPPORTED:
        raise Failure(f"an unstreamed message's interval acknowledged {ack.result}")
    ack = v.command(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, mavlink.MAVLINK_MSG_ID_SYS_STATUS, -1)
    if ack.result != mavlink.MAV_RESULT_ACCEPTED:
        raise Failure(f"SET_MESSAGE_INTERVAL(SYS_STATUS, off) acknowledged {ack.result}")
    v.recv(["NONE"], 1.5)
    ack = v.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_SYS_STATUS)
    if ack.result != mavlink.MAV_RESULT_ACCEPTED:
        raise Failure(f"REQUEST_MESSAGE(SYS_STATUS) acknowledged {ack.result}")
    v.expect(["SYS_STATUS"], 10, "SYS_STATUS on request")
    v.command(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, mavlink.MAVLINK_MSG_ID_SYS_STATUS, 0)
    print("SET_MESSAGE_INTERVAL: off, 20 ms, a bad interval DENIED, an unstreamed message "
          "UNSUPPORTED; REQUEST_MESSAGE(SYS_STATUS) sent once")


def to_global(origin, north, east):
    """Latitude and longitude (1e-7 degrees) of a local point near the origin, as the vehicle
    converts it (WGS-84 radii at the origin; the second-order terms are nothing at metres)."""
    a, e2 = 6378137.0, 6.69437999014e-3
    lat0 = math.radians(origin[0] * 1e-7)
    w = 1 - e2 * math.sin(lat0) ** 2
    up = origin[2] * 1e-3
    m, n = a * (1 - e2) / w ** 1.5 + up, a / math.sqrt(w) + up
    lat = origin[0] + math.degrees(north / m) * 1e7
    lon = origin[1] + math.degrees(east / (n * math.cos(lat0))) * 1e7
    return lat, lon


def command_int_origin_checks(v):
    """MAV_CMD_DO_SET_GLOBAL_ORIGIN as COMMAND_INT (x, y 1e-7 degrees, z m): another origin set
    and read back, a frame with a relative altitude and a latitude beyond 85 degrees refused
    (the origin unchanged), a command the vehicle does not do UNSUPPORTED as COMMAND_LONG is;
    then ORIGIN again, as the rest of the test expects it."""
    cmd = mavlink.MAV_CMD_DO_SET_GLOBAL_ORIGIN
    ack = v.command_int(cmd, x=ORIGIN_INT[0], y=ORIGIN_INT[1], z=ORIGIN_INT[2] * 1e-3)
    if ack.result != mavlink.MAV_RESULT_ACCEPTED:
        raise Failure(f"DO_SET_GLOBAL_ORIGIN acknowledged {ack.result}")
    o = v.expect(["GPS_GLOBAL_ORIGIN"], 10, "GPS_GLOBAL_ORIGIN after DO_SET_GLOBAL_ORIGIN",
                 lambda m: m.latitude == ORIGIN_INT[0])
    if (o.latitude, o.longitude, o.altitude) != ORIGIN_INT:
        raise Failure(f"origin set to {ORIGIN_INT} by COMMAND_INT, GPS_GLOBAL_ORIGIN says "
                      f"{(o.latitude, o.longitude, o.altitude)}")
    ack = v.command_int(cmd, frame=mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT, x=ORIGIN[0],
                        y=ORIGIN[1], z=1.0)
    if ack.result != UNSUPPORTED_MAV_FRAME:
        raise Failure(f"DO_SET_GLOBAL_ORIGIN with a relative altitude acknowledged {ack.result}")
    ack = v.command_int(cmd, x=860000000, y=ORIGIN[1], z=1.0)
    if ack.result != mavlink.MAV_RESULT_DENIED:
        raise Failure(f"DO_SET_GLOBAL_ORIGIN at 86 degrees acknowledged {ack.result}")
    v.text_matching("latitude beyond 85", 10)
    ack = v.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN)
    o = v.expect(["GPS_GLOBAL_ORIGIN"], 10, "GPS_GLOBAL_ORIGIN on request")
    if o.latitude != ORIGIN_INT[0]:
        raise Failure(f"a refused DO_SET_GLOBAL_ORIGIN moved the origin to {o.latitude}")
    ack = v.command_int(mavlink.MAV_CMD_NAV_TAKEOFF, x=ORIGIN[0], y=ORIGIN[1], z=1.0)
    if ack.result != mavlink.MAV_RESULT_UNSUPPORTED:
        raise Failure(f"NAV_TAKEOFF as COMMAND_INT acknowledged {ack.result}")
    ack = v.command_int(cmd, x=ORIGIN[0], y=ORIGIN[1], z=ORIGIN[2] * 1e-3)
    o = v.expect(["GPS_GLOBAL_ORIGIN"], 10, "GPS_GLOBAL_ORIGIN after DO_SET_GLOBAL_ORIGIN",
                 lambda m: m.latitude == ORIGIN[0])
    if ack.result != mavlink.MAV_RESULT_ACCEPTED or (o.longitude, o.altitude) != ORIGIN[1:]:
        raise Failure(f"origin set back by COMMAND_INT: {o} (ack {ack.result})")
    print("COMMAND_INT: DO_SET_GLOBAL_ORIGIN set and read back, a relative altitude and 86 "
          "degrees refused, NAV_TAKEOFF UNSUPPORTED")


def map_checks(v):
    """The vehicle on a map: the origin (GPS_GLOBAL_ORIGIN) by default and set with
    SET_GPS_GLOBAL_ORIGIN (its ORIG_* parameters answered), HOME_POSITION on request (the
    origin before any flight; MAVProxy's MAV_CMD_GET_HOME_POSITION too), GLOBAL_POSITION_INT
    streamed: the local position through the origin."""
    ack = v.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN)
    if ack.result != mavlink.MAV_RESULT_ACCEPTED:
        raise Failure(f"REQUEST_MESSAGE(GPS_GLOBAL_ORIGIN) acknowledged {ack.result}")
    o = v.expect(["GPS_GLOBAL_ORIGIN"], 10, "GPS_GLOBAL_ORIGIN")
    if (o.latitude, o.longitude, o.altitude) != DEFAULT_ORIGIN:
        raise Failure(f"default origin {(o.latitude, o.longitude, o.altitude)}")
    v.conn.mav.set_gps_global_origin_send(1, *ORIGIN)
    o = v.expect(["GPS_GLOBAL_ORIGIN"], 10, "GPS_GLOBAL_ORIGIN after SET_GPS_GLOBAL_ORIGIN",
                 lambda m: m.latitude == ORIGIN[0])
    if (o.latitude, o.longitude, o.altitude) != ORIGIN:
        raise Failure(f"origin set to {ORIGIN}, GPS_GLOBAL_ORIGIN says "
                      f"{(o.latitude, o.longitude, o.altitude)}")
    lat_deg = v.param_read(name="ORIG_LAT_DEG").param_value
    lat_e7 = v.param_read(name="ORIG_LAT_E7").param_value
    if (lat_deg, lat_e7) != (-33.0, -8688123.0):
        raise Failure(f"ORIG_LAT_DEG, ORIG_LAT_E7 read {lat_deg}, {lat_e7}")
    ack = v.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN)
    o = v.expect(["GPS_GLOBAL_ORIGIN"], 10, "GPS_GLOBAL_ORIGIN on request")
    if ack.result != mavlink.MAV_RESULT_ACCEPTED or o.latitude != ORIGIN[0]:
        raise Failure(f"GPS_GLOBAL_ORIGIN read back {o.latitude} (ack {ack.result})")
    for cmd, params in [(mavlink.MAV_CMD_REQUEST_MESSAGE, [mavlink.MAVLINK_MSG_ID_HOME_POSITION]),
                        (mavlink.MAV_CMD_GET_HOME_POSITION, [])]:
        ack = v.command(cmd, *params)
        if ack.result != mavlink.MAV_RESULT_ACCEPTED:
            raise Failure(f"command {cmd} (HOME_POSITION) acknowledged {ack.result}")
        home = v.expect(["HOME_POSITION"], 10, f"HOME_POSITION after command {cmd}")
        if (home.latitude, home.longitude, home.altitude) != ORIGIN or home.x != 0:
            raise Failure(f"HOME_POSITION before a flight {home}, not the origin")
    if v.has_text("refused: not supported"):
        raise Failure(f"a request refused: {v.texts[-5:]}")
    command_int_origin_checks(v)
    # Both streams read the last control step's state; on the ground at rest it barely
    # moves, so a LOCAL_POSITION_NED within 150 ms is the same place to a centimetre.
    local = []
    end = time.monotonic() + 10
    while time.monotonic() < end:
        m = v.recv(["LOCAL_POSITION_NED", "GLOBAL_POSITION_INT"], 1)
        if m is None:
            continue
        if m.get_type() == "LOCAL_POSITION_NED":
            local.append(m)
            continue
        near = [p for p in local if abs(p.time_boot_ms - m.time_boot_ms) <= 150]
        if not near:
            continue
        p = min(near, key=lambda p: abs(p.time_boot_ms - m.time_boot_ms))
        lat, lon = to_global(ORIGIN, p.x, p.y)
        if abs(m.lat - lat) > 3 or abs(m.lon - lon) > 3:
            raise Failure(f"GLOBAL_POSITION_INT at {m.lat}, {m.lon} for the local "
                          f"{p.x:.3f}, {p.y:.3f}: expected {lat:.0f}, {lon:.0f}")
        if abs(m.relative_alt + p.z * 1000) > 10 or abs(m.alt - (ORIGIN[2] - p.z * 1000)) > 10:
            raise Failure(f"GLOBAL_POSITION_INT altitudes {m.alt}, {m.relative_alt} "
                          f"for z = {p.z}")
        print(f"map: origin set and read back, HOME_POSITION the origin, GLOBAL_POSITION_INT "
              f"{m.lat}, {m.lon} for the local {p.x:.3f}, {p.y:.3f} "
              f"({m.time_boot_ms - p.time_boot_ms} ms apart)")
        return
    raise Failure("no GLOBAL_POSITION_INT with a LOCAL_POSITION_NED within 150 ms")


def timesync_checks(v):
    """TIMESYNC both ways: the vehicle answers a request with its time and the request's,
    and asks once a second itself (answered here as a motion-capture computer would)."""
    v.conn.mav.timesync_send(0, 123456789)
    answer = v.expect(["TIMESYNC"], 10, "TIMESYNC answer",
                      lambda m: m.tc1 != 0 and m.ts1 == 123456789)
    request = v.expect(["TIMESYNC"], 10, "TIMESYNC request from the vehicle",
                       lambda m: m.tc1 == 0 and m.ts1 > 0)
    v.conn.mav.timesync_send(time.monotonic_ns(), request.ts1)
    print(f"TIMESYNC: answered (vehicle time {answer.tc1} ns); the vehicle asks too")


def signing_timestamp():
    """Now in MAVLink signing's units: 10 us since 2015-01-01."""
    return int((time.time() - 1420070400) * 100000)


def signing_checks(v):
    """SETUP_SIGNING, then: the vehicle signs, refuses unsigned commands and writes."""
    v.conn.mav.setup_signing_send(1, 1, list(SIGNING_KEY), signing_timestamp())
    v.text_matching("signing: on", 10)
    v.conn.setup_signing(SIGNING_KEY, sign_outgoing=False)
    hb = v.expect(["HEARTBEAT"], 10, "a signed HEARTBEAT",
                  lambda m: m.get_srcComponent() == 1 and m.get_signed())
    ack = v.command(mavlink.MAV_CMD_MISSION_START)
    if ack.result != mavlink.MAV_RESULT_DENIED:
        raise Failure(f"an unsigned MISSION_START acknowledged {ack.result}, expected DENIED")
    v.text_matching("not signed", 10)
    old = v.param_read(name=CHECKS_PARAM).param_value
    if v.param_set(CHECKS_PARAM, CHECKS_VALUE).param_value != old:
        raise Failure(f"an unsigned PARAM_SET of {CHECKS_PARAM} was taken")
    v.conn.mav.signing.sign_outgoing = True
    print(f"signing on: the vehicle signs (HEARTBEAT seq {hb.get_seq()}); an unsigned start "
          "and parameter write refused")


def mavproxy_check(args, parameters):
    """MAVProxy, headless, connects to the vehicle and fetches every parameter by itself
    (it reads no commands from stdin when --non-interactive, so this is what it is asked)."""
    mavproxy = shutil.which("mavproxy.py")
    if mavproxy is None:
        if os.environ.get("HIL_REQUIRED") == "1":
            raise Failure("MAVProxy is not installed (pip install MAVProxy) and HIL_REQUIRED=1")
        print("MAVProxy is not installed (pip install MAVProxy): its check skipped")
        return
    plant = start_hil(args, ["--signing-key", SIGNING_KEY.hex()], listen=False)
    want = f"Received {parameters} parameters"
    seen = []
    with tempfile.TemporaryDirectory(prefix="mavproxy-") as logs:
        proxy = subprocess.Popen(
            [mavproxy, f"--master=udpin:127.0.0.1:{plant.port}", "--source-system=255",
             "--non-interactive", f"--state-basedir={logs}"],
            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
            text=True)
        stop = threading.Timer(60, proxy.kill)
        stop.start()
        try:
            for line in proxy.stdout:
                seen.append(line.rstrip())
                if want in line:
                    break
            # Then a while as a user would leave it open: MAVProxy asks for the home position
            # every few seconds, and a refusal repeated each time would fill its console.
            quiet_until = time.monotonic() + MAVPROXY_WATCH_S
            stop.cancel()
            stop = threading.Timer(MAVPROXY_WATCH_S + 5, proxy.kill)
            stop.start()
            for line in proxy.stdout:
                seen.append(line.rstrip())
                if time.monotonic() > quiet_until:
                    break
        finally:
            stop.cancel()
            proxy.kill()
            proxy.communicate()
            plant.kill()
            plant.communicate()
    if not any("Detected vehicle 1:1" in line for line in seen):
        raise Failure(f"MAVProxy did not see the vehicle: {seen[-5:]}")
    if not any(want in line for line in seen):
        raise Failure(f"MAVProxy did not fetch the {parameters} parameters: {seen[-5:]}")
    # Every request answered at connect: its FTP read of PX4's parameter file (a NAK, under
    # the session MAVProxy named: it routes answers by it), and the geofence's SYS_STATUS bits.
    for bad in ("FTP: request timed out", "fence breach"):
        if any(bad in line for line in seen):
            raise Failure(f"MAVProxy said {bad!r}: {[line for line in seen if bad in line][:2]}")
    refusals = [line for line in seen if "refused" in line or "denied" in line.lower()]
    repeated = {line for line in refusals if refusals.count(line) > 1}
    if repeated:
        raise Failure(f"MAVProxy's console repeats refusals: {sorted(repeated)[:3]}")
    print(f"MAVProxy (headless): vehicle 1:1 detected, {parameters} parameters fetched, "
          f"no refusal repeated over {MAVPROXY_WATCH_S} s, no FTP time-out, no fence breach")


def start_hil(args, extra, dialect="common", listen=True):
    """`host-sim hil --gcs` on rect-ex1 with a ground station on a free local port. With
    `listen` this script's ground station is bound there before the plant starts, so nothing
    the vehicle says first is lost (MAVSDK and MAVProxy bind their own). Returns the plant
    with `.port` and `.ground` (the listening Vehicle, or None)."""
    ground = Vehicle(0, dialect) if listen else None
    port = ground.port if ground else free_udp_port()
    cmd = [args.host_sim, "hil", "--scenario", args.scenario, "--qemu", args.elf,
           "--storage", args.storage, "--gcs", f"udp:127.0.0.1:{port}", "--ground-start",
           "--json"] + list(extra)
    plant = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    plant.port, plant.ground = port, ground
    plant.robots = scenario_robots(args.scenario)
    return plant


def delivered(plant):
    """The plant's report once its mission ended (`--json`), checked delivered: the
    distance from the target, m."""
    out, err = plant.communicate(timeout=300)
    try:
        report = json.loads(out)
    except json.JSONDecodeError:
        raise Failure(f"host-sim printed no JSON (exit {plant.returncode}): {err[-500:]}")
    if not report["delivered"]:
        raise Failure(f"not delivered: landed {report['final_position_error_m']:.2f} m away")
    return report["final_position_error_m"]


def run_against_plant(name, description, checks, extra=(), failures=(Failure,),
                      dialect="common", listen=True):
    """A check script's main: its arguments (--host-sim, --elf, --scenario), a plant on fresh
    storage with `extra` arguments ([`start_hil`]), `checks(plant)`, and one line saying
    whether all held (exit 0) or what failed (exit 1; `failures` are the exceptions that say
    so)."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--host-sim", required=True)
    parser.add_argument("--elf", required=True)
    parser.add_argument("--scenario", required=True)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix=f"{name.replace(' ', '-')}-") as tmp:
        args.storage = tmp
        started = time.monotonic()
        plant = start_hil(args, extra, dialect, listen)
        try:
            checks(plant)
        except failures as e:
            print(f"{name}: FAILED: {e}", file=sys.stderr)
            return 1
        finally:
            if plant.poll() is None:
                plant.kill()
                plant.communicate()
        print(f"{name}: all checks held in {time.monotonic() - started:.0f} s")
    return 0


def connect(plant):
    """The plant's listening ground station once the vehicle's HEARTBEAT came, aimed at it."""
    v = plant.ground
    v.robots = plant.robots
    hb = v.recv(["HEARTBEAT"], 60, lambda m: m.get_srcComponent() == 1)
    if hb is None:
        plant.kill()
        out, err = plant.communicate()
        raise Failure(f"no HEARTBEAT from the vehicle; host-sim said: {err.strip()[-500:]}")
    if hb.get_srcSystem() == 0 or hb.autopilot != mavlink.MAV_AUTOPILOT_GENERIC:
        raise Failure(f"HEARTBEAT from system {hb.get_srcSystem()} autopilot {hb.autopilot}")
    v.conn.target_system, v.conn.target_component = 1, 1
    return v


def ftp_read(v, path):
    """A file read whole over MAVLink FTP (OpenFileRO, ReadFile, TerminateSession), as
    QGroundControl reads the component metadata: its bytes."""
    seq = [0]

    def ask(opcode, session=0, offset=0, size=0, data=b""):
        seq[0] += 1
        payload = data.ljust(239, b"\0")
        header = struct.pack("<HBBBBBBI", seq[0], session, opcode, size or len(data), 0, 0, 0,
                             offset)
        v.conn.mav.file_transfer_protocol_send(0, 1, 1, list(header + payload))
        m = v.expect(["FILE_TRANSFER_PROTOCOL"], 10, f"an FTP answer about {path}")
        raw = bytes(m.payload)
        _, got_session, op, n, req, _, _, _ = struct.unpack("<HBBBBBBI", raw[:12])
        return op, got_session, raw[12:12 + n]

    op, session, data = ask(4, data=path.encode())  # OpenFileRO
    if op != 128:
        raise Failure(f"FTP OpenFileRO {path}: NAK {data!r}")
    size = struct.unpack("<I", data[:4])[0]
    out = bytearray()
    while len(out) < size:
        op, _, data = ask(5, session=session, offset=len(out), size=239)  # ReadFile
        if op != 128 or not data:
            raise Failure(f"FTP ReadFile {path} at {len(out)}: NAK {data!r}")
        out += data
    ask(1, session=session)  # TerminateSession
    return bytes(out)


def metadata_checks(v, param_count):
    """QGroundControl's parameter metadata over FTP: the general file names the parameter
    file with its CRC-32, and the parameter file lists every parameter."""
    general = json.loads(ftp_read(v, "/comp_general.json"))
    entry = next(m for m in general["metadataTypes"] if m["type"] == 1)
    uri = entry["uri"]
    served = ftp_read(v, uri.replace("mftp://", ""))
    # The CRC is of the file as served; a name ending in .xz is decompressed, as
    # QGroundControl does.
    if zlib.crc32(served) != entry["fileCrc"]:
        raise Failure(f"{uri}: CRC-32 {zlib.crc32(served)} against the general file's "
                      f"{entry['fileCrc']}")
    if not uri.endswith(".json.xz"):
        raise Failure(f"{uri}: the parameter file is served xz-compressed")
    try:
        body = lzma.decompress(served, format=lzma.FORMAT_XZ)
    except lzma.LZMAError as e:
        raise Failure(f"{uri}: not an xz file ({e})")
    names = [p["name"] for p in json.loads(body)["parameters"]]
    if len(names) != param_count:
        raise Failure(f"{uri} lists {len(names)} parameters; the vehicle has {param_count}")
    print(f"parameter metadata over FTP: {uri}, {len(served)} bytes ({len(body)} decompressed), "
          f"its CRC-32 as the general file says, {len(names)} parameters")


def first_run(args):
    plant = start_hil(args, [])
    try:
        v = connect(plant)
        print("connected: HEARTBEAT from 1/1, MAV_AUTOPILOT_GENERIC")
        ack = v.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION)
        if ack.result != mavlink.MAV_RESULT_ACCEPTED:
            raise Failure(f"REQUEST_MESSAGE(AUTOPILOT_VERSION) acknowledged {ack.result}")
        version = v.expect(["AUTOPILOT_VERSION"], 10, "AUTOPILOT_VERSION")
        need = (mavlink.MAV_PROTOCOL_CAPABILITY_MAVLINK2
                | mavlink.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
                | mavlink.MAV_PROTOCOL_CAPABILITY_FTP
                | mavlink.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE
                | mavlink.MAV_PROTOCOL_CAPABILITY_MISSION_INT)
        # Not the other parameter encoding (one of the two).
        never = (mavlink.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_C_CAST
                 | mavlink.MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT)
        if version.capabilities & need != need or version.capabilities & never:
            raise Failure(f"AUTOPILOT_VERSION capabilities {version.capabilities:#x}")
        # The same request as COMMAND_INT, as MAVSDK may send it.
        ack = v.command_int(mavlink.MAV_CMD_REQUEST_MESSAGE,
                            params=[mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION])
        if ack.result != mavlink.MAV_RESULT_ACCEPTED:
            raise Failure(f"REQUEST_MESSAGE(AUTOPILOT_VERSION) as COMMAND_INT: {ack.result}")
        v.expect(["AUTOPILOT_VERSION"], 10, "AUTOPILOT_VERSION asked by COMMAND_INT")
        v.conn.mav.mission_request_list_send(1, 1)
        count = v.expect(["MISSION_COUNT"], 10, "MISSION_COUNT")
        if count.count != 0:
            raise Failure(f"MISSION_COUNT {count.count}, expected 0")
        print("AUTOPILOT_VERSION and MISSION_COUNT 0 as QGroundControl expects")
        telemetry_checks(v)
        map_checks(v)
        timesync_checks(v)

        params = v.all_params()
        print(f"{len(params)} parameters, indices 0..{len(params) - 1}")
        metadata_checks(v, len(params))
        for name in [CHECKS_PARAM, "MAX_TILT", "LIFT_SIGMA"]:
            if name not in params:
                raise Failure(f"parameter {name} missing")
            i, value = params[name]
            by_name, by_index = v.param_read(name=name), v.param_read(index=i)
            if (by_name.param_index, by_index.param_id) != (i, name):
                raise Failure(f"{name}: read by name gave index {by_name.param_index}, "
                              f"by index {i} gave {by_index.param_id}")
        old_tilt = params["MAX_TILT"][1]

        ack = v.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1.0)
        if ack.result != mavlink.MAV_RESULT_DENIED:
            raise Failure(f"arming acknowledged {ack.result}, expected DENIED")
        v.text_matching("refused", 10)
        print("arming refused: COMMAND_ACK DENIED with a STATUSTEXT")

        for name, bad, why in BAD_VALUES:
            answer = v.param_set(name, bad)
            if answer.param_value != params[name][1]:
                raise Failure(f"{name} = {bad} taken ({answer.param_value})")
            v.text_matching(why, 10)
        print("bad values refused: PARAM_VALUE with the old value and a STATUSTEXT each")
        if v.param_read(name="MAX_TILT").param_value != old_tilt:
            raise Failure("MAX_TILT changed by a refused value")

        signing_checks(v)
        answer = v.param_set(CHECKS_PARAM, CHECKS_VALUE)
        if answer.param_value != CHECKS_VALUE:
            raise Failure(f"{CHECKS_PARAM} = {CHECKS_VALUE} answered {answer.param_value}")
        print(f"{CHECKS_PARAM} set to {CHECKS_VALUE}; cutting the power")
        return len(params)
    finally:
        # The power cut: host-sim and, with it, QEMU die at once.
        plant.kill()
        plant.communicate()
        plant.ground.conn.close()


def second_run(args):
    plant = start_hil(args, ["--signing-key", SIGNING_KEY.hex()])
    try:
        v = connect(plant)
        v.conn.setup_signing(SIGNING_KEY, sign_outgoing=False)
        if v.param_set("MAX_TILT", 0.3).param_value == 0.3:
            raise Failure("after the restart an unsigned PARAM_SET was taken: signing lost")
        v.conn.mav.signing.sign_outgoing = True
        print("after the restart signing is on: an unsigned PARAM_SET refused")
        value = v.param_read(name=CHECKS_PARAM).param_value
        if value != CHECKS_VALUE:
            raise Failure(f"after the restart {CHECKS_PARAM} reads {value}, set {CHECKS_VALUE}")
        if len(v.all_params()) == 0:
            raise Failure("no parameters after the restart")
        print(f"after the restart {CHECKS_PARAM} = {value}")
        v.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN)
        o = v.expect(["GPS_GLOBAL_ORIGIN"], 10, "GPS_GLOBAL_ORIGIN after the restart")
        if (o.latitude, o.longitude, o.altitude) != ORIGIN:
            raise Failure(f"after the restart the origin is {(o.latitude, o.longitude)}")
        print("after the restart the map origin is the one set")
        # A restart forgets where the robots stand: the operator confirms the rails again (the
        # plant confirms them too, as its set-up, but a ground station may be quicker). The
        # description is restored, checked, loaded into the planner and only then handed to
        # the mission, so the ground station waits until the vehicle shows it (a rail
        # position for each robot), not for a text that may come before it listens.
        v.payload_loaded()
        confirm = v.command(CONFIRM_RAILS, 1)
        if confirm.result != mavlink.MAV_RESULT_ACCEPTED:
            raise Failure(f"the rails' confirmation acknowledged {confirm.result} "
                          f"(last texts: {v.texts[-3:]})")
        # A start while the vehicle loads the description into its planner is
        # TEMPORARILY_REJECTED (with a STATUSTEXT): the command protocol's answer to try again,
        # which a ground station does.
        deadline = time.time() + 20
        while True:
            ack = v.command(mavlink.MAV_CMD_MISSION_START)
            if ack.result != mavlink.MAV_RESULT_TEMPORARILY_REJECTED or time.time() > deadline:
                break
            time.sleep(0.2)  # the retry's pace, as a ground station's
        if ack.result != mavlink.MAV_RESULT_ACCEPTED:
            raise Failure(f"MISSION_START acknowledged {ack.result} (last texts: {v.texts[-3:]})")
        v.mission_state([RUNNING], "started", 20)
        answer = v.param_set("MAX_TILT", 0.3)
        if answer.param_value == 0.3:
            raise Failure("MAX_TILT changed while the mission runs")
        v.text_matching("running", 10)
        print("mission started; a PARAM_SET in flight refused")
        # In the air, on the map: above the origin, within metres of it.
        up = v.wait_for("GLOBAL_POSITION_INT in the air (over 0.3 m above the origin)",
                        ["GLOBAL_POSITION_INT"], lambda m: m.relative_alt > 300, 900)
        if abs(up.lat - ORIGIN[0]) > 1000 or abs(up.lon - ORIGIN[1]) > 1000:
            raise Failure(f"in the air at {up.lat}, {up.lon}: not near the origin")
        print(f"  GLOBAL_POSITION_INT in the air: {up.relative_alt} mm above the origin")
        v.mission_state([COMPLETED, ABORTED], "over", 900)
        out, err = plant.communicate(timeout=120)
        try:
            report = json.loads(out)
        except json.JSONDecodeError:
            raise Failure(f"host-sim printed no JSON (exit {plant.returncode}): {err[-500:]}")
        if not any("restored from storage" in t["text"] for t in report["statustexts"]):
            raise Failure("the payload description was not restored from storage at the restart")
        # The phases as the plant logged them from the vehicle's texts over the lockstep link,
        # where none is lost.
        names = [p["name"] for p in report["phases"]]
        order = [names.index(n) if n in names else -1 for n in FLOWN_PHASES]
        if -1 in order or order != sorted(order):
            raise Failure(f"the mission's phases {names}: not {', '.join(FLOWN_PHASES)} in order")
        print(f"  phases in order: {', '.join(FLOWN_PHASES)}")
        checks = [p for p in report["phases"] if p["name"] == "preflight-checks"]
        if not checks or abs(checks[0]["duration_s"] - CHECKS_VALUE) > 0.1:
            raise Failure(f"pre-flight checks lasted {checks}, {CHECKS_PARAM} = {CHECKS_VALUE}")
        print(f"pre-flight checks lasted {checks[0]['duration_s']:.2f} s ({CHECKS_PARAM}); "
              f"delivered: {report['delivered']}, host-sim exit {plant.returncode}")
        if plant.returncode != 0 or not report["delivered"]:
            raise Failure(f"mission not delivered (exit {plant.returncode})")
    finally:
        if plant.poll() is None:
            plant.kill()
            plant.communicate()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host-sim", required=True)
    parser.add_argument("--elf", required=True)
    parser.add_argument("--scenario", required=True)
    parser.add_argument("--storage", help="parameter flash directory (default: a fresh one)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="ground-station-") as tmp:
        args.storage = args.storage or tmp
        started = time.monotonic()
        try:
            parameters = first_run(args)
            mavproxy_check(args, parameters)
            second_run(args)
        except Failure as e:
            print(f"ground station: FAILED: {e}", file=sys.stderr)
            return 1
        print(f"ground station: all checks held in {time.monotonic() - started:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
