#!/usr/bin/env python3
"""The MAVSDK example (examples/mavsdk_mission.py) against the firmware under QEMU, through
`host-sim hil --gcs`, paced at 4x real time: it connects, reads the position and attitude,
uploads the paper's case with `mission_raw`, starts it, holds it in flight (the vehicle
stays within 0.1 m) and resumes it, and sees every item reached and the landing; the
plant's report then says the payload was delivered at the target.

Run by tests/hil/ground/mavsdk_mission.rs (cargo test); by hand:

    python3 tests/mavsdk_mission.py --host-sim target/debug/host-sim \
        --elf target/thumbv7em-none-eabihf/release/firmware-qemu \
        --scenario tests/scenarios/rect-ex1.toml

Exit status 0 when everything holds; 2 with one line on stderr when MAVSDK-Python or
pymavlink is missing.
"""

import asyncio
import collections
import logging
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "examples"))
import ground_station as gs  # noqa: E402  (exits 2 without pymavlink)
import mavsdk_mission  # noqa: E402  (exits 2 without MAVSDK-Python)


class LastLines(logging.Handler):
    """The last lines mavsdk_server printed (MAVSDK-Python hands them to the logger
    "mavsdk_server"), to say what it last did when a call to it fails."""

    def __init__(self, count=40):
        super().__init__(logging.DEBUG)
        self.lines = collections.deque(maxlen=count)

    def emit(self, record):
        self.lines.append(record.getMessage())


def main():
    server_log = LastLines()
    logger = logging.getLogger("mavsdk_server")
    logger.setLevel(logging.DEBUG)
    logger.addHandler(server_log)
    logger.propagate = False

    def checks(plant):
        try:
            seen = asyncio.run(mavsdk_mission.fly(f"udpin://127.0.0.1:{plant.port}",
                                                  hold_s=1.0))
        except Exception:
            print("mavsdk_server's last lines:\n  " + "\n  ".join(server_log.lines),
                  file=sys.stderr)
            raise
        print(f"delivered {gs.delivered(plant):.3f} m from the target; "
              f"moved {seen['moved_while_held_m']:.3f} m while held")

    return gs.run_against_plant("mavsdk mission", __doc__.splitlines()[0], checks,
                                ["--speed", "4"], (gs.Failure, mavsdk_mission.Failed),
                                listen=False)


if __name__ == "__main__":
    code = main()
    # MAVSDK's server and gRPC threads can keep the interpreter from exiting after a
    # failure (seen: a failed check then hung to the test's 900 s backstop): leave at once.
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)
