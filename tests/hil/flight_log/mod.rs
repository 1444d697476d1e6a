//! The firmware's flight log (docs/formats.md#flight-logs), from a flight with `hil --storage`:
//! what it keeps in its storage (`storage`), and what a ground station downloads from it
//! (`download`, the binary's longest test: its name sorts first, so libtest starts it first).

mod download;
mod storage;
