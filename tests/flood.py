#!/usr/bin/env python3
"""A flooding ground station against the firmware under QEMU, with pymavlink, through
`host-sim hil --gcs` (docs/ground-link.md#under-a-flood).

Run by tests/hil/ground/flood.rs (cargo test); by hand:

    python3 tests/flood.py --host-sim target/debug/host-sim \
        --elf target/thumbv7em-none-eabihf/release/firmware-qemu \
        --scenario tests/scenarios/rect-ex1.toml [--rate 200] [--kinds bytes,mix,param-list]

First the mission flies with no ground station (`hil --json --storage`, a fresh storage): the
clean run (`--clean-report FILE`: that run's report, flown already by the caller; the Rust
test shares the flight with the other tests that need it). Then, for each
kind of flood, it flies again with this script as its ground station (`--gcs --linger 30`),
which from the mission's start (the HEARTBEAT says it runs) to the mission's end sends `--rate` messages a second
(default 200; seconds of the vehicle's clock, read from the time stamps of its telemetry, so
the flood is as dense for the vehicle however slowly QEMU runs it on a loaded machine; the run
paced at 4 times real time; at most rate x 120 of them) besides its own heartbeat once a
second of the wall's:

- `bytes`: random bytes, 1 to 300 in each datagram;
- `mix`: bad parameter writes (a value out of range, not a number), unknown commands, FTP
  garbage, mission counts, log-list and parameter-list requests, drawn at random;
- `param-list`: `PARAM_REQUEST_LIST` alone (each asks for every parameter, ~3.7 KB).

Each flooded run must hold:
1. the mission delivers with exactly the clean run's result (lifts, estimate, positions,
   phases, final position, steps);
2. the vehicle's heartbeat reaches the ground station throughout: on the vehicle's clock
   (the `TIMESYNC` request sent with each heartbeat carries it) no gap above 1.5 s;
3. after the flood, a well-behaved ground station gets every parameter: `PARAM_REQUEST_LIST`,
   asked again after 2 s with no answer (as QGroundControl does), at most 10 times.

It prints, per kind, the messages sent, the frames the radio link (the bridge) dropped, the
replies the vehicle dropped and the parameter lists it restarted (`SYS_STATUS`
`errors_count1`, `errors_count2`), and the largest heartbeat gap on the vehicle's clock and on
the wall clock.

Exit status 0 when everything holds; 2 with one line on stderr when pymavlink is missing
(the Rust test turns that into a skip or, in CI, a failure); 1 for any failure, saying which.
"""

import argparse
import json
import os
import random
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ground_station as gs  # noqa: E402  (pymavlink's absence exits 2 there)
from ground_station import ABORTED, COMPLETED, Failure, mavlink  # noqa: E402

KINDS = ("bytes", "mix", "param-list")
# What must match the clean run exactly (the JSON keys of `hil --json`).
RESULT_KEYS = ("delivered", "aborted", "estimate", "measurements", "lifts", "positions",
               "phases", "final_position_error_m", "dropped", "mission_state", "ticks")
# The vehicle's attitude and local position come at 10 Hz of its clock, stamped with it.
STAMP_INTERVAL_S = 0.1
# The flood's length at most, s of the vehicle's clock.
MAX_SECONDS = 120
# Wall seconds a flooded mission may take at most: a backstop only (the plant fails a run whose
# firmware stalls after FLOODED_REPLY_TIMEOUT_S); a starved QEMU runs many times slower.
MAX_WALL_S = 900
# Messages a second: a busy ground station's 200 (1,000 and 2,000 hold on an idle machine,
# docs/failures.md).
RATE = 200
# The flooded runs are paced at this many times real time, so the vehicle's clock (QEMU's,
# which runs slower than the wall's while the lockstep goes flat out) keeps near the wall's:
# the flood's rate, the link's and the heartbeat's second are then the same second.
SPEED = 4
LONGEST_BEAT_GAP_S = 1.5
# Wall seconds the plant waits for each lockstep reply in a flooded run (the default is 10).
# Serving the flood keeps the firmware busy, and QEMU then emulates it slower than the wall's
# clock: a parameter-list flood measured heartbeat gaps of 1.00 s on the vehicle's clock and
# 3.3 to 4.4 s on the wall's, and once in CI, on a loaded two-core machine, a step waited more
# than 10 s. A firmware that stalls still fails the run, after this long.
FLOODED_REPLY_TIMEOUT_S = 60
# Parameter-list requests after the flood, 2 s apart, before it counts as failed.
LIST_TRIES = 10
# The flooder's own system id: the plant (255) uploads the payload with FTP meanwhile.
FLOODER_SYSTEM = 254


def plant_command(args, extra):
    return [args.host_sim, "hil", "--scenario", args.scenario, "--qemu", args.elf, "--json",
            "--storage", args.storage] + extra


def report_of(plant, what):
    out, err = plant.communicate(timeout=300)
    try:
        return json.loads(out)
    except json.JSONDecodeError:
        raise Failure(f"{what}: host-sim printed no JSON (exit {plant.returncode}): "
                      f"{err.strip()[-500:]}")


class Flooder:
    """The hostile ground station: one kind of flood at a rate, and what it saw."""

    def __init__(self, conn, kind, rate, seed):
        self.conn, self.kind, self.rate = conn, kind, rate
        self.random = random.Random(seed)
        self.sent = 0
        self.started = self.now = None

    def due(self, now):
        """Sends the messages due by `now`, s of the vehicle's clock (the rate from the first
        call)."""
        if self.started is None:
            self.started = now
        self.now = now
        due = min(int((now - self.started) * self.rate), self.rate * MAX_SECONDS)
        while self.sent < due:
            self.one()
            self.sent += 1

    def one(self):
        mav, r = self.conn.mav, self.random
        kind = self.kind
        if kind == "bytes":
            self.conn.write(bytes(r.getrandbits(8) for _ in range(r.randint(1, 300))))
            return
        if kind == "mix":
            kind = r.choice(["param-set", "command", "ftp", "mission-count", "log-list",
                             "param-list"])
        if kind == "param-list":
            mav.param_request_list_send(1, 1)
        elif kind == "param-set":
            value = r.choice([5.0, float("nan")])
            mav.param_set_send(1, 1, b"MAX_TILT", value, mavlink.MAV_PARAM_TYPE_REAL32)
        elif kind == "command":
            mav.command_long_send(1, 1, r.randint(40000, 41000), 0, *[0.0] * 7)
        elif kind == "ftp":
            mav.file_transfer_protocol_send(0, 1, 1, [r.getrandbits(8) for _ in range(251)])
        elif kind == "mission-count":
            mav.mission_count_send(1, 1, r.randint(1, 50), mavlink.MAV_MISSION_TYPE_MISSION, 0)
        elif kind == "log-list":
            mav.log_request_list_send(1, 1, 0, 0xFFFF)


def whole_list(v, kind):
    """Every parameter, as a well-behaved ground station asks: `PARAM_REQUEST_LIST`, asked
    again after 2 s with nothing, as QGroundControl does; at most [`LIST_TRIES`] times. A
    random-bytes flood may end inside a false frame header, whose length (up to 280 bytes)
    the bridge's parser then fills with the next real bytes: at a heartbeat a second, the
    first requests are swallowed, as they would be behind a noisy radio. Returns the values
    and the requests it took."""
    values, count = {}, None
    for tries in range(1, LIST_TRIES + 1):
        v.conn.mav.param_request_list_send(1, 1)
        while count is None or len(values) < count:
            m = v.recv(["PARAM_VALUE"], 2)
            if m is None:
                break
            count = m.param_count
            values[m.param_index] = m.param_id
        if count is not None and len(values) == count:
            return values, tries
    heard = v.recv(["HEARTBEAT"], 2, lambda m: m.get_srcComponent() == 1) is not None
    raise Failure(f"{kind}: after the flood, {len(values)} of {count} parameters came "
                  f"in {LIST_TRIES} requests (the vehicle's heartbeat "
                  f"{'still comes' if heard else 'stopped too'})")


def worst_step(report):
    """The worst control step a run's report says, for people."""
    worst = report.get("worst_tick") or {}
    unit = "instructions" if worst.get("name") == "tick_insn" else "cycles"
    return f"{worst.get('value', float('nan')):,.0f} {unit}" if worst else "not reported"


def flooded_run(args, kind, clean):
    # Listening before the plant starts: nothing the vehicle says first is lost.
    v = gs.Vehicle(0, system=FLOODER_SYSTEM)
    v.conn.target_system, v.conn.target_component = 1, 1
    plant = subprocess.Popen(
        plant_command(args, ["--gcs", f"udp:127.0.0.1:{v.port}", "--linger", "30",
                             "--speed", str(SPEED),
                             "--reply-timeout", str(FLOODED_REPLY_TIMEOUT_S)]),
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        # The plant uploads the payload description and starts the mission: the flood begins
        # when the vehicle's HEARTBEAT says it runs (it comes each second, so none is missed).
        try:
            v.mission_state([gs.RUNNING], "started by the plant", 60)
        except Failure as e:
            raise Failure(f"{kind}: {e}")
        flooder = Flooder(v.conn, kind, args.rate, seed=KINDS.index(kind) + 1)
        beats_wall, beats_vehicle = [], []
        status = None
        state = None
        chunks = {}  # a long STATUSTEXT's chunks, by its id
        started = time.monotonic()
        vehicle_s = None  # the vehicle's clock, from its telemetry's time stamps
        while state not in (COMPLETED, ABORTED):
            if time.monotonic() - started > MAX_WALL_S:
                raise Failure(f"{kind}: the mission did not end within {MAX_WALL_S} s")
            if plant.poll() is not None:
                raise Failure(f"{kind}: host-sim ended during the flood: "
                              f"{plant.communicate()[1].strip()[-500:]}")
            if vehicle_s is not None:
                # Between two stamps the vehicle's clock runs on at the pace the run is held
                # to, at most to where the next stamp (10 Hz) would say: smooth when QEMU keeps
                # pace, never ahead of the vehicle when it does not.
                ahead = min((time.monotonic() - stamped_at) * SPEED, STAMP_INTERVAL_S)
                flooder.due(vehicle_s + ahead)
            v.beat()
            m = v.conn.recv_match(blocking=True, timeout=0.002)
            while m is not None:
                t = m.get_type()
                stamp = getattr(m, "time_boot_ms", None)
                if stamp is not None and m.get_srcSystem() == 1 and \
                        stamp * 1e-3 > (vehicle_s or 0.0):
                    vehicle_s, stamped_at = stamp * 1e-3, time.monotonic()
                if t == "HEARTBEAT" and m.get_srcComponent() == 1:
                    beats_wall.append(time.monotonic())
                    state = m.custom_mode & 0xFF
                elif t == "TIMESYNC" and m.tc1 == 0 and m.get_srcSystem() == 1:
                    beats_vehicle.append(m.ts1 * 1e-9)
                elif t == "SYS_STATUS":
                    status = m
                elif t == "STATUSTEXT":
                    v.texts.append(m.text)
                    chunks.setdefault(m.id, []).append(m.text)
                m = v.conn.recv_match(blocking=False)
        if state != COMPLETED:
            raise Failure(f"{kind}: the mission aborted: {v.texts[-3:]}")
        # After the flood: the values of its last list drained (none for 0.5 s; at most 10 s),
        # then a well-behaved parameter list, whole.
        drained = time.monotonic() + 10
        while (v.recv(["PARAM_VALUE"], 0.5) is not None) and time.monotonic() < drained:
            pass
        listed = time.monotonic()
        params, tries = whole_list(v, kind)
        list_s = time.monotonic() - listed
        # Quiet now: the plant ends its linger after 2 s of silence.
        v.conn.close()
        report = report_of(plant, kind)
    finally:
        if plant.poll() is None:
            plant.kill()
            plant.communicate()
    for key in RESULT_KEYS:
        if report.get(key) != clean.get(key):
            raise Failure(f"{kind}: `{key}` differs from the clean run: "
                          f"{report.get(key)!r} against {clean.get(key)!r}")
    gap = lambda times: max((b - a for a, b in zip(times, times[1:])), default=float("inf"))
    vehicle_gap, wall_gap = gap(beats_vehicle), gap(beats_wall)
    if vehicle_gap > LONGEST_BEAT_GAP_S:
        raise Failure(f"{kind}: a heartbeat gap of {vehicle_gap:.2f} s on the vehicle's clock "
                      f"(at most {LONGEST_BEAT_GAP_S} s)")
    link = report.get("gcs_link") or {}
    replies = status.errors_count1 if status else 0
    lists = status.errors_count2 if status else 0
    texts = ["".join(c) for i, c in sorted(chunks.items()) if i] + \
        [c for c in chunks.get(0, [])]
    told = [t for t in texts if t.startswith("link: in")]
    span = (flooder.now - flooder.started) if flooder.started is not None else 0.0
    print(f"  {kind}: {flooder.sent} messages sent over {span:.0f} s of the vehicle's clock "
          f"({time.monotonic() - started:.0f} s wall); "
          f"radio dropped {link.get('dropped_frames', 0)} of "
          f"{link.get('dropped_frames', 0) + link.get('forwarded_frames', 0)} frames; "
          f"vehicle dropped {replies} replies, restarted {lists} parameter lists "
          f"({len(told)} texts said so, the last: {told[-1] if told else 'none'!r}); largest heartbeat gap {vehicle_gap:.2f} s on the "
          f"vehicle's clock, {wall_gap:.2f} s wall; then {len(params)} parameters in "
          f"{list_s:.1f} s ({tries} request{'s' if tries > 1 else ''}); delivered as the clean "
          f"run; worst control step {worst_step(report)} (clean run {worst_step(clean)})")
    return report


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host-sim", required=True)
    parser.add_argument("--elf", required=True)
    parser.add_argument("--scenario", required=True)
    parser.add_argument("--rate", type=int, default=RATE, help="messages a second")
    parser.add_argument("--kinds", default=",".join(KINDS))
    parser.add_argument("--clean-report",
                        help="the clean run's report (`hil --json --storage` of the same "
                             "mission with a fresh storage), when it was flown already")
    args = parser.parse_args()
    kinds = args.kinds.split(",")
    unknown = [k for k in kinds if k not in KINDS]
    if unknown or not 1 <= args.rate <= 5000:
        print(f"flood: --kinds from {','.join(KINDS)}, --rate 1 to 5000", file=sys.stderr)
        return 1
    started = time.monotonic()
    try:
        if args.clean_report:
            with open(args.clean_report) as f:
                clean = json.load(f)
        else:
            with tempfile.TemporaryDirectory(prefix="flood-") as tmp:
                args.storage = tmp
                clean = report_of(subprocess.Popen(plant_command(args, []),
                                                   stdout=subprocess.PIPE,
                                                   stderr=subprocess.PIPE, text=True),
                                  "clean run")
        if not clean.get("delivered"):
            raise Failure(f"the clean run did not deliver: {clean.get('aborted')}")
        for kind in kinds:
            with tempfile.TemporaryDirectory(prefix=f"flood-{kind}-") as tmp:
                args.storage = tmp
                flooded_run(args, kind, clean)
    except Failure as e:
        print(f"flood: FAILED: {e}", file=sys.stderr)
        return 1
    print(f"flood: all checks held in {time.monotonic() - started:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
