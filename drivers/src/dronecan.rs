//! DroneCAN (UAVCAN v0) for CAN ESCs, as PX4 drives them over its `uavcan` module: the bit
//! packing of the data types ([`bits`]), transfers on CAN 2.0B frames ([`transfer`]), the ESC
//! messages ([`esc`]: `RawCommand` out, `Status` in), the nodes' heartbeat
//! ([`node_status`]), the flight controller's side of the bus ([`esc_bus`]) and what it sends
//! and takes while DroneCAN is the ESC protocol in force ([`esc_output`]), and the bus
//! load of the traffic ([`bus_load`]). docs/hardware.md#can-escs says how the Pixhawk 6C's
//! CAN1 carries them.
//!
//! Written once here rather than taken from a crate: the Rust DroneCAN crates either speak
//! Cyphal (UAVCAN v1, `canadensis`), are tied to one HAL's CAN driver (`dronecan`), or were
//! left at a first release (`uavcan-core` 0.0.1). The encodings are held to the reference
//! implementation's: the tests compare every byte with frames pydronecan made
//! (`drivers/tools/dronecan_vectors.py`).

pub mod bits;
pub mod bus_load;
pub mod esc;
pub mod esc_bus;
pub mod esc_output;
pub mod node_status;
pub mod transfer;

#[cfg(test)]
mod tests;
