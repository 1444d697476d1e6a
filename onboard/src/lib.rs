//! What the flight controller runs between its I/O, as plain `no_std` code the host tests:
//! the autonomy's seam to the mission ([`autonomy`]) and the MAVLink link's receive service
//! ([`link_service`], docs/ground-link.md) with the flash storage behind it ([`store`],
//! [`slots`]: parameters, signing key, payload description, mission, power-cut safe). The firmware's tasks only move bytes and values
//! between this code, the board and each other; the fuzz targets drive the same code.
#![cfg_attr(not(test), no_std)]
#![deny(missing_docs)]

pub mod autonomy;
pub mod link_service;
pub mod payload_loading;
pub mod slots;
pub mod store;
