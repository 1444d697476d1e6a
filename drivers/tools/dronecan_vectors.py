#!/usr/bin/env python3
"""Test vectors for drivers/src/dronecan, made by the reference DroneCAN implementation.

pydronecan (PyPI `dronecan`, 1.0.27) encodes each message below and cuts it into CAN frames;
this prints them as the Rust constants drivers/src/dronecan/tests.rs holds. Run it with
`pip install dronecan==1.0.27` to check or remake them:

    python3 drivers/tools/dronecan_vectors.py
"""
import dronecan
from dronecan import uavcan
from dronecan.transport import Transfer


def frames(name, message, source, transfer_id, priority):
    transfer = Transfer(payload=message, source_node_id=source, transfer_id=transfer_id,
                        transfer_priority=priority, service_not_message=False)
    print(f"/// {name}, from pydronecan {dronecan.version.__version__}.")
    print(f"const {name}: &[(u32, &[u8])] = &[")
    for frame in transfer.to_frames():
        data = ", ".join(f"0x{b:02x}" for b in bytes(frame.bytes))
        print(f"    (0x{frame.message_id:08x}, &[{data}]),")
    print("];")


frames("RAW_COMMAND_FOUR", uavcan.equipment.esc.RawCommand(cmd=[0, 100, 8191, -8192]), 1, 5, 5)
frames("RAW_COMMAND_SIXTEEN",
       uavcan.equipment.esc.RawCommand(cmd=[(i * 547) % 8192 for i in range(16)]), 1, 30, 5)
frames("ESC_STATUS",
       uavcan.equipment.esc.Status(error_count=3, voltage=15.2, current=4.5, temperature=300.0,
                                   rpm=-5000, power_rating_pct=42, esc_index=11), 23, 31, 16)
frames("NODE_STATUS",
       uavcan.protocol.NodeStatus(uptime_sec=123456, health=1, mode=0, sub_mode=2,
                                  vendor_specific_status_code=0xBEEF), 7, 0, 16)
