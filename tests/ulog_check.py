#!/usr/bin/env python3
"""Opens a flight log with pyulog, the reference ULog reader, and checks what the vehicle's
logs must hold (docs/formats.md#flight-logs): the logged topics, each with monotonic
timestamps, every parameter, the information section and the status texts.

usage: ulog_check.py FILE.ulg PARAMETERS TOPIC [TOPIC ...]
Exit 0 when the log holds it all, 1 (with what is wrong) when not, 2 when pyulog is missing.
"""
import sys

try:
    from pyulog import ULog
except ImportError:
    print("pyulog is not installed (python3 -m pip install pyulog)", file=sys.stderr)
    sys.exit(2)


def main():
    path, parameters, topics = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
    log = ULog(path)
    problems = []
    names = {d.name for d in log.data_list}
    for topic in topics:
        if topic not in names:
            problems.append(f"topic {topic} is missing")
    for d in log.data_list:
        t = d.data["timestamp"]
        if len(t) == 0:
            problems.append(f"{d.name} has no data")
        elif any(b < a for a, b in zip(t, t[1:])):
            problems.append(f"{d.name}: timestamps go backwards")
    if len(log.initial_parameters) != parameters:
        problems.append(f"{len(log.initial_parameters)} parameters, expected {parameters}")
    for key in ("sys_name", "ver_sw", "ver_hw"):
        if key not in log.msg_info_dict:
            problems.append(f"information {key} is missing")
    if not log.logged_messages:
        problems.append("no logged strings")
    if log.dropouts:
        problems.append(f"{len(log.dropouts)} dropouts")
    if problems:
        print("\n".join(problems), file=sys.stderr)
        sys.exit(1)
    sizes = ", ".join(f"{d.name} {len(d.data['timestamp'])}" for d in log.data_list)
    print(f"pyulog read {path}: {len(log.data_list)} topics ({sizes}), "
          f"{len(log.initial_parameters)} parameters, {len(log.logged_messages)} strings")


main()
