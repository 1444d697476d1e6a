//! MAVLink FTP (the MAVLink "File Transfer Protocol" service, `FILE_TRANSFER_PROTOCOL`):
//! how a ground station writes the payload description to the vehicle before the mission.
//!
//! The `FILE_TRANSFER_PROTOCOL` payload (251 bytes) carries, little-endian: `seq_number` u16,
//! `session` u8, `opcode` u8, `size` u8, `req_opcode` u8, `burst_complete` u8, padding u8,
//! `offset` u32 and up to [`DATA_LEN`] bytes of data. The ground side (client) sends commands;
//! the vehicle (server) answers each with `ACK` or `NAK` (data\[0\] the error code) carrying
//! `req_opcode` = the command's opcode, `seq_number` one more than the command's, and the
//! command's `session`. A session opened is the one the client named in its open command (as
//! ArduPilot has it; QGroundControl and PX4's clients take the session from the answer, which
//! is then the same; MAVProxy routes each answer to its operation by that session, and an
//! answer with another one is lost to it). A command repeated with the same `seq_number` (the
//! client timed out) gets the same answer again, without being carried out twice.
//!
//! [`Server`] is the vehicle's minimal server: one session, one writable file
//! ([`PAYLOAD_PATH`]) held in RAM, and the opcodes `TerminateSession`, `ResetSessions`,
//! `CreateFile`, `OpenFileWO`, `WriteFile`. With [`Server::handle_with`] it also serves
//! read-only files held in flash ([`ReadOnlyFile`]: the component metadata,
//! docs/ground-link.md#parameter-metadata) with `OpenFileRO`, `ReadFile` and `BurstReadFile`
//! (a burst of one message, `burst_complete` set: the client asks again from the next offset).
//! Everything else is refused with `UnknownCommand`.
//! [`Upload`] is the ground side of writing one file: `ResetSessions`, `CreateFile`, the
//! `WriteFile`s, `TerminateSession`.
//!
//! The message is in `wire`, the vehicle's server in `server`, the ground side's upload in
//! `upload`.

mod server;
mod upload;
mod wire;

pub use server::{FileEvent, PAYLOAD_PATH, ReadOnlyFile, Server, component_metadata, refusal};
pub use upload::{Progress, Upload, UploadError};
pub use wire::{DATA_LEN, ErrorCode, FtpMessage, Opcode, PAYLOAD_LEN};
