#!/usr/bin/env python3
"""Opens a flight log with pyulog, the reference ULog reader, and checks what the vehicle's
logs must hold (docs/formats.md#flight-logs): the logged topics, each with monotonic
timestamps, PX4's field names where the topic is PX4's (the setpoints beside the estimate,
their thrust normalised and negative up), the lift's posterior spread and model, every
parameter, the information section and the status texts.

usage: ulog_check.py FILE.ulg PARAMETERS TOPIC [TOPIC ...]
Exit 0 when the log holds it all, 1 (with what is wrong) when not, 2 when pyulog is missing.
"""
import sys

try:
    from pyulog import ULog
except ImportError:
    print("pyulog is not installed (python3 -m pip install pyulog)", file=sys.stderr)
    sys.exit(2)


# Fields a topic must have, as pyulog names them (arrays flattened as name[i]).
FIELDS = {
    "vehicle_attitude_setpoint": ["q_d[0]", "q_d[1]", "q_d[2]", "q_d[3]",
                                  "thrust_body[0]", "thrust_body[1]", "thrust_body[2]"],
    "vehicle_rates_setpoint": ["roll", "pitch", "yaw",
                               "thrust_body[0]", "thrust_body[1]", "thrust_body[2]"],
    "lift": ["pair", "thrust_n", "com_x", "com_y", "mass", "confidence",
             "com_x_std", "com_y_std", "mass_std", "model_n"],
}


def check_fields(log, problems):
    """PX4's field names on the setpoints, and values that mean what the docs say."""
    data = {d.name: d.data for d in log.data_list}
    for topic, fields in FIELDS.items():
        if topic not in data:
            continue
        for field in fields:
            if field not in data[topic]:
                problems.append(f"{topic} has no field {field}")
    for topic in ("vehicle_attitude_setpoint", "vehicle_rates_setpoint"):
        d = data.get(topic)
        if d is None or "thrust_body[2]" not in d:
            continue
        z = d["thrust_body[2]"]
        if not all(-1.0 <= v <= 0.0 for v in z):
            problems.append(f"{topic}: thrust_body[2] outside [-1, 0] (normalised, negative up)")
        if not any(v < -0.05 for v in z):
            problems.append(f"{topic}: thrust_body[2] never asks for thrust")
    d = data.get("vehicle_attitude_setpoint")
    if d is not None and all(f"q_d[{i}]" in d for i in range(4)):
        for k in range(len(d["timestamp"])):
            norm = sum(d[f"q_d[{i}]"][k] ** 2 for i in range(4))
            if abs(norm - 1.0) > 1e-3:
                problems.append(f"vehicle_attitude_setpoint: q_d of norm {norm:.4f}")
                break
    d = data.get("lift")
    if d is not None and all(f in d for f in FIELDS["lift"]):
        for k in range(len(d["timestamp"])):
            spread = [d[f][k] for f in ("com_x_std", "com_y_std", "mass_std")]
            if not all(v > 0.0 for v in spread):
                problems.append(f"lift {k}: posterior spread {spread} not positive")
            if not d["model_n"][k] > 0.0:
                problems.append(f"lift {k}: model_n {d['model_n'][k]} not a thrust")


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
    check_fields(log, problems)
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
