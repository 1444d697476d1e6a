#!/usr/bin/env python3
"""Flies the paper's case with MAVSDK-Python: the payload carried from where it rests to the
target 0.3 m north and 1.98 m east of the motion-capture origin at 0.5 m, with a hold on the
way (docs/ground-link.md#scripting-with-mavsdk).

    pip install mavsdk==3.17.4      # the gRPC API with mavsdk_server in the wheel
    python3 examples/mavsdk_mission.py --url udpin://0.0.0.0:14540

The vehicle (or `host-sim hil --gcs udp:127.0.0.1:14540`) sends to that port. The script:

1. connects and reads the vehicle's position (GLOBAL_POSITION_INT), attitude
   (ATTITUDE_QUATERNION) and map origin (GPS_GLOBAL_ORIGIN);
2. uploads the mission with `mission_raw`: NAV_TAKEOFF to 0.5 m, NAV_WAYPOINT at the target,
   NAV_LOITER_TIME 2 s, NAV_LAND there (latitude and longitude from the origin);
3. starts it (`start_mission`: the Mission mode, PX4's AUTO/MISSION). The vehicle estimates
   the payload, moves its robots and arms itself: no `action.arm()` (it refuses one);
4. once the vehicle is on its way to the target, holds it (`action.hold()`) for a few
   seconds, checks it stays put, and resumes (`start_mission` again);
5. follows the items reached (`mission_progress`) and waits for the landing.

Exit status 0 when the payload landed with every item reached; 1 when something failed (one
line says what); 2 when MAVSDK-Python is not installed.
"""

import argparse
import asyncio
import math
import socket
import sys
import time
import warnings

try:
    # MAVSDK-Python 3.x warns on import that the next major version renames the package.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FutureWarning)
        from mavsdk import System
        from mavsdk.mission_raw import MissionItem
        from mavsdk.telemetry import FlightMode, LandedState
except ImportError:
    print("MAVSDK-Python is not installed (pip install mavsdk==3.17.4)", file=sys.stderr)
    sys.exit(2)

# The paper's case: the target (m north, m east of the origin) and its height (m).
TARGET = (0.3, 1.98)
HEIGHT = 0.5
HOVER_S = 2.0
# MAVLink numbers used below (MAV_CMD, MAV_FRAME).
NAV_WAYPOINT, NAV_LOITER_TIME, NAV_LAND, NAV_TAKEOFF = 16, 19, 21, 22
GLOBAL_RELATIVE_ALT_INT = 6
# Longest a MAVSDK call may wait for the vehicle's answer, s.
ANSWER_S = 60
# Horizontal speed below which the held vehicle counts as at rest, m/s.
SETTLED_M_S = 0.05
EARTH_RADIUS = 6_378_137.0


class Failed(Exception):
    """What did not happen."""


def offset(lat_deg, lon_deg, north, east):
    """Latitude and longitude (degrees) `north`, `east` metres from a point (flat earth:
    exact to millimetres over a motion-capture volume)."""
    lat = lat_deg + math.degrees(north / EARTH_RADIUS)
    lon = lon_deg + math.degrees(east / (EARTH_RADIUS * math.cos(math.radians(lat_deg))))
    return lat, lon


def item(seq, command, lat=0.0, lon=0.0, z=0.0, param1=0.0):
    """A mission item in the global frame with altitude above the take-off point (latitude
    and longitude 0: where the vehicle is)."""
    return MissionItem(seq=seq, frame=GLOBAL_RELATIVE_ALT_INT, command=command,
                       current=int(seq == 0), autocontinue=1, param1=param1, param2=0.0,
                       param3=0.0, param4=float("nan"), x=int(round(lat * 1e7)),
                       y=int(round(lon * 1e7)), z=z, mission_type=0)


async def first(stream, timeout, what, condition=lambda _: True):
    """The first value of a MAVSDK stream meeting `condition`, within `timeout` seconds."""
    async def find():
        async for value in stream:
            if condition(value):
                return value
    try:
        return await asyncio.wait_for(find(), timeout)
    except asyncio.TimeoutError:
        raise Failed(f"no {what} within {timeout} s")


async def answered(call, what, timeout=ANSWER_S):
    """What a MAVSDK call returns, within `timeout` seconds (a vehicle that went away would
    leave it waiting)."""
    try:
        return await asyncio.wait_for(call, timeout)
    except asyncio.TimeoutError:
        raise Failed(f"no answer to {what} within {timeout} s")


def free_tcp_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


async def fly(url, log=print, hold_s=3.0):
    """Flies the mission through the vehicle at `url`; returns what was seen."""
    drone = System(port=free_tcp_port())
    await drone.connect(system_address=url)
    await first(drone.core.connection_state(), 120, "connection", lambda s: s.is_connected)
    log("connected")
    position = await first(drone.telemetry.position(), 60, "position")
    q = await first(drone.telemetry.attitude_quaternion(), 60, "attitude")
    log(f"position {position.latitude_deg:.7f}, {position.longitude_deg:.7f}, "
        f"{position.relative_altitude_m:.2f} m; attitude w {q.w:.3f}")
    origin = await answered(drone.telemetry.get_gps_global_origin(), "the map origin")
    lat, lon = offset(origin.latitude_deg, origin.longitude_deg, *TARGET)
    mission = [
        item(0, NAV_TAKEOFF, z=HEIGHT),
        item(1, NAV_WAYPOINT, lat, lon, HEIGHT),
        item(2, NAV_LOITER_TIME, z=HEIGHT, param1=HOVER_S),
        item(3, NAV_LAND, lat, lon, 0.0),
    ]
    await answered(drone.mission_raw.upload_mission(mission), "the mission's upload")
    log(f"mission of {len(mission)} items uploaded")

    reached = []

    async def follow_progress():
        async for p in drone.mission_raw.mission_progress():
            reached.append(p.current)
            log(f"mission progress {p.current}/{p.total}")

    modes = []

    async def follow_modes():
        async for m in drone.telemetry.flight_mode():
            if not modes or modes[-1] != m:
                modes.append(m)

    progress = asyncio.ensure_future(follow_progress())
    mode_log = asyncio.ensure_future(follow_modes())
    try:
        # The vehicle may still be loading its payload description: it answers "not now".
        deadline = time.monotonic() + 60
        while True:
            try:
                await answered(drone.mission_raw.start_mission(), "the mission's start")
                break
            except Exception as e:  # MissionRawError(DENIED) while it loads
                if time.monotonic() > deadline:
                    raise Failed(f"the mission did not start: {e}")
                await asyncio.sleep(0.5)
        log("mission started: estimating the payload, then the formation, then the flight")
        await first(drone.telemetry.landed_state(), 600, "take-off",
                    lambda s: s == LandedState.IN_AIR)
        # On the way to the target (the take-off item reached), hold.
        await first(drone.mission_raw.mission_progress(), 120, "the take-off reached",
                    lambda p: p.current >= 1)
        await answered(drone.action.hold(), "the hold")
        # Read from the modes followed above: one subscription to the flight mode (a second
        # one beside it once lost mavsdk_server's gRPC stream under load).
        end = time.monotonic() + 30
        while FlightMode.HOLD not in modes:
            if time.monotonic() > end:
                raise Failed(f"no Hold mode within 30 s: modes {modes}")
            await asyncio.sleep(0.1)
        # The vehicle stops where its plan was when the hold came: held from when it has
        # come to rest there, for `hold_s` seconds (the measurement's window).
        a = await first(drone.telemetry.position_velocity_ned(), 30, "the vehicle at rest",
                        lambda p: math.hypot(p.velocity.north_m_s, p.velocity.east_m_s)
                        < SETTLED_M_S)
        await asyncio.sleep(hold_s)
        b = await first(drone.telemetry.position_velocity_ned(), 10, "position")
        moved = math.dist((a.position.north_m, a.position.east_m),
                          (b.position.north_m, b.position.east_m))
        log(f"held {hold_s:.0f} s: moved {moved:.3f} m")
        if moved > 0.1:
            raise Failed(f"the vehicle moved {moved:.2f} m while held")
        held_at = len(modes)
        progress_at_hold = max(reached, default=0)
        await answered(drone.mission_raw.start_mission(), "the mission's resumption")
        # Resumed: the Mission mode seen after the hold, or the progress moving on (on a fast
        # or loaded run the mode may be Mission and over before a heartbeat is read). Waited
        # for on what the vehicle says, with a backstop.
        end = time.monotonic() + 120
        while not (FlightMode.MISSION in modes[held_at:]
                   or max(reached, default=0) > progress_at_hold):
            if time.monotonic() > end:
                raise Failed(f"not resumed: modes since the hold {modes[held_at:]}, "
                             f"progress {reached[-1:]}")
            await asyncio.sleep(0.1)
        log("resumed")
        await first(drone.telemetry.landed_state(), 600, "the landing",
                    lambda s: s == LandedState.ON_GROUND)
        log("landed")
        # The last item's progress may come after the landed state.
        end = time.monotonic() + 30
        while (not reached or max(reached) < len(mission)) and time.monotonic() < end:
            await asyncio.sleep(0.1)  # polling the progress followed above
    finally:
        progress.cancel()
        mode_log.cancel()
    if not reached or max(reached) < len(mission):
        raise Failed(f"items reached: progress went to {reached[-1:] or 'nothing'}")
    return {"moved_while_held_m": moved, "progress": reached}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--url", default="udpin://0.0.0.0:14540",
                        help="where the vehicle's MAVLink comes (MAVSDK connection URL)")
    args = parser.parse_args()
    try:
        asyncio.run(fly(args.url))
    except Failed as e:
        print(f"mavsdk mission: FAILED: {e}", file=sys.stderr)
        return 1
    print("mavsdk mission: landed with every item reached")
    return 0


if __name__ == "__main__":
    sys.exit(main())
