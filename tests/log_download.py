#!/usr/bin/env python3
"""The flight logs downloaded from the firmware under QEMU with MAVLink's log protocol, as
QGroundControl and MAVProxy fetch them (docs/formats.md#downloading-the-logs), through
`host-sim hil --gcs`.

Run by tests/hil/flight_log/download.rs (cargo test), on a storage directory the firmware has
flown a mission into; by hand:

    python3 tests/log_download.py --host-sim target/debug/host-sim \
        --elf target/thumbv7em-none-eabihf/release/firmware-qemu \
        --scenario tests/scenarios/rect-ex1.toml --storage DIR

The firmware restarted on that storage (idle, `--ground-start`), with pymavlink:

0. SYS_STATUS: MAV_SYS_STATUS_LOGGING present, enabled and healthy;
1. LOG_REQUEST_LIST: a LOG_ENTRY for each log-NNN.ulg in DIR, with its size;
2. each log downloaded block by block (LOG_REQUEST_DATA of 45 KiB, missing pieces asked
   again), byte for byte the file in DIR, then drawn by `host-sim plot`; the speed is
   printed; meanwhile the vehicle's HEARTBEAT keeps coming, at most 1.5 s of its clock apart
   (each comes with a TIMESYNC request stamped with that clock, which under QEMU runs at its
   own pace, not the wall's); then during a download to the end a PARAM_REQUEST_READ is
   answered;
3. a request for a log that is not kept: no LOG_DATA, a STATUSTEXT saying so; a request past
   the end and one of count 0: one LOG_DATA of count 0 each;
4. MAVProxy (when installed; required with HIL_REQUIRED=1): `log list`, `log download 0`,
   the file byte for byte the one in DIR;
5. LOG_ERASE: the logs erased (a STATUSTEXT), the list then empty, DIR without logs.

Exit status 0 when everything holds; 2 with one line on stderr when pymavlink is missing;
1 for any failure, saying which.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ground_station as gs  # noqa: E402  (exits 2 when pymavlink is missing)

mavlink = gs.mavlink
Failure = gs.Failure
# Bytes a LOG_REQUEST_DATA asks for at a time (QGroundControl asks 90 * 1024).
BLOCK = 90 * 512
# Wall seconds a block may take at most: a backstop only (a block fails after ten requests on
# the vehicle's clock, above), for a vehicle whose clock stopped.
BLOCK_BACKSTOP_S = 120
# Longest the vehicle's heartbeats may be apart during a download, s of the vehicle's clock
# (it sends one a second, with a TIMESYNC request stamped with its clock).
MAX_BEAT_GAP_S = 1.5


def stored_logs(storage):
    """The log files in the storage directory, by id."""
    logs = []
    while os.path.exists(os.path.join(storage, f"log-{len(logs):03}.ulg")):
        logs.append(os.path.join(storage, f"log-{len(logs):03}.ulg"))
    return logs


class Watch:
    """What else the vehicle sends during a download: its heartbeats, each on the vehicle's
    clock (the TIMESYNC request it sends with each carries its time), and the rest by type."""

    def __init__(self):
        self.beats = []
        self.others = {}

    def see(self, m):
        kind = m.get_type()
        if kind == "TIMESYNC" and m.get_srcComponent() == 1 and m.tc1 == 0:
            # (wall time, vehicle time in s)
            self.beats.append((time.monotonic(), m.ts1 * 1e-9))
        elif kind not in ("LOG_DATA", "LOG_ENTRY"):
            self.others[kind] = self.others.get(kind, 0) + 1

    def during(self, start, end):
        """The heartbeats between two wall times: how many, over how long on the vehicle's
        clock, and the widest gap between two on it."""
        clock = [c for t, c in self.beats if start <= t <= end]
        if len(clock) < 2:
            return len(clock), 0.0, float("inf")
        return len(clock), clock[-1] - clock[0], max(b - a for a, b in zip(clock, clock[1:]))


def receive(v, watch, timeout):
    """The next message (or None after `timeout`), the ground's heartbeat kept going."""
    v.beat()
    m = v.conn.recv_match(blocking=True, timeout=timeout)
    if m is None:
        return None
    if m.get_type() == "STATUSTEXT":
        v.texts.append(m.text)
    watch.see(m)
    return m


def list_logs(v, watch):
    v.conn.mav.log_request_list_send(1, 1, 0, 0xFFFF)
    entries, count = {}, None
    end = time.monotonic() + 20
    while time.monotonic() < end and (count is None or len(entries) < max(count, 1)):
        m = receive(v, watch, 0.5)
        if m is None or m.get_type() != "LOG_ENTRY":
            continue
        count = m.num_logs
        entries[m.id] = m
    if count is None:
        raise Failure("no LOG_ENTRY answered LOG_REQUEST_LIST within 20 s")
    return count, entries


def vehicle_clock(watch):
    """The vehicle's clock, s, as its last heartbeat's TIMESYNC said; None before one came."""
    return watch.beats[-1][1] if watch.beats else None


def download(v, watch, log_id, size):
    """Log `log_id` block by block, as QGroundControl does: its bytes."""
    data = bytearray(size)
    for block_start in range(0, size, BLOCK):
        block_end = min(size, block_start + BLOCK)
        missing = set(range(block_start, block_end, 90))
        v.conn.mav.log_request_data_send(1, 1, log_id, block_start, block_end - block_start)
        asked = block_asked = time.monotonic()
        retries = 0
        counted_at = vehicle_clock(watch)
        while missing:
            m = receive(v, watch, 0.5)
            if m is not None and m.get_type() == "LOG_DATA" and m.id == log_id:
                if m.ofs in missing:
                    data[m.ofs:m.ofs + m.count] = bytes(m.data[:m.count])
                    missing.discard(m.ofs)
                    asked = time.monotonic()
                continue
            if time.monotonic() - asked > 1.0:
                # Asked again after a second of the wall's without the rest of the block, and
                # counted against the ten only once the vehicle's clock has moved on a second
                # too: on a loaded machine QEMU runs it slower than the wall's, and ten seconds
                # of the wall's were once too few for it to answer.
                now = vehicle_clock(watch)
                if now is None or counted_at is None or now - counted_at >= 1.0:
                    retries += 1
                    counted_at = now
                if retries > 10 or time.monotonic() - block_asked > BLOCK_BACKSTOP_S:
                    raise Failure(f"log {log_id}: the block at {block_start} did not come "
                                  f"({len(missing)} pieces missing after {retries} requests, "
                                  f"{time.monotonic() - block_asked:.0f} s)")
                first, last = min(missing), max(missing)
                v.conn.mav.log_request_data_send(1, 1, log_id, first, min(block_end, last + 90)
                                                 - first)
                asked = time.monotonic()
    v.conn.mav.log_request_end_send(1, 1)
    return bytes(data)


def expect_data(v, watch, log_id, ofs, count, what):
    """The LOG_DATA answering a request of `count` bytes from `ofs`: one, empty. The request is
    sent again when nothing answers it within a second and a half (as a ground station does: a
    frame can be lost between the ground and the vehicle), so each answer must be that one."""
    got = []
    for _ in range(3):
        v.conn.mav.log_request_data_send(1, 1, log_id, ofs, count)
        end = time.monotonic() + 1.5
        while time.monotonic() < end:
            m = receive(v, watch, 0.3)
            if m is not None and m.get_type() == "LOG_DATA":
                got.append((m.id, m.ofs, m.count))
        if got:
            break
    if not got or any(g != (log_id, ofs, 0) for g in got):
        raise Failure(f"{what}: LOG_DATA {got}, expected one of count 0 at {ofs}")


def hostile_requests(v, watch, count, size):
    before = len(v.texts)
    v.conn.mav.log_request_data_send(1, 1, 0xFFFF, 0, 0xFFFFFFFF)
    end = time.monotonic() + 3
    while time.monotonic() < end:
        m = receive(v, watch, 0.3)
        if m is not None and m.get_type() == "LOG_DATA":
            raise Failure(f"a LOG_DATA answered a request for log 65535: {m}")
    if not any("no log 65535" in t for t in v.texts[before:]):
        raise Failure(f"no STATUSTEXT about log 65535 (got {v.texts[before:]})")
    expect_data(v, watch, 0, size, 0xFFFFFFFF, "a request from the end")
    expect_data(v, watch, 0, 0xFFFFFF00, 90, "a request far past the end")
    expect_data(v, watch, 0, 90, 0, "a request of count 0")
    print(f"hostile requests: log 65535 of {count} not answered (a STATUSTEXT says so); from "
          "the end, far past it and of count 0: one empty LOG_DATA each")


# MAVProxy as `mavproxy.py` starts it, its link's socket given the receive buffer this script's
# own pymavlink asks for (ground_station.RECEIVE_BUFFER; SO_RCVBUFFORCE where allowed, past the
# system's maximum): with the system's default (208 KB) the log's LOG_DATA, which the vehicle
# sends at several times real time, overflowed it whenever MAVProxy was descheduled on a busy
# machine (some 20,000 datagrams dropped in a download), and MAVProxy then spent minutes asking
# for the gaps.
MAVPROXY_WITH_BUFFER = """
import runpy, socket, sys
from pymavlink import mavutil
size = int(sys.argv.pop(1))
opened = mavutil.mavudp.__init__
def with_buffer(self, *args, **kwargs):
    opened(self, *args, **kwargs)
    for option in (getattr(socket, "SO_RCVBUFFORCE", None), socket.SO_RCVBUF):
        try:
            self.port.setsockopt(socket.SOL_SOCKET, option, size)
            break
        except (OSError, TypeError):
            pass
mavutil.mavudp.__init__ = with_buffer
sys.argv[0] = "mavproxy.py"
runpy.run_module("MAVProxy.mavproxy", run_name="__main__", alter_sys=True)
"""


def mavproxy_download(args, log_path):
    """MAVProxy's `log list` and `log download 0`, typed in as a person would: the file."""
    mavproxy = shutil.which("mavproxy.py")
    if mavproxy is None:
        if os.environ.get("HIL_REQUIRED") == "1":
            raise Failure("MAVProxy is not installed (pip install MAVProxy) and HIL_REQUIRED=1")
        print("MAVProxy is not installed (pip install MAVProxy): its check skipped")
        return
    want = open(log_path, "rb").read()
    # On a busy machine MAVProxy falls behind, and what overflows its socket it asks for again
    # after 0.7 s without data (each request replacing the one before, as in PX4): with the
    # system's default buffer the download took 175 to 270 s on two loaded cores, whatever the
    # plant's pace (1, 2 or 4 times real time), and once the plant's idle steps ran out first;
    # with MAVPROXY_WITH_BUFFER's, 58 to 67 s there and a few dozen requests again. The plant
    # is paced to 2 times real time: its 15 minutes of idle steps are 7.5 of the wall's.
    plant = gs.start_hil(args, ["--speed", "2"], listen=False)
    with tempfile.TemporaryDirectory(prefix="mavproxy-logs-") as state:
        out_file = os.path.join(state, "log0.ulg")
        proxy = subprocess.Popen(
            [sys.executable, "-c", MAVPROXY_WITH_BUFFER, str(gs.RECEIVE_BUFFER),
             f"--master=udpin:127.0.0.1:{plant.port}", "--source-system=255",
             f"--state-basedir={state}"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
            text=True, bufsize=1, env={**os.environ, "PYTHONUNBUFFERED": "1"})
        stop = threading.Timer(300, proxy.kill)
        stop.start()
        seen = []
        started = None
        try:
            for line in proxy.stdout:
                line = line.rstrip()
                seen.append(line)
                if "Detected vehicle 1:1" in line and started is None:
                    proxy.stdin.write("log list\n")
                    proxy.stdin.flush()
                    started = 0.0
                elif "Log 0 " in line and "numLogs" in line and started == 0.0:
                    proxy.stdin.write(f"log download 0 {out_file}\n")
                    proxy.stdin.flush()
                    started = time.monotonic()
                elif "Finished downloading" in line:
                    break
        finally:
            stop.cancel()
            proxy.kill()
            proxy.communicate()
            plant.kill()
            plant.communicate()
        took = time.monotonic() - started if started else 0.0
        finished = [line for line in seen if "Finished downloading" in line]
        if not finished:
            raise Failure(f"MAVProxy did not download the log: {seen[-8:]}")
        got = open(out_file, "rb").read()
        if got != want:
            raise Failure(f"MAVProxy's download ({len(got)} bytes) differs from {log_path} "
                          f"({len(want)} bytes)")
        listed = [line for line in seen if "Log 0 " in line and "numLogs" in line]
        print(f"MAVProxy: {listed[0].split('Log 0 ')[-1].strip()}; "
              f"{finished[0].split('> ')[-1].strip()} "
              f"({len(got) / max(took, 1e-9) / 1000:.1f} kB/s from the command); the same bytes")


def erase(v, watch, storage):
    v.conn.mav.log_erase_send(1, 1)
    v.text_matching("flight logs erased", 10)
    count, entries = list_logs(v, watch)
    if count != 0 or list(entries) != [0] or entries[0].size != 0:
        raise Failure(f"after LOG_ERASE the list says {count} logs: {entries}")
    if stored_logs(storage):
        raise Failure(f"after LOG_ERASE {stored_logs(storage)} are still there")
    print("LOG_ERASE: the logs erased; the list then one LOG_ENTRY of num_logs 0")


def with_plant(args, checks):
    """Runs `checks` on a vehicle restarted on the storage. The plant steps the idle vehicle
    for at most 15 minutes of its time: at full speed about a minute of the wall's, which the
    downloads and the checks after them come close to; paced at 8 times real time it is two."""
    plant = gs.start_hil(args, ["--speed", "8"])
    try:
        checks(gs.connect(plant))
    finally:
        plant.ground.conn.close()
        plant.kill()
        plant.communicate()


def logging_health(v):
    """SYS_STATUS says the vehicle keeps logs and its storage works (MAV_SYS_STATUS_LOGGING
    present, enabled and healthy)."""
    bit = mavlink.MAV_SYS_STATUS_LOGGING
    status = v.expect(["SYS_STATUS"], 10, "SYS_STATUS")
    bits = (status.onboard_control_sensors_present, status.onboard_control_sensors_enabled,
            status.onboard_control_sensors_health)
    if not all(b & bit for b in bits):
        raise Failure(f"SYS_STATUS logging bits (present, enabled, healthy) {bits}")
    print("SYS_STATUS: the log storage present, enabled and healthy")


def plot_downloaded(args, log_bytes):
    """`host-sim plot` draws the mission's summary from the downloaded log: its page written."""
    with tempfile.TemporaryDirectory() as out:
        path = os.path.join(out, "downloaded.ulg")
        with open(path, "wb") as f:
            f.write(log_bytes)
        run = subprocess.run([args.host_sim, "plot", path, "--output", out, "--json"],
                             capture_output=True, text=True, timeout=120)
        if run.returncode != 0:
            raise Failure(f"host-sim plot of the downloaded log failed: {run.stderr.strip()}")
        report = json.loads(run.stdout)
        files = report.get("files", [])
        if not files or not all(os.path.getsize(f) > 1000 for f in files):
            raise Failure(f"host-sim plot of the downloaded log wrote {files}")
        if not report.get("mission_ended") or len(report.get("lifts", [])) == 0:
            raise Failure(f"host-sim plot read no whole mission from the downloaded log: "
                          f"{report.get('notes')}")
        print(f"host-sim plot drew the downloaded log: {[os.path.basename(f) for f in files]}")


def pymavlink_checks(v, args, files, sizes):
    logging_health(v)
    watch = Watch()
    count, entries = list_logs(v, watch)
    listed = [entries[i].size if i in entries else None for i in range(count)]
    if count != len(files) or listed != sizes:
        raise Failure(f"LOG_ENTRY: {count} logs of {listed} bytes; stored {sizes}")
    print(f"LOG_REQUEST_LIST: {count} log(s), sizes {listed} as stored")

    for log_id, path in enumerate(files):
        size = sizes[log_id]
        want = open(path, "rb").read()
        started = time.monotonic()
        got = download(v, watch, log_id, size)
        took = time.monotonic() - started
        if got != want:
            first = next(i for i in range(size) if got[i] != want[i])
            raise Failure(f"log {log_id}: the download differs from {path} at byte {first}")
        beats, span, gap = watch.during(started, time.monotonic())
        print(f"log {log_id}: {size} bytes downloaded in {took:.1f} s "
              f"({size / took / 1000:.1f} kB/s), byte for byte the stored file; "
              f"{beats} heartbeats meanwhile over {span:.1f} s of the vehicle's clock, "
              f"at most {gap:.2f} s apart")
        if gap > MAX_BEAT_GAP_S:
            raise Failure(f"the vehicle's heartbeats were {gap:.2f} s of its clock apart "
                          f"during the download (at most {MAX_BEAT_GAP_S} s)")
        plot_downloaded(args, got)
    # The link's other services during a download.
    v.conn.mav.log_request_data_send(1, 1, 0, 0, 0xFFFFFFFF)
    asked = time.monotonic()
    v.conn.mav.param_request_read_send(1, 1, b"MAX_TILT", -1)
    answer = None
    while answer is None and time.monotonic() - asked < 10:
        m = receive(v, watch, 0.5)
        if m is not None and m.get_type() == "PARAM_VALUE":
            answer = time.monotonic() - asked
    v.conn.mav.log_request_end_send(1, 1)
    if answer is None:
        raise Failure("no PARAM_VALUE within 10 s during a download")
    print(f"during a download a PARAM_REQUEST_READ was answered in {answer * 1000:.0f} ms; "
          f"meanwhile also {', '.join(sorted(watch.others))}")
    # What was on its way when LOG_REQUEST_END came.
    while receive(v, watch, 0.5) is not None and time.monotonic() - asked < 20:
        pass
    hostile_requests(v, watch, count, sizes[0])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host-sim", required=True)
    parser.add_argument("--elf", required=True)
    parser.add_argument("--scenario", required=True)
    parser.add_argument("--storage", required=True, help="the directory the logs are in")
    args = parser.parse_args()
    files = stored_logs(args.storage)
    if not files:
        print(f"log download: FAILED: no log-000.ulg in {args.storage}", file=sys.stderr)
        return 1
    # The plant steps the idle vehicle at up to 15 minutes of its time (two minutes of the
    # wall's at 8 times real time, 7.5 at 2): each part has a plant of its own, on the same
    # storage.
    try:
        sizes = [os.path.getsize(f) for f in files]
        with_plant(args, lambda v: pymavlink_checks(v, args, files, sizes))
        mavproxy_download(args, files[0])
        with_plant(args, lambda v: erase(v, Watch(), args.storage))
    except Failure as e:
        print(f"log download: FAILED: {e}", file=sys.stderr)
        return 1
    print("log download: all checks held")
    return 0


if __name__ == "__main__":
    sys.exit(main())
