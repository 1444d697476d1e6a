//! The firmware's flight log (docs/formats.md#flight-logs), from the flight with `hil --storage`
//! the tests share ([`crate::storage_flight`]): what it keeps in its storage (`storage`), and
//! what a ground station downloads from it (`download`, the binary's longest test: its name
//! sorts first, so libtest starts it first).

mod download;
mod storage;
