#!/usr/bin/env python3
"""The MAVSDK example (examples/mavsdk_mission.py) against the firmware under QEMU, through
`host-sim hil --gcs`, paced at 4x real time: it connects, reads the position and attitude,
uploads the paper's case with `mission_raw`, starts it, holds it in flight (the vehicle
stays within 0.1 m) and resumes it, and sees every item reached and the landing; the
plant's report then says the payload was delivered at the target.

Run by tests/mavsdk_mission.rs (cargo test); by hand:

    python3 tests/mavsdk_mission.py --host-sim target/debug/host-sim \
        --elf target/thumbv7em-none-eabihf/release/firmware-qemu \
        --scenario tests/scenarios/rect-ex1.toml

Exit status 0 when everything holds; 2 with one line on stderr when MAVSDK-Python or
pymavlink is missing.
"""

import argparse
import asyncio
import json
import os
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "examples"))
import ground_station as gs  # noqa: E402  (exits 2 without pymavlink)
import mavsdk_mission  # noqa: E402  (exits 2 without MAVSDK-Python)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host-sim", required=True)
    parser.add_argument("--elf", required=True)
    parser.add_argument("--scenario", required=True)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="mavsdk-") as tmp:
        args.storage = tmp
        started = time.monotonic()
        port = gs.free_udp_port()
        plant = gs.start_hil(args, port, ["--speed", "4"])
        try:
            seen = asyncio.run(mavsdk_mission.fly(f"udpin://127.0.0.1:{port}", hold_s=1.0))
            out, err = plant.communicate(timeout=300)
            report = json.loads(out) if out.strip() else None
            if report is None:
                raise mavsdk_mission.Failed(f"host-sim printed no JSON: {err[-500:]}")
            if not report["delivered"]:
                raise mavsdk_mission.Failed(
                    f"not delivered: landed {report['final_position_error_m']:.2f} m away")
            print(f"delivered {report['final_position_error_m']:.3f} m from the target; "
                  f"moved {seen['moved_while_held_m']:.3f} m while held")
        except mavsdk_mission.Failed as e:
            print(f"mavsdk mission: FAILED: {e}", file=sys.stderr)
            return 1
        finally:
            if plant.poll() is None:
                plant.kill()
                plant.communicate()
        print(f"mavsdk mission: all checks held in {time.monotonic() - started:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
