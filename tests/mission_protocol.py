#!/usr/bin/env python3
"""The mission protocol's edge cases against the firmware under QEMU, with pymavlink, through
`host-sim hil --gcs` (docs/ground-link.md#missions).

Run by tests/hil/ground/mission_protocol.rs (cargo test); by hand:

    python3 tests/mission_protocol.py --host-sim target/debug/host-sim \
        --elf target/thumbv7em-none-eabihf/release/firmware-qemu \
        --scenario tests/scenarios/rect-ex1.toml

What it checks, in order, on one run of the firmware (paced at 4x real time, so the vehicle's
1.5 s item timeout is 0.4 s here):

1. no mission at first (MISSION_COUNT 0); the modes listed (AVAILABLE_MODES) and the
   HEARTBEAT's custom_mode in PX4's numbers (AUTO/READY);
2. a count over capacity (1,000 items) refused NO_SPACE with a STATUSTEXT;
3. the paper's case uploaded (take-off, the target, a hover, a landing) with an item sent out
   of order and one twice: the vehicle asks again for the one it expects, then ACCEPTED;
   downloaded back item for item;
4. bad items (a waypoint 5 km away, a NaN altitude, a local frame, a return-to-launch
   command) each refused in the MISSION_ACK with the reason in a STATUSTEXT, and the old
   mission still there;
5. an upload that stops mid-way: the vehicle asks again for the missing item, then cancels
   (OPERATION_CANCELLED), the old mission kept;
6. the mission started with MAV_CMD_DO_SET_MODE (PX4's AUTO/MISSION, as MAVSDK sends it); in
   the air (EXTENDED_SYS_STATE) a clear and an upload are refused (DENIED, the mission is
   running), the HEARTBEAT says MISSION; every item reached (MISSION_ITEM_REACHED 0 to 3),
   and the plant's report says the payload was delivered at the target.

Exit status 0 when everything holds; 2 with one line on stderr when pymavlink is missing.
"""

import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ground_station as gs  # noqa: E402  (pymavlink's absence exits 2 there)
from ground_station import Failure, mavlink  # noqa: E402

# The paper's case (rect-ex1): the target 0.3 m north, 1.98 m east, 0.5 m up.
TARGET = (0.3, 1.98, 0.5)
# Long enough that the checks in the air (a clear and an upload refused, the HEARTBEAT's mode)
# find the vehicle still flying on a loaded machine: with 2 s the landing came first there.
HOVER_S = 10.0
RELATIVE = mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT


def item(seq, command, north=0.0, east=0.0, z=0.0, frame=RELATIVE, param1=0.0, here=False):
    """A MISSION_ITEM_INT's fields, placed from the map origin (the default: PX4's simulation
    home); `here`: latitude and longitude 0 (where the vehicle is)."""
    lat, lon = (0, 0) if here else gs.to_global(gs.DEFAULT_ORIGIN, north, east)
    return dict(seq=seq, frame=frame, command=command, current=int(seq == 0), autocontinue=1,
                param1=param1, param2=0.0, param3=0.0, param4=0.0, x=int(round(lat)),
                y=int(round(lon)), z=z)


def paper_mission():
    north, east, up = TARGET
    return [
        item(0, mavlink.MAV_CMD_NAV_TAKEOFF, z=up, here=True),
        item(1, mavlink.MAV_CMD_NAV_WAYPOINT, north, east, up),
        item(2, mavlink.MAV_CMD_NAV_LOITER_TIME, z=up, param1=HOVER_S, here=True),
        item(3, mavlink.MAV_CMD_NAV_LAND, north, east, 0.0),
    ]


def send_item(v, it, seq=None):
    fields = dict(it)
    if seq is not None:
        fields["seq"] = seq
    v.conn.mav.mission_item_int_send(1, 1, fields["seq"], fields["frame"], fields["command"],
                                     fields["current"], fields["autocontinue"],
                                     fields["param1"], fields["param2"], fields["param3"],
                                     fields["param4"], fields["x"], fields["y"], fields["z"], 0)


def request(v, what):
    return v.expect(["MISSION_REQUEST_INT", "MISSION_ACK"], 10, what)


def upload(v, items):
    """Uploads `items` answering each MISSION_REQUEST_INT; the MISSION_ACK that ends it."""
    v.conn.mav.mission_count_send(1, 1, len(items), 0)
    while True:
        m = request(v, "a MISSION_REQUEST_INT or MISSION_ACK during an upload")
        if m.get_type() == "MISSION_ACK":
            return m
        if not 0 <= m.seq < len(items):
            raise Failure(f"the vehicle asked for item {m.seq} of {len(items)}")
        send_item(v, items[m.seq])


def download(v):
    v.conn.mav.mission_request_list_send(1, 1, 0)
    count = v.expect(["MISSION_COUNT"], 10, "MISSION_COUNT").count
    got = []
    for seq in range(count):
        v.conn.mav.mission_request_int_send(1, 1, seq, 0)
        got.append(v.expect(["MISSION_ITEM_INT"], 10, f"MISSION_ITEM_INT {seq}",
                            lambda m, s=seq: m.seq == s))
    v.conn.mav.mission_ack_send(1, 1, mavlink.MAV_MISSION_ACCEPTED, 0)
    return got


def same(sent, got):
    return (got.command == sent["command"] and got.frame == sent["frame"]
            and got.x == sent["x"] and got.y == sent["y"]
            and math.isclose(got.z, sent["z"], abs_tol=1e-6)
            and math.isclose(got.param1, sent["param1"], abs_tol=1e-6))


def refused(v, ack, result, says):
    if ack.get_type() != "MISSION_ACK" or ack.type != result:
        raise Failure(f"expected MISSION_ACK {result}, got {ack}")
    v.text_matching(says, 10)


def modes_checks(v):
    hb = v.expect(["HEARTBEAT"], 10, "HEARTBEAT", lambda m: m.get_srcComponent() == 1)
    if (hb.custom_mode >> 16) & 0xFF != 4 or hb.custom_mode >> 24 != 1:
        raise Failure(f"HEARTBEAT custom_mode {hb.custom_mode:#x}: not PX4's AUTO/READY")
    v.conn.mav.command_long_send(1, 1, mavlink.MAV_CMD_REQUEST_MESSAGE, 0, 435, 0, 0, 0, 0, 0,
                                 0)
    names = {}
    end = time.monotonic() + 10
    while time.monotonic() < end and len(names) < 4:
        m = v.recv(["AVAILABLE_MODES"], 1)
        if m is not None:
            name = m.mode_name if isinstance(m.mode_name, str) else m.mode_name.decode()
            names[m.mode_index] = (name.rstrip("\0"), m.custom_mode, m.standard_mode)
    if sorted(n[0] for n in names.values()) != ["Hold", "Land", "Mission", "Ready"]:
        raise Failure(f"AVAILABLE_MODES: {names}")
    print(f"modes: {', '.join(n[0] for n in names.values())}; the HEARTBEAT says AUTO/READY")


def ground_checks(v):
    if download(v):
        raise Failure("a mission on a fresh vehicle")
    modes_checks(v)
    v.conn.mav.mission_count_send(1, 1, 1000, 0)
    refused(v, request(v, "MISSION_ACK to 1,000 items"), mavlink.MAV_MISSION_NO_SPACE,
            "at most 16")
    print("1,000 items refused: NO_SPACE, with a STATUSTEXT")

    mission = paper_mission()
    v.conn.mav.mission_count_send(1, 1, len(mission), 0)
    m = request(v, "MISSION_REQUEST_INT 0")
    send_item(v, mission[0])
    m = request(v, "MISSION_REQUEST_INT 1")
    if m.get_type() != "MISSION_REQUEST_INT" or m.seq != 1:
        raise Failure(f"after item 0 the vehicle sent {m}")
    send_item(v, mission[2])  # out of order
    send_item(v, mission[0])  # a duplicate
    asked = [request(v, "a request after an item out of order").seq for _ in range(2)]
    if asked != [1, 1]:
        raise Failure(f"after items out of order the vehicle asked for {asked}, not 1 and 1")
    for seq in range(1, len(mission)):
        send_item(v, mission[seq])
        m = request(v, f"the answer to item {seq}")
        while m.get_type() == "MISSION_REQUEST_INT" and m.seq == seq:
            m = request(v, f"the answer to item {seq}")  # a retry raced our item
    if m.get_type() != "MISSION_ACK" or m.type != mavlink.MAV_MISSION_ACCEPTED:
        raise Failure(f"the paper's mission: {m}")
    v.text_matching("mission of 4 items accepted", 10)
    got = download(v)
    if len(got) != 4 or not all(same(s, g) for s, g in zip(mission, got)):
        raise Failure(f"downloaded back: {got}")
    print("the paper's case uploaded (an item out of order and one twice asked for again), "
          "downloaded back the same")

    north_far = item(1, mavlink.MAV_CMD_NAV_WAYPOINT, 5000.0, 0.0, 0.5)
    nan = item(1, mavlink.MAV_CMD_NAV_WAYPOINT, 1.0, 0.0, float("nan"))
    local = dict(item(1, mavlink.MAV_CMD_NAV_WAYPOINT, 1.0, 0.0, 0.5),
                 frame=mavlink.MAV_FRAME_LOCAL_NED)
    rtl = item(1, mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH)
    bad = [(north_far, mavlink.MAV_MISSION_INVALID_PARAM5_X, "m from the origin"),
           (nan, mavlink.MAV_MISSION_INVALID, "not a number"),
           (local, mavlink.MAV_MISSION_UNSUPPORTED_FRAME, "frame 1 is not flown"),
           (rtl, mavlink.MAV_MISSION_UNSUPPORTED, "command 20 is not flown")]
    for it, result, says in bad:
        refused(v, upload(v, [mission[0], it]), result, says)
    if len(download(v)) != 4:
        raise Failure("a refused upload replaced the mission")
    print("a waypoint 5 km away, a NaN altitude, a local frame and RTL refused with their "
          "reasons; the old mission kept")

    v.conn.mav.mission_count_send(1, 1, 3, 0)
    request(v, "MISSION_REQUEST_INT 0")
    send_item(v, mission[0])
    retries, ack = 0, None
    # A backstop only: the vehicle gives up after its own retries, on its clock, which on a
    # loaded machine QEMU runs many times slower than the wall's (30 s was once too short).
    end = time.monotonic() + 120
    while ack is None and time.monotonic() < end:
        m = v.recv(["MISSION_REQUEST_INT", "MISSION_ACK"], 1)
        if m is None:
            continue
        if m.get_type() == "MISSION_ACK":
            ack = m
        elif m.seq == 1:
            retries += 1
    if ack is None or ack.type != mavlink.MAV_MISSION_OPERATION_CANCELLED or retries < 2:
        raise Failure(f"a silent upload: {retries} requests again, then {ack}")
    v.text_matching("never came", 10)
    if len(download(v)) != 4:
        raise Failure("a cancelled upload replaced the mission")
    print(f"an upload that stopped: item 1 asked for {retries} times, then cancelled; "
          "the old mission kept")
    return mission


def flight_checks(v, plant, mission):
    v.payload_loaded()
    deadline = time.time() + 30
    while True:
        ack = v.command(mavlink.MAV_CMD_DO_SET_MODE, 1, 4, 4)
        if ack.result != mavlink.MAV_RESULT_TEMPORARILY_REJECTED or time.time() > deadline:
            break
        time.sleep(0.2)
    if ack.result != mavlink.MAV_RESULT_ACCEPTED:
        raise Failure(f"DO_SET_MODE AUTO/MISSION acknowledged {ack.result}")
    print("started with MAV_CMD_DO_SET_MODE AUTO/MISSION")
    v.keep.add("MISSION_ITEM_REACHED")
    # The vehicle's HEARTBEATs kept as they come, whatever is awaited: the mode is read from
    # the first one after it said it was in the air (one comes each second of its clock, well
    # within the flight), not from whichever comes after the refusals below, which on a
    # loaded machine may come after the landing.
    v.keep.add("HEARTBEAT")
    v.expect(["EXTENDED_SYS_STATE"], 600, "EXTENDED_SYS_STATE in the air",
             lambda m: m.landed_state == mavlink.MAV_LANDED_STATE_IN_AIR)
    beats_before = len(v.kept.get("HEARTBEAT", []))
    v.conn.mav.mission_clear_all_send(1, 1, 0)
    refused(v, v.expect(["MISSION_ACK"], 10, "MISSION_ACK to a clear in flight"),
            mavlink.MAV_MISSION_DENIED, "mission not cleared: the mission is running")
    refused(v, upload(v, mission[:2]), mavlink.MAV_MISSION_DENIED,
            "mission upload refused: the mission is running")
    vehicle = lambda m: m.get_srcComponent() == 1  # noqa: E731
    in_air = [m for m in v.kept.get("HEARTBEAT", [])[beats_before:] if vehicle(m)]
    hb = in_air[0] if in_air else v.expect(["HEARTBEAT"], 10, "HEARTBEAT in flight", vehicle)
    if hb.custom_mode >> 24 != 4:
        raise Failure(f"in flight the HEARTBEAT's custom_mode is {hb.custom_mode:#x}")
    print("in the air: a clear and an upload refused (DENIED, the mission is running); "
          "the HEARTBEAT says AUTO/MISSION")
    end = time.monotonic() + 300
    while len(v.kept.get("MISSION_ITEM_REACHED", [])) < len(mission) and time.monotonic() < end:
        v.recv([], 1)
    reached = [m.seq for m in v.kept.get("MISSION_ITEM_REACHED", [])]
    if reached != list(range(len(mission))):
        raise Failure(f"items reached: {reached}")
    print(f"items reached in order: {reached}")
    print(f"delivered {gs.delivered(plant):.3f} m from the target")


def main():
    # The development dialect: pymavlink 2.4.50 has the standard modes' messages only there
    # (MAVLink moved them to common in 2024).
    def checks(plant):
        v = gs.connect(plant)
        mission = ground_checks(v)
        flight_checks(v, plant, mission)

    return gs.run_against_plant("mission protocol", __doc__.splitlines()[0], checks,
                                ["--speed", "4"], dialect="development")


if __name__ == "__main__":
    sys.exit(main())
