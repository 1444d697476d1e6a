//! The vehicle's minimal MAVLink FTP server: one session, one writable file
//! ([`PAYLOAD_PATH`]) held in RAM, and read-only files held in flash ([`ReadOnlyFile`]: the
//! component metadata, docs/ground-link.md#parameter-metadata); a repeated command answered
//! again without being carried out twice.

use super::{DATA_LEN, ErrorCode, FtpMessage, Opcode};
use crate::msg::COMPONENT_METADATA_DATA;

/// The one file the vehicle accepts: the payload description (`shared::scenario_wire`).
pub const PAYLOAD_PATH: &str = "/payload.rtsc";

/// What the server did with a command, beyond answering it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileEvent {
    /// Nothing to act on.
    None,
    /// The write session on [`PAYLOAD_PATH`] was closed: the file (its first `len` bytes) is
    /// complete.
    Written {
        /// File length, bytes.
        len: usize,
    },
}

/// A file the server offers for reading only: a path and contents fixed at build time.
#[derive(Clone, Copy, Debug)]
pub struct ReadOnlyFile {
    /// Its path, as clients name it (the leading `/` optional).
    pub path: &'static str,
    /// Its contents.
    pub contents: &'static [u8],
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Access {
    /// On [`PAYLOAD_PATH`]; whether anything was written (or the file created).
    Write { wrote: bool },
    /// On the read-only file of this index.
    Read(u8),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Session {
    id: u8,
    access: Access,
}

/// The vehicle's FTP server: one session and one writable file of at most `N` bytes.
pub struct Server<const N: usize> {
    file: [u8; N],
    len: usize,
    session: Option<Session>,
    /// The last command (its [`Server::repeat_key`]) and its answer.
    last: Option<((u16, u8, u8, u32), FtpMessage)>,
}

impl<const N: usize> Default for Server<N> {
    fn default() -> Self {
        Self::new()
    }
}

fn path_of(m: &FtpMessage) -> &[u8] {
    let d = m.data();
    // Paths may come NUL-terminated.
    let end = d.iter().position(|&b| b == 0).unwrap_or(d.len());
    &d[..end]
}

/// Whether `path` (as a client sent it) names `ours`, with or without the leading `/`.
fn names(path: &[u8], ours: &str) -> bool {
    let ours = ours.as_bytes();
    path == ours || ours.strip_prefix(b"/") == Some(path)
}

impl<const N: usize> Server<N> {
    /// A server with an empty file and no session.
    pub const fn new() -> Self {
        Self {
            file: [0; N],
            len: 0,
            session: None,
            last: None,
        }
    }

    /// The file's whole buffer, to fill with a stored file (then [`Self::restored`]).
    pub fn restore_buffer(&mut self) -> &mut [u8] {
        &mut self.file
    }

    /// The first `len` bytes of the buffer are the file, restored from storage.
    pub fn restored(&mut self, len: usize) {
        self.len = len.min(N);
    }

    /// The file's contents so far.
    pub fn file(&self) -> &[u8] {
        &self.file[..self.len]
    }

    /// Answers `request`; the answer's `seq` is the request's plus one. A repeated request
    /// (same `seq` as the last) gets the last answer again and changes nothing.
    pub fn handle(&mut self, request: &FtpMessage) -> (FtpMessage, FileEvent) {
        self.handle_with(request, &[])
    }

    /// [`Self::handle`], also serving `files` for reading (always the same files, in the
    /// same order: a read session refers to its file by index).
    pub fn handle_with(
        &mut self,
        request: &FtpMessage,
        files: &[ReadOnlyFile],
    ) -> (FtpMessage, FileEvent) {
        let key = Self::repeat_key(request);
        if let Some((last, answer)) = self.last
            && last == key
        {
            return (answer, FileEvent::None);
        }
        let (mut answer, event) = self.execute(request, files);
        answer.seq = request.seq.wrapping_add(1);
        answer.req_opcode = request.opcode;
        answer.session = request.session;
        self.last = Some((key, answer));
        (answer, event)
    }

    /// What a command repeated by its client (it timed out) has the same: its `seq_number`,
    /// opcode, session and offset. Another client's command that only shares the
    /// `seq_number` is carried out, not answered with the last answer.
    fn repeat_key(request: &FtpMessage) -> (u16, u8, u8, u32) {
        (request.seq, request.opcode, request.session, request.offset)
    }

    fn execute(&mut self, r: &FtpMessage, files: &[ReadOnlyFile]) -> (FtpMessage, FileEvent) {
        const TERMINATE: u8 = Opcode::TerminateSession as u8;
        const RESET: u8 = Opcode::ResetSessions as u8;
        const CREATE: u8 = Opcode::CreateFile as u8;
        const OPEN_WO: u8 = Opcode::OpenFileWO as u8;
        const WRITE: u8 = Opcode::WriteFile as u8;
        const OPEN_RO: u8 = Opcode::OpenFileRO as u8;
        const READ: u8 = Opcode::ReadFile as u8;
        const BURST: u8 = Opcode::BurstReadFile as u8;
        match r.opcode {
            TERMINATE => match self.session {
                Some(s) if s.id == r.session => {
                    self.session = None;
                    let event = match s.access {
                        Access::Write { wrote: true } => FileEvent::Written { len: self.len },
                        _ => FileEvent::None,
                    };
                    (ack(r.session), event)
                }
                _ => (nak(r.session, ErrorCode::InvalidSession), FileEvent::None),
            },
            RESET => {
                self.session = None;
                (ack(0), FileEvent::None)
            }
            OPEN_RO => (self.open_read(r, files), FileEvent::None),
            READ | BURST => (self.read(r, files), FileEvent::None),
            CREATE | OPEN_WO => {
                if self.session.is_some() {
                    return (nak(0, ErrorCode::NoSessionsAvailable), FileEvent::None);
                }
                if !names(path_of(r), PAYLOAD_PATH) {
                    return (nak(0, ErrorCode::FileProtected), FileEvent::None);
                }
                if r.opcode == CREATE {
                    self.len = 0;
                }
                let id = r.session;
                // A created file counts as written even if no data follows.
                self.session = Some(Session {
                    id,
                    access: Access::Write {
                        wrote: r.opcode == CREATE,
                    },
                });
                (ack(id), FileEvent::None)
            }
            WRITE => {
                let Some(Session {
                    access: Access::Write { wrote },
                    ..
                }) = self.session.as_mut().filter(|s| s.id == r.session)
                else {
                    return (nak(r.session, ErrorCode::InvalidSession), FileEvent::None);
                };
                if usize::from(r.size) > DATA_LEN {
                    return (nak(r.session, ErrorCode::InvalidDataSize), FileEvent::None);
                }
                let start = r.offset as usize;
                let end = start.saturating_add(usize::from(r.size));
                if end > N {
                    // The file would not fit: the payload description is far smaller.
                    return (nak(r.session, ErrorCode::Fail), FileEvent::None);
                }
                if start > self.len {
                    self.file[self.len..start].fill(0);
                }
                self.file[start..end].copy_from_slice(r.data());
                self.len = self.len.max(end);
                *wrote = true;
                (ack(r.session), FileEvent::None)
            }
            _ => (nak(r.session, ErrorCode::UnknownCommand), FileEvent::None),
        }
    }

    /// `OpenFileRO`: a read session on one of `files`; the answer carries its length (u32).
    /// An open read session is replaced (reading changes nothing; a client that lost track
    /// of its session can start again), a write session is not.
    fn open_read(&mut self, r: &FtpMessage, files: &[ReadOnlyFile]) -> FtpMessage {
        if matches!(self.session, Some(s) if matches!(s.access, Access::Write { .. })) {
            return nak(0, ErrorCode::NoSessionsAvailable);
        }
        let path = path_of(r);
        let Some((index, file)) = files
            .iter()
            .enumerate()
            .take(usize::from(u8::MAX))
            .find(|(_, f)| names(path, f.path))
        else {
            // The payload description is written, never read back.
            let code = if names(path, PAYLOAD_PATH) {
                ErrorCode::FileProtected
            } else {
                ErrorCode::FileNotFound
            };
            return nak(0, code);
        };
        let id = r.session;
        self.session = Some(Session {
            id,
            access: Access::Read(index as u8),
        });
        let len = u32::try_from(file.contents.len()).unwrap_or(u32::MAX);
        let mut answer = ack(id);
        answer.set_data(&len.to_le_bytes());
        answer
    }

    /// `ReadFile` and `BurstReadFile`: up to [`DATA_LEN`] bytes (or the `size` asked for)
    /// from `offset`; `NAK` `EOF` at or past the end.
    fn read(&self, r: &FtpMessage, files: &[ReadOnlyFile]) -> FtpMessage {
        let file = match self.session {
            Some(Session {
                id,
                access: Access::Read(index),
            }) if id == r.session => files.get(usize::from(index)),
            _ => None,
        };
        let Some(file) = file else {
            return nak(r.session, ErrorCode::InvalidSession);
        };
        let start = usize::try_from(r.offset).unwrap_or(usize::MAX);
        let Some(rest) = file.contents.get(start..).filter(|rest| !rest.is_empty()) else {
            return nak(r.session, ErrorCode::Eof);
        };
        let wanted = match usize::from(r.size) {
            0 => DATA_LEN,
            n => n.min(DATA_LEN),
        };
        let mut answer = ack(r.session);
        answer.offset = r.offset;
        answer.set_data(&rest[..wanted.min(rest.len())]);
        answer.burst_complete = u8::from(r.opcode == Opcode::BurstReadFile as u8);
        answer
    }
}

/// `COMPONENT_METADATA`: the general metadata file at `uri` (`mftp://` and a path this
/// server serves, docs/ground-link.md#parameter-metadata) with its CRC-32 `file_crc`.
pub fn component_metadata(time_boot_ms: u32, file_crc: u32, uri: &str) -> COMPONENT_METADATA_DATA {
    COMPONENT_METADATA_DATA {
        time_boot_ms,
        file_crc,
        uri: uri.into(),
    }
}

/// The answer to `request` from a sender the vehicle does not trust (an unsigned one once
/// signing is on): `NAK` `FileProtected`, nothing done.
pub fn refusal(request: &FtpMessage) -> FtpMessage {
    let mut answer = nak(request.session, ErrorCode::FileProtected);
    answer.seq = request.seq.wrapping_add(1);
    answer.req_opcode = request.opcode;
    answer
}

fn ack(session: u8) -> FtpMessage {
    FtpMessage {
        session,
        opcode: Opcode::Ack as u8,
        ..FtpMessage::default()
    }
}

fn nak(session: u8, code: ErrorCode) -> FtpMessage {
    let mut m = FtpMessage {
        session,
        opcode: Opcode::Nak as u8,
        ..FtpMessage::default()
    };
    m.set_data(&[code as u8]);
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ftp::PAYLOAD_LEN;
    use std::vec::Vec;

    #[test]
    fn a_repeated_command_gets_the_same_answer_and_is_not_done_twice() {
        let mut server = Server::<1024>::new();
        let mut create = FtpMessage::command(4, Opcode::CreateFile);
        create.set_data(PAYLOAD_PATH.as_bytes());
        let (first, _) = server.handle(&create);
        let (again, _) = server.handle(&create);
        assert_eq!(first, again);
        assert_eq!(first.opcode, Opcode::Ack as u8);
        assert_eq!(first.seq, 5);
        // Had the repeat been executed it would have failed: the session is taken.
        let mut other = create;
        other.seq = 6;
        let (busy, _) = server.handle(&other);
        assert_eq!(busy.nak_code(), Some(ErrorCode::NoSessionsAvailable));
    }

    #[test]
    fn other_files_oversized_writes_and_unknown_commands_are_refused() {
        let mut server = Server::<64>::new();
        let mut create = FtpMessage::command(0, Opcode::CreateFile);
        create.set_data(b"/etc/passwd");
        assert_eq!(
            server.handle(&create).0.nak_code(),
            Some(ErrorCode::FileProtected)
        );
        let mut create = FtpMessage::command(2, Opcode::CreateFile);
        create.set_data(b"payload.rtsc\0");
        let (ok, _) = server.handle(&create);
        assert_eq!(ok.opcode, Opcode::Ack as u8);
        let mut write = FtpMessage::command(4, Opcode::WriteFile);
        write.session = ok.session;
        write.offset = 60;
        write.set_data(&[9; 10]);
        assert_eq!(server.handle(&write).0.nak_code(), Some(ErrorCode::Fail));
        let mut wrong_session = write;
        wrong_session.seq = 6;
        wrong_session.session = ok.session.wrapping_add(1);
        wrong_session.offset = 0;
        assert_eq!(
            server.handle(&wrong_session).0.nak_code(),
            Some(ErrorCode::InvalidSession)
        );
        let list = FtpMessage::command(8, Opcode::ListDirectory);
        assert_eq!(
            server.handle(&list).0.nak_code(),
            Some(ErrorCode::UnknownCommand)
        );
    }

    const FILES: [ReadOnlyFile; 2] = [
        ReadOnlyFile {
            path: "/comp_general.json",
            contents: b"{\"version\":1}",
        },
        ReadOnlyFile {
            path: "/big.bin",
            contents: &[7; 600],
        },
    ];

    fn send<const N: usize>(server: &mut Server<N>, seq: u16, m: FtpMessage) -> FtpMessage {
        let mut m = m;
        m.seq = seq;
        let request = FtpMessage::from_payload(&m.to_payload());
        let (answer, event) = server.handle_with(&request, &FILES);
        assert_eq!(event, FileEvent::None);
        FtpMessage::from_payload(&answer.to_payload())
    }

    #[test]
    fn another_clients_command_with_the_same_number_is_carried_out_not_repeated() {
        let mut server: Server<64> = Server::new();
        let mut reset = FtpMessage::command(0, Opcode::ResetSessions);
        reset.session = 3;
        assert_eq!(server.handle(&reset).0.opcode, Opcode::Ack as u8);
        // The same number from another client (another opcode and session): its own answer.
        let mut open = FtpMessage::command(0, Opcode::OpenFileRO);
        open.session = 210;
        open.set_data(b"/no/such/file");
        let answer = server.handle(&open).0;
        assert_eq!(answer.nak_code(), Some(ErrorCode::FileNotFound));
        assert_eq!(
            (answer.req_opcode, answer.session),
            (Opcode::OpenFileRO as u8, 210)
        );
    }

    #[test]
    fn every_answer_carries_the_session_the_client_named() {
        // MAVProxy names a session of its own and routes each answer by it: an open of a file
        // that is not there, and one that is, answer under that session.
        let mut server: Server<64> = Server::new();
        let mut missing = FtpMessage::command(0, Opcode::OpenFileRO);
        missing.session = 210;
        missing.set_data(b"@PARAM/param.pck");
        let answer = server.handle_with(&missing, &FILES).0;
        assert_eq!(answer.nak_code(), Some(ErrorCode::FileNotFound));
        assert_eq!((answer.session, answer.seq, answer.req_opcode), (210, 1, 4));
        let mut open = FtpMessage::command(2, Opcode::OpenFileRO);
        open.session = 77;
        open.set_data(FILES[0].path.as_bytes());
        let answer = server.handle_with(&open, &FILES).0;
        assert_eq!((answer.opcode, answer.session), (Opcode::Ack as u8, 77));
        let read = server
            .handle_with(&read_at(77, Opcode::ReadFile, 0, 0), &FILES)
            .0;
        assert_eq!((read.data(), read.session), (FILES[0].contents, 77));
        let mut unknown = FtpMessage::command(4, Opcode::ListDirectory);
        unknown.session = 9;
        let answer = server.handle_with(&unknown, &FILES).0;
        assert_eq!(answer.nak_code(), Some(ErrorCode::UnknownCommand));
        assert_eq!(answer.session, 9);
    }

    fn open_ro<const N: usize>(server: &mut Server<N>, seq: u16, path: &[u8]) -> FtpMessage {
        let mut open = FtpMessage::command(seq, Opcode::OpenFileRO);
        open.set_data(path);
        send(server, seq, open)
    }

    fn read_at(session: u8, op: Opcode, offset: u32, size: u8) -> FtpMessage {
        let mut m = FtpMessage::command(0, op);
        m.session = session;
        m.offset = offset;
        m.size = size;
        m
    }

    #[test]
    fn a_read_only_file_is_read_whole_by_offsets() {
        let mut server = Server::<64>::new();
        let open = open_ro(&mut server, 0, b"/big.bin");
        assert_eq!(open.opcode, Opcode::Ack as u8);
        assert_eq!(open.req_opcode, Opcode::OpenFileRO as u8);
        assert_eq!(open.data(), &600u32.to_le_bytes());
        let mut got = Vec::new();
        let mut seq = 2;
        for op in [Opcode::ReadFile, Opcode::BurstReadFile] {
            got.clear();
            loop {
                let answer = send(
                    &mut server,
                    seq,
                    read_at(open.session, op, got.len() as u32, 0),
                );
                seq += 2;
                if answer.nak_code() == Some(ErrorCode::Eof) {
                    break;
                }
                assert_eq!(answer.opcode, Opcode::Ack as u8);
                assert_eq!(answer.req_opcode, op as u8);
                assert_eq!(answer.offset as usize, got.len());
                assert_eq!(answer.burst_complete, u8::from(op == Opcode::BurstReadFile));
                assert!(answer.size > 0);
                got.extend_from_slice(answer.data());
            }
            assert_eq!(&got[..], FILES[1].contents);
        }
        // A smaller read where the client asks for one; the last bytes; the end exactly.
        let answer = send(
            &mut server,
            seq,
            read_at(open.session, Opcode::ReadFile, 10, 5),
        );
        assert_eq!((answer.offset, answer.size), (10, 5));
        let answer = send(
            &mut server,
            seq + 2,
            read_at(open.session, Opcode::ReadFile, 598, 0),
        );
        assert_eq!(answer.data(), &[7, 7]);
        let answer = send(
            &mut server,
            seq + 4,
            read_at(open.session, Opcode::ReadFile, 600, 0),
        );
        assert_eq!(answer.nak_code(), Some(ErrorCode::Eof));
        let mut terminate = FtpMessage::command(0, Opcode::TerminateSession);
        terminate.session = open.session;
        assert_eq!(
            send(&mut server, seq + 6, terminate).opcode,
            Opcode::Ack as u8
        );
        // The session is gone.
        let answer = send(
            &mut server,
            seq + 8,
            read_at(open.session, Opcode::ReadFile, 0, 0),
        );
        assert_eq!(answer.nak_code(), Some(ErrorCode::InvalidSession));
    }

    #[test]
    fn unknown_files_hostile_offsets_and_wrong_sessions_are_refused() {
        let mut server = Server::<64>::new();
        assert_eq!(
            open_ro(&mut server, 0, b"/etc/passwd").nak_code(),
            Some(ErrorCode::FileNotFound)
        );
        assert_eq!(
            open_ro(&mut server, 2, PAYLOAD_PATH.as_bytes()).nak_code(),
            Some(ErrorCode::FileProtected)
        );
        // Without the leading slash, NUL-terminated.
        let open = open_ro(&mut server, 4, b"comp_general.json\0junk");
        assert_eq!(open.opcode, Opcode::Ack as u8);
        assert_eq!(open.data(), &(FILES[0].contents.len() as u32).to_le_bytes());
        let s = open.session;
        for (i, offset) in [u32::MAX, u32::MAX - 3, 1 << 31, 14]
            .into_iter()
            .enumerate()
        {
            let answer = send(
                &mut server,
                6 + 2 * i as u16,
                read_at(s, Opcode::BurstReadFile, offset, 255),
            );
            assert_eq!(answer.nak_code(), Some(ErrorCode::Eof), "offset {offset}");
        }
        // A size past DATA_LEN reads at most DATA_LEN (here: the file's 14 bytes).
        let answer = send(&mut server, 20, read_at(s, Opcode::ReadFile, 0, 255));
        assert_eq!(answer.data(), FILES[0].contents);
        let answer = send(
            &mut server,
            22,
            read_at(s.wrapping_add(1), Opcode::ReadFile, 0, 0),
        );
        assert_eq!(answer.nak_code(), Some(ErrorCode::InvalidSession));
        // A read session takes no writes; the read-only files take no CreateFile.
        let mut write = FtpMessage::command(0, Opcode::WriteFile);
        write.session = s;
        write.set_data(b"x");
        assert_eq!(
            send(&mut server, 24, write).nak_code(),
            Some(ErrorCode::InvalidSession)
        );
        // A second open replaces the read session (a client that lost it starts again), here
        // under another session id.
        let mut open = FtpMessage::command(26, Opcode::OpenFileRO);
        open.session = s.wrapping_add(1);
        open.set_data(b"/big.bin");
        let again = send(&mut server, 26, open);
        assert_eq!(again.opcode, Opcode::Ack as u8);
        assert_eq!(again.session, s.wrapping_add(1));
        assert_eq!(
            send(&mut server, 28, read_at(s, Opcode::ReadFile, 0, 0)).nak_code(),
            Some(ErrorCode::InvalidSession)
        );
        let mut reset = FtpMessage::command(0, Opcode::ResetSessions);
        reset.session = 0;
        send(&mut server, 30, reset);
        let mut create = FtpMessage::command(0, Opcode::CreateFile);
        create.set_data(b"/comp_general.json");
        assert_eq!(
            send(&mut server, 32, create).nak_code(),
            Some(ErrorCode::FileProtected)
        );
    }

    #[test]
    fn an_upload_still_works_beside_the_read_only_files_and_blocks_reading() {
        let mut server = Server::<1024>::new();
        let mut create = FtpMessage::command(0, Opcode::CreateFile);
        create.set_data(PAYLOAD_PATH.as_bytes());
        let (ok, _) = server.handle_with(&create, &FILES);
        assert_eq!(ok.opcode, Opcode::Ack as u8);
        assert_eq!(
            open_ro(&mut server, 2, b"/big.bin").nak_code(),
            Some(ErrorCode::NoSessionsAvailable),
            "the upload's session stays"
        );
        let mut terminate = FtpMessage::command(4, Opcode::TerminateSession);
        terminate.session = ok.session;
        let (_, event) = server.handle_with(&terminate, &FILES);
        assert_eq!(event, FileEvent::Written { len: 0 });
        assert_eq!(
            open_ro(&mut server, 6, b"/big.bin").opcode,
            Opcode::Ack as u8
        );
    }

    proptest::proptest! {
        #[test]
        fn any_command_is_answered_without_panicking(payload in proptest::collection::vec(proptest::prelude::any::<u8>(), PAYLOAD_LEN)) {
            let mut p = [0u8; PAYLOAD_LEN];
            p.copy_from_slice(&payload);
            let mut server = Server::<512>::new();
            let request = FtpMessage::from_payload(&p);
            let (answer, _) = server.handle_with(&request, &FILES);
            proptest::prop_assert_eq!(answer.seq, request.seq.wrapping_add(1));
            // With a read session open, any read is answered too.
            let mut open = FtpMessage::command(request.seq.wrapping_add(7), Opcode::OpenFileRO);
            open.set_data(b"/big.bin");
            let (opened, _) = server.handle_with(&open, &FILES);
            let mut read = request;
            read.seq = open.seq.wrapping_add(3);
            read.session = opened.session;
            read.opcode = Opcode::ReadFile as u8;
            let (answer, _) = server.handle_with(&read, &FILES);
            proptest::prop_assert!(usize::from(answer.size) <= DATA_LEN);
        }
    }
}
