//! One MAVLink FTP message as the `FILE_TRANSFER_PROTOCOL` payload carries it (its layout is
//! in [`crate::ftp`]), with the opcodes and the `NAK` error codes.

use crate::msg::FILE_TRANSFER_PROTOCOL_DATA;

/// Bytes of data one FTP message carries.
pub const DATA_LEN: usize = 239;
/// Length of the whole FTP payload.
pub const PAYLOAD_LEN: usize = 251;

/// FTP opcodes (MAVLink FTP, "Opcodes").
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Opcode {
    None = 0,
    TerminateSession = 1,
    ResetSessions = 2,
    ListDirectory = 3,
    OpenFileRO = 4,
    ReadFile = 5,
    CreateFile = 6,
    WriteFile = 7,
    RemoveFile = 8,
    CreateDirectory = 9,
    RemoveDirectory = 10,
    OpenFileWO = 11,
    TruncateFile = 12,
    Rename = 13,
    CalcFileCRC32 = 14,
    BurstReadFile = 15,
    Ack = 128,
    Nak = 129,
}

/// FTP error codes of a `NAK` (MAVLink FTP, "NAK error information").
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum ErrorCode {
    None = 0,
    Fail = 1,
    FailErrno = 2,
    InvalidDataSize = 3,
    InvalidSession = 4,
    NoSessionsAvailable = 5,
    Eof = 6,
    UnknownCommand = 7,
    FileExists = 8,
    FileProtected = 9,
    FileNotFound = 10,
}

impl ErrorCode {
    fn from_u8(v: u8) -> Option<Self> {
        use ErrorCode::*;
        [
            None,
            Fail,
            FailErrno,
            InvalidDataSize,
            InvalidSession,
            NoSessionsAvailable,
            Eof,
            UnknownCommand,
            FileExists,
            FileProtected,
            FileNotFound,
        ]
        .into_iter()
        .find(|c| *c as u8 == v)
    }
}

/// One FTP message (command or answer).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FtpMessage {
    /// Sequence number.
    pub seq: u16,
    /// Session id.
    pub session: u8,
    /// Opcode (see [`Opcode`]).
    pub opcode: u8,
    /// Bytes of `data` in use.
    pub size: u8,
    /// In an answer: the opcode answered.
    pub req_opcode: u8,
    /// Burst reads only.
    pub burst_complete: u8,
    /// File offset, bytes.
    pub offset: u32,
    /// Data.
    pub data: [u8; DATA_LEN],
}

impl Default for FtpMessage {
    fn default() -> Self {
        Self {
            seq: 0,
            session: 0,
            opcode: 0,
            size: 0,
            req_opcode: 0,
            burst_complete: 0,
            offset: 0,
            data: [0; DATA_LEN],
        }
    }
}

impl FtpMessage {
    /// A command `opcode` with sequence number `seq`.
    pub fn command(seq: u16, opcode: Opcode) -> Self {
        Self {
            seq,
            opcode: opcode as u8,
            ..Self::default()
        }
    }

    /// Reads the FTP payload of a `FILE_TRANSFER_PROTOCOL`.
    pub fn from_payload(p: &[u8; PAYLOAD_LEN]) -> Self {
        let mut data = [0; DATA_LEN];
        data.copy_from_slice(&p[12..]);
        Self {
            seq: u16::from_le_bytes([p[0], p[1]]),
            session: p[2],
            opcode: p[3],
            size: p[4],
            req_opcode: p[5],
            burst_complete: p[6],
            offset: u32::from_le_bytes([p[8], p[9], p[10], p[11]]),
            data,
        }
    }

    /// The FTP payload.
    pub fn to_payload(&self) -> [u8; PAYLOAD_LEN] {
        let mut p = [0; PAYLOAD_LEN];
        p[..2].copy_from_slice(&self.seq.to_le_bytes());
        p[2] = self.session;
        p[3] = self.opcode;
        p[4] = self.size;
        p[5] = self.req_opcode;
        p[6] = self.burst_complete;
        p[8..12].copy_from_slice(&self.offset.to_le_bytes());
        p[12..].copy_from_slice(&self.data);
        p
    }

    /// As a `FILE_TRANSFER_PROTOCOL` to `system`/`component`.
    pub fn to_message(&self, system: u8, component: u8) -> FILE_TRANSFER_PROTOCOL_DATA {
        FILE_TRANSFER_PROTOCOL_DATA {
            target_network: 0,
            target_system: system,
            target_component: component,
            payload: self.to_payload(),
        }
    }

    /// The data in use (`size` bytes, at most [`DATA_LEN`]).
    pub fn data(&self) -> &[u8] {
        &self.data[..usize::from(self.size).min(DATA_LEN)]
    }

    /// Sets the data (cut to [`DATA_LEN`]).
    pub fn set_data(&mut self, bytes: &[u8]) {
        let n = bytes.len().min(DATA_LEN);
        self.data[..n].copy_from_slice(&bytes[..n]);
        self.size = n as u8;
    }

    /// The error code of a `NAK`.
    pub fn nak_code(&self) -> Option<ErrorCode> {
        (self.opcode == Opcode::Nak as u8)
            .then(|| ErrorCode::from_u8(self.data[0]))
            .flatten()
    }
}
