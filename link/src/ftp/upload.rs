//! The ground side of writing one file over MAVLink FTP ([`Upload`]): `ResetSessions`,
//! `CreateFile`, the `WriteFile`s, `TerminateSession`; a command whose answer does not come in
//! time is sent again unchanged.

use super::{DATA_LEN, ErrorCode, FtpMessage, Opcode};

/// Why an upload failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UploadError {
    /// The vehicle refused a step.
    Refused {
        /// The step's opcode.
        step: Opcode,
        /// The vehicle's error code (`None` if it sent an unknown one).
        code: Option<ErrorCode>,
    },
}

impl core::fmt::Display for UploadError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Refused { step, code } => {
                write!(f, "the vehicle refused FTP {step:?}")?;
                match code {
                    Some(c) => write!(f, " ({c:?})"),
                    None => write!(f, " (unknown error code)"),
                }
            }
        }
    }
}

/// The ground side of writing one file: which command to send next, and what to make of the
/// answers. Resend [`Upload::current`] unchanged when an answer does not come in time.
pub struct Upload<'a> {
    path: &'a str,
    contents: &'a [u8],
    seq: u16,
    step: Opcode,
    session: u8,
    offset: usize,
}

/// Where an upload stands after an answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// The answer is not to the current command (a stale or foreign one): keep waiting.
    Ignored,
    /// Send [`Upload::current`] next.
    Continue,
    /// The file is written and its session closed.
    Done,
}

impl<'a> Upload<'a> {
    /// An upload of `contents` to `path`.
    pub fn new(path: &'a str, contents: &'a [u8]) -> Self {
        Self {
            path,
            contents,
            seq: 0,
            step: Opcode::ResetSessions,
            session: 0,
            offset: 0,
        }
    }

    /// The command to send now.
    pub fn current(&self) -> FtpMessage {
        let mut m = FtpMessage::command(self.seq, self.step);
        m.session = self.session;
        match self.step {
            Opcode::CreateFile => m.set_data(self.path.as_bytes()),
            Opcode::WriteFile => {
                let end = (self.offset + DATA_LEN).min(self.contents.len());
                m.offset = self.offset as u32;
                m.set_data(&self.contents[self.offset..end]);
            }
            _ => {}
        }
        m
    }

    /// Takes the vehicle's answer.
    pub fn on_answer(&mut self, answer: &FtpMessage) -> Result<Progress, UploadError> {
        if answer.seq != self.seq.wrapping_add(1) || answer.req_opcode != self.step as u8 {
            return Ok(Progress::Ignored);
        }
        if answer.opcode != Opcode::Ack as u8 {
            return Err(UploadError::Refused {
                step: self.step,
                code: answer.nak_code(),
            });
        }
        self.seq = self.seq.wrapping_add(2);
        self.step = match self.step {
            Opcode::ResetSessions => Opcode::CreateFile,
            Opcode::CreateFile => {
                self.session = answer.session;
                Opcode::WriteFile
            }
            Opcode::WriteFile => {
                self.offset = (self.offset + DATA_LEN).min(self.contents.len());
                if self.offset < self.contents.len() {
                    Opcode::WriteFile
                } else {
                    Opcode::TerminateSession
                }
            }
            _ => return Ok(Progress::Done),
        };
        Ok(Progress::Continue)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ftp::{FileEvent, PAYLOAD_PATH, Server};
    use std::vec::Vec;

    fn upload_through<const N: usize>(
        server: &mut Server<N>,
        contents: &[u8],
    ) -> Result<Vec<FileEvent>, UploadError> {
        let mut up = Upload::new(PAYLOAD_PATH, contents);
        let mut events = Vec::new();
        for _ in 0..100 {
            let request = up.current();
            // Go through the wire format both ways.
            let request = FtpMessage::from_payload(&request.to_payload());
            let (answer, event) = server.handle(&request);
            events.push(event);
            if up.on_answer(&FtpMessage::from_payload(&answer.to_payload()))? == Progress::Done {
                return Ok(events);
            }
        }
        panic!("upload did not finish");
    }

    #[test]
    fn a_file_of_several_chunks_arrives_whole() {
        let contents: Vec<u8> = (0..700u32).map(|i| (i * 7 % 251) as u8).collect();
        let mut server = Server::<1024>::new();
        let events = upload_through(&mut server, &contents).expect("accepted");
        assert_eq!(server.file(), &contents[..]);
        assert_eq!(events.last(), Some(&FileEvent::Written { len: 700 }));
        assert_eq!(
            events.iter().filter(|e| **e != FileEvent::None).count(),
            1,
            "one completed file"
        );
    }

    #[test]
    fn a_second_upload_replaces_the_first() {
        let mut server = Server::<1024>::new();
        upload_through(&mut server, &[1u8; 500]).unwrap();
        upload_through(&mut server, &[2u8; 10]).unwrap();
        assert_eq!(server.file(), &[2u8; 10]);
    }

    #[test]
    fn a_refusal_ends_the_upload_naming_the_step() {
        let mut server = Server::<16>::new();
        assert_eq!(
            upload_through(&mut server, &[0u8; 100]),
            Err(UploadError::Refused {
                step: Opcode::WriteFile,
                code: Some(ErrorCode::Fail)
            })
        );
    }
}
