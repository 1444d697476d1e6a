//! MAVLink's log protocol, vehicle side (docs/formats.md#downloading-the-logs): the flight logs
//! in a [`LogStorage`] listed, downloaded and erased as PX4 and ArduPilot serve theirs, so
//! QGroundControl's log download, MAVProxy's `log` module and pymavlink fetch them.
//!
//! | request | answer |
//! |---|---|
//! | `LOG_REQUEST_LIST` (start, end) | a `LOG_ENTRY` for each id from start to end, clamped to the logs kept (ids from 0, oldest first); with no logs, one `LOG_ENTRY` with `num_logs` 0 and id 0 |
//! | `LOG_REQUEST_DATA` (id, ofs, count) | `LOG_DATA` of up to 90 bytes at ofs, ofs + 90, ... up to ofs + count or the log's end (count `0xFFFFFFFF`: to the end); a request that reaches past the end (or asks for nothing) ends with a `LOG_DATA` of count 0 unless its last one was short, so one from or past the end is answered by that one alone |
//! | `LOG_REQUEST_DATA` for a log that is not kept | no `LOG_DATA`, as PX4 (and what was being sent goes on); a notice for people |
//! | `LOG_REQUEST_END` | stops sending |
//! | `LOG_ERASE` | every log erased, unless the caller says why not (armed, a log being written): then a notice |
//!
//! Each new request replaces the one being answered. The service does no I/O but the storage's:
//! [`LogService::next`] says what to send next, and the caller decides how many a turn.

use crate::msg::{LOG_DATA_DATA, LOG_ENTRY_DATA, LOG_REQUEST_DATA_DATA, LOG_REQUEST_LIST_DATA};
use flight_log::keeper::LogStorage;

/// Bytes of log a `LOG_DATA` carries at most.
pub const DATA_LEN: usize = 90;

/// A `LOG_REQUEST_DATA` count meaning "to the end of the log" (MAVProxy asks so).
pub const TO_THE_END: u32 = u32::MAX;

/// The one `LOG_ENTRY` that answers a list when no logs are kept (`num_logs` 0, id 0), as
/// QGroundControl and MAVProxy expect.
pub fn no_logs_entry() -> LOG_ENTRY_DATA {
    LOG_ENTRY_DATA {
        time_utc: 0,
        size: 0,
        id: 0,
        num_logs: 0,
        last_log_num: 0,
    }
}

/// A log-protocol request addressed to the vehicle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogRequest {
    /// `LOG_REQUEST_LIST`: the entries of ids `start..=end`.
    List {
        /// First id.
        start: u16,
        /// Last id (`0xFFFF`: the last log).
        end: u16,
    },
    /// `LOG_REQUEST_DATA`: `count` bytes of log `id` from `ofs`.
    Data {
        /// The log.
        id: u16,
        /// First byte.
        ofs: u32,
        /// How many bytes ([`TO_THE_END`]: all from `ofs`).
        count: u32,
    },
    /// `LOG_REQUEST_END`: stop sending.
    End,
    /// `LOG_ERASE`: erase every log.
    Erase,
}

impl LogRequest {
    /// The request a `LOG_REQUEST_LIST` makes.
    pub fn from_list(m: &LOG_REQUEST_LIST_DATA) -> Self {
        Self::List {
            start: m.start,
            end: m.end,
        }
    }

    /// The request a `LOG_REQUEST_DATA` makes.
    pub fn from_data(m: &LOG_REQUEST_DATA_DATA) -> Self {
        Self::Data {
            id: m.id,
            ofs: m.ofs,
            count: m.count,
        }
    }
}

/// A message to send.
#[derive(Clone, Debug, PartialEq)]
pub enum LogReply {
    /// A `LOG_ENTRY`.
    Entry(LOG_ENTRY_DATA),
    /// A `LOG_DATA`.
    Data(LOG_DATA_DATA),
}

/// What people should hear of a request (a `STATUSTEXT`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogNotice {
    /// A download of a log that is not kept.
    NoSuchLog {
        /// The id asked for.
        id: u16,
        /// How many logs are kept.
        count: u16,
    },
    /// `LOG_ERASE` refused, for this reason.
    EraseRefused(&'static str),
    /// Every log was erased: this many.
    Erased(u16),
}

impl core::fmt::Display for LogNotice {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::NoSuchLog { id, count: 0 } => {
                write!(f, "log download refused: no log {id}, no logs are kept")
            }
            Self::NoSuchLog { id, count } => write!(
                f,
                "log download refused: no log {id} (the logs are 0 to {})",
                count - 1
            ),
            Self::EraseRefused(why) => write!(f, "log erase refused: {why}"),
            Self::Erased(1) => f.write_str("flight logs erased: 1 log"),
            Self::Erased(n) => write!(f, "flight logs erased: {n} logs"),
        }
    }
}

/// What is being sent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Sending {
    Nothing,
    /// `LOG_ENTRY`s: `next` to `last`, of `count` logs.
    Entries {
        next: u16,
        last: u16,
        count: u16,
    },
    /// `LOG_DATA` of log `id` from `ofs` to `end`; then, if `empty_after`, one of count 0 at
    /// `end` (unless the last was short).
    Data {
        id: u16,
        ofs: u32,
        end: u32,
        empty_after: bool,
    },
}

/// The log service: the request being answered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LogService {
    sending: Sending,
}

impl Default for LogService {
    fn default() -> Self {
        Self::new()
    }
}

impl LogService {
    /// Answering nothing.
    pub const fn new() -> Self {
        Self {
            sending: Sending::Nothing,
        }
    }

    /// Whether there is something to send ([`Self::next`] gives it).
    pub fn sending(&self) -> bool {
        self.sending != Sending::Nothing
    }

    /// Takes `request`; `erase_refused` says why no log may be erased now (the vehicle is
    /// armed, a log is being written). Returns what people should hear of it, or the
    /// storage's error (then nothing is sent for it).
    pub fn handle<S: LogStorage>(
        &mut self,
        request: LogRequest,
        storage: &mut S,
        erase_refused: Option<&'static str>,
    ) -> Result<Option<LogNotice>, S::Error> {
        match request {
            LogRequest::List { start, end } => {
                self.sending = Sending::Nothing;
                let count = storage.count()?;
                let last = end.min(count.saturating_sub(1));
                self.sending = Sending::Entries {
                    next: start.min(last),
                    last,
                    count,
                };
                Ok(None)
            }
            LogRequest::Data { id, ofs, count } => {
                let kept = storage.count()?;
                if id >= kept {
                    // As PX4: not answered, and what was being sent goes on.
                    return Ok(Some(LogNotice::NoSuchLog { id, count: kept }));
                }
                self.sending = Sending::Nothing;
                let size = storage.size(id)?;
                let asked_end = ofs.saturating_add(count);
                self.sending = Sending::Data {
                    id,
                    ofs,
                    end: asked_end.min(size).max(ofs),
                    empty_after: count == 0 || asked_end > size,
                };
                Ok(None)
            }
            LogRequest::End => {
                self.sending = Sending::Nothing;
                Ok(None)
            }
            LogRequest::Erase => {
                if let Some(why) = erase_refused {
                    return Ok(Some(LogNotice::EraseRefused(why)));
                }
                self.sending = Sending::Nothing;
                let count = storage.count()?;
                storage.erase_all()?;
                Ok(Some(LogNotice::Erased(count)))
            }
        }
    }

    /// The next message to send, if any; a storage error ends the answer.
    pub fn next<S: LogStorage>(&mut self, storage: &mut S) -> Result<Option<LogReply>, S::Error> {
        let reply = match self.sending {
            Sending::Nothing => return Ok(None),
            Sending::Entries { next, last, count } => {
                self.sending = if next < last {
                    Sending::Entries {
                        next: next + 1,
                        last,
                        count,
                    }
                } else {
                    Sending::Nothing
                };
                if count == 0 {
                    return Ok(Some(LogReply::Entry(no_logs_entry())));
                }
                let size = storage.size(next).inspect_err(|_| self.stop())?;
                LogReply::Entry(LOG_ENTRY_DATA {
                    time_utc: 0,
                    size,
                    id: next,
                    num_logs: count,
                    last_log_num: count.saturating_sub(1),
                })
            }
            Sending::Data {
                id,
                ofs,
                end,
                empty_after,
            } => {
                let mut data = [0u8; DATA_LEN];
                let want = (end - ofs).min(DATA_LEN as u32) as usize;
                let n = if want == 0 {
                    0
                } else {
                    let got = storage
                        .read(id, ofs, &mut data[..want])
                        .inspect_err(|_| self.stop())?;
                    got.min(want)
                };
                let next_ofs = ofs + n as u32;
                self.sending = if n == DATA_LEN && (next_ofs < end || empty_after) {
                    Sending::Data {
                        id,
                        ofs: next_ofs,
                        end,
                        empty_after,
                    }
                } else {
                    // The last: short (the log's end, or the storage's), or empty.
                    Sending::Nothing
                };
                LogReply::Data(LOG_DATA_DATA {
                    ofs,
                    id,
                    count: n as u8,
                    data,
                })
            }
        };
        Ok(Some(reply))
    }

    fn stop(&mut self) {
        self.sending = Sending::Nothing;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flight_log::memory::MemoryLogs;
    use std::vec::Vec;

    /// Logs of these sizes, each byte of log `i` at offset `o` being `(i * 7 + o) % 251`.
    fn logs(sizes: &[usize]) -> MemoryLogs {
        let mut storage = MemoryLogs::default();
        for (i, &size) in sizes.iter().enumerate() {
            storage
                .logs
                .push((0..size).map(|o| ((i * 7 + o) % 251) as u8).collect());
        }
        storage
    }

    /// Everything the service sends for `request`, with what people hear.
    fn answer(
        service: &mut LogService,
        storage: &mut MemoryLogs,
        request: LogRequest,
    ) -> (Vec<LogReply>, Option<LogNotice>) {
        let notice = service
            .handle(request, storage, None)
            .expect("the storage works");
        (drain(service, storage), notice)
    }

    fn drain(service: &mut LogService, storage: &mut MemoryLogs) -> Vec<LogReply> {
        let mut out = Vec::new();
        while let Some(reply) = service.next(storage).expect("the storage works") {
            out.push(reply);
            assert!(out.len() < 100_000, "the answer ends");
        }
        assert!(!service.sending());
        out
    }

    fn data(replies: &[LogReply]) -> Vec<&LOG_DATA_DATA> {
        replies
            .iter()
            .map(|r| match r {
                LogReply::Data(d) => d,
                LogReply::Entry(e) => panic!("a LOG_ENTRY in a download: {e:?}"),
            })
            .collect()
    }

    /// The ids a list of `start..=end` answers.
    fn listed(
        service: &mut LogService,
        storage: &mut MemoryLogs,
        start: u16,
        end: u16,
    ) -> Vec<u16> {
        let (replies, _) = answer(service, storage, LogRequest::List { start, end });
        entries(&replies).iter().map(|e| e.id).collect()
    }

    fn entries(replies: &[LogReply]) -> Vec<&LOG_ENTRY_DATA> {
        replies
            .iter()
            .map(|r| match r {
                LogReply::Entry(e) => e,
                LogReply::Data(d) => panic!("a LOG_DATA in a listing: id {}", d.id),
            })
            .collect()
    }

    /// The bytes the messages carry, checking each is at the offset the last one ended.
    fn joined(messages: &[&LOG_DATA_DATA], from: u32) -> Vec<u8> {
        let mut bytes = Vec::new();
        let mut at = from;
        for m in messages {
            assert_eq!(m.ofs, at, "offsets follow each other");
            assert_eq!((m.ofs - from) % DATA_LEN as u32, 0, "a multiple of 90 on");
            bytes.extend_from_slice(&m.data[..usize::from(m.count)]);
            at += u32::from(m.count);
        }
        bytes
    }

    #[test]
    fn the_list_has_an_entry_per_log_with_its_size() {
        let mut storage = logs(&[1000, 0, 90]);
        let mut service = LogService::new();
        let (replies, notice) = answer(
            &mut service,
            &mut storage,
            LogRequest::List {
                start: 0,
                end: 0xFFFF,
            },
        );
        assert_eq!(notice, None);
        let got: Vec<(u16, u16, u16, u32, u32)> = entries(&replies)
            .iter()
            .map(|e| (e.id, e.num_logs, e.last_log_num, e.size, e.time_utc))
            .collect();
        assert_eq!(got, [(0, 3, 2, 1000, 0), (1, 3, 2, 0, 0), (2, 3, 2, 90, 0)]);
        // A part of the list, and a range past the logs clamped to the last.
        assert_eq!(listed(&mut service, &mut storage, 1, 1), [1]);
        assert_eq!(listed(&mut service, &mut storage, 9, 40), [2]);
        // Start after end: the one entry at end.
        assert_eq!(listed(&mut service, &mut storage, 2, 0), [0]);
    }

    #[test]
    fn with_no_logs_the_list_is_one_entry_saying_so() {
        let mut storage = logs(&[]);
        let (replies, _) = answer(
            &mut LogService::new(),
            &mut storage,
            LogRequest::List {
                start: 0,
                end: 0xFFFF,
            },
        );
        let got = entries(&replies);
        assert_eq!(got.len(), 1);
        assert_eq!(
            (got[0].id, got[0].num_logs, got[0].last_log_num, got[0].size),
            (0, 0, 0, 0)
        );
    }

    #[test]
    fn a_download_to_the_end_is_the_log_in_90_byte_messages() {
        // 1000 = 11 * 90 + 10: the last one short ends it.
        let mut storage = logs(&[1000]);
        let mut service = LogService::new();
        let (replies, notice) = answer(
            &mut service,
            &mut storage,
            LogRequest::Data {
                id: 0,
                ofs: 0,
                count: TO_THE_END,
            },
        );
        assert_eq!(notice, None);
        let messages = data(&replies);
        assert_eq!(messages.len(), 12);
        assert_eq!(messages[11].count, 10);
        assert_eq!(joined(&messages, 0), storage.logs[0]);
        // A log of whole messages: an empty one at its end says it is complete.
        let mut storage = logs(&[0, 180]);
        let (replies, _) = answer(
            &mut service,
            &mut storage,
            LogRequest::Data {
                id: 1,
                ofs: 0,
                count: TO_THE_END,
            },
        );
        let messages = data(&replies);
        assert_eq!(
            messages
                .iter()
                .map(|m| (m.ofs, m.count))
                .collect::<Vec<_>>(),
            [(0, 90), (90, 90), (180, 0)]
        );
        assert_eq!(joined(&messages, 0), storage.logs[1]);
        // An empty log: one empty message.
        let (replies, _) = answer(
            &mut service,
            &mut storage,
            LogRequest::Data {
                id: 0,
                ofs: 0,
                count: TO_THE_END,
            },
        );
        assert_eq!(
            data(&replies)
                .iter()
                .map(|m| (m.ofs, m.count))
                .collect::<Vec<_>>(),
            [(0, 0)]
        );
    }

    #[test]
    fn a_block_is_what_was_asked_from_where_it_was_asked() {
        let mut storage = logs(&[1000]);
        let mut service = LogService::new();
        // A block inside the log, as QGroundControl asks: exactly its bytes, nothing after.
        let (replies, _) = answer(
            &mut service,
            &mut storage,
            LogRequest::Data {
                id: 0,
                ofs: 100,
                count: 200,
            },
        );
        let messages = data(&replies);
        assert_eq!(
            messages
                .iter()
                .map(|m| (m.ofs, m.count))
                .collect::<Vec<_>>(),
            [(100, 90), (190, 90), (280, 20)]
        );
        assert_eq!(joined(&messages, 100), storage.logs[0][100..300]);
        // A block reaching past the end: up to the end; short, so nothing more.
        let (replies, _) = answer(
            &mut service,
            &mut storage,
            LogRequest::Data {
                id: 0,
                ofs: 950,
                count: 900,
            },
        );
        let messages = data(&replies);
        assert_eq!(
            messages
                .iter()
                .map(|m| (m.ofs, m.count))
                .collect::<Vec<_>>(),
            [(950, 50)]
        );
        assert_eq!(joined(&messages, 950), storage.logs[0][950..]);
        // A block that ends at the end exactly: no empty message (none was asked past it).
        let (replies, _) = answer(
            &mut service,
            &mut storage,
            LogRequest::Data {
                id: 0,
                ofs: 820,
                count: 180,
            },
        );
        assert_eq!(
            data(&replies)
                .iter()
                .map(|m| (m.ofs, m.count))
                .collect::<Vec<_>>(),
            [(820, 90), (910, 90)]
        );
    }

    #[test]
    fn past_the_end_or_nothing_asked_is_one_empty_message() {
        let mut storage = logs(&[1000]);
        let mut service = LogService::new();
        for (ofs, count) in [
            (1000, TO_THE_END),
            (1000, 90),
            (5000, 10),
            (u32::MAX, u32::MAX),
            (u32::MAX - 5, 90),
            (10, 0),
        ] {
            let (replies, notice) = answer(
                &mut service,
                &mut storage,
                LogRequest::Data { id: 0, ofs, count },
            );
            assert_eq!(notice, None);
            assert_eq!(
                data(&replies)
                    .iter()
                    .map(|m| (m.ofs, m.count))
                    .collect::<Vec<_>>(),
                [(ofs, 0)],
                "ofs {ofs} count {count}"
            );
        }
    }

    #[test]
    fn a_log_that_is_not_kept_is_not_answered_and_what_was_being_sent_goes_on() {
        let mut storage = logs(&[1000]);
        let mut service = LogService::new();
        service
            .handle(
                LogRequest::Data {
                    id: 0,
                    ofs: 0,
                    count: TO_THE_END,
                },
                &mut storage,
                None,
            )
            .expect("works");
        let first = service.next(&mut storage).expect("works");
        assert!(matches!(first, Some(LogReply::Data(ref d)) if d.ofs == 0));
        for id in [1, 7, 0xFFFF] {
            let notice = service
                .handle(
                    LogRequest::Data {
                        id,
                        ofs: 0,
                        count: TO_THE_END,
                    },
                    &mut storage,
                    None,
                )
                .expect("works");
            assert_eq!(notice, Some(LogNotice::NoSuchLog { id, count: 1 }));
        }
        let rest = drain(&mut service, &mut storage);
        let mut all = data(core::slice::from_ref(first.as_ref().expect("one")));
        all.extend(data(&rest));
        assert_eq!(joined(&all, 0), storage.logs[0]);
        let mut none = logs(&[]);
        let (replies, notice) = answer(
            &mut service,
            &mut none,
            LogRequest::Data {
                id: 0xFFFF,
                ofs: u32::MAX,
                count: 0,
            },
        );
        assert!(replies.is_empty());
        assert_eq!(
            notice.map(|n| std::format!("{n}")),
            Some("log download refused: no log 65535, no logs are kept".into())
        );
    }

    #[test]
    fn a_new_request_replaces_the_old_and_the_end_stops_it() {
        let mut storage = logs(&[1000, 500]);
        let mut service = LogService::new();
        let data0 = LogRequest::Data {
            id: 0,
            ofs: 0,
            count: TO_THE_END,
        };
        service.handle(data0, &mut storage, None).expect("works");
        let _ = service.next(&mut storage);
        service
            .handle(
                LogRequest::Data {
                    id: 1,
                    ofs: 450,
                    count: TO_THE_END,
                },
                &mut storage,
                None,
            )
            .expect("works");
        let messages = drain(&mut service, &mut storage);
        assert_eq!(
            data(&messages)
                .iter()
                .map(|m| (m.id, m.ofs, m.count))
                .collect::<Vec<_>>(),
            [(1, 450, 50)]
        );
        service.handle(data0, &mut storage, None).expect("works");
        let _ = service.next(&mut storage);
        service
            .handle(
                LogRequest::List {
                    start: 0,
                    end: 0xFFFF,
                },
                &mut storage,
                None,
            )
            .expect("works");
        assert_eq!(entries(&drain(&mut service, &mut storage)).len(), 2);
        service.handle(data0, &mut storage, None).expect("works");
        assert!(service.sending());
        service
            .handle(LogRequest::End, &mut storage, None)
            .expect("works");
        assert!(!service.sending());
        assert_eq!(service.next(&mut storage), Ok(None));
    }

    #[test]
    fn erase_empties_the_storage_unless_refused() {
        let mut storage = logs(&[1000, 500]);
        let mut service = LogService::new();
        let notice = service
            .handle(
                LogRequest::Erase,
                &mut storage,
                Some("the vehicle is armed"),
            )
            .expect("works");
        assert_eq!(
            notice.map(|n| std::format!("{n}")),
            Some("log erase refused: the vehicle is armed".into())
        );
        assert_eq!(storage.logs.len(), 2);
        service
            .handle(
                LogRequest::Data {
                    id: 0,
                    ofs: 0,
                    count: TO_THE_END,
                },
                &mut storage,
                None,
            )
            .expect("works");
        let notice = service
            .handle(LogRequest::Erase, &mut storage, None)
            .expect("works");
        assert_eq!(notice, Some(LogNotice::Erased(2)));
        assert!(storage.logs.is_empty());
        assert!(!service.sending(), "the download stopped with its log");
        let (replies, _) = answer(
            &mut service,
            &mut storage,
            LogRequest::List {
                start: 0,
                end: 0xFFFF,
            },
        );
        assert_eq!(entries(&replies)[0].num_logs, 0);
    }

    #[test]
    fn a_storage_that_fails_ends_the_answer() {
        struct Failing;
        impl LogStorage for Failing {
            type Error = &'static str;
            fn count(&mut self) -> Result<u16, Self::Error> {
                Ok(2)
            }
            fn size(&mut self, _: u16) -> Result<u32, Self::Error> {
                Ok(1000)
            }
            fn create(&mut self) -> Result<u16, Self::Error> {
                Err("read only")
            }
            fn append(&mut self, _: &[u8]) -> Result<(), Self::Error> {
                Err("read only")
            }
            fn close(&mut self) -> Result<(), Self::Error> {
                Ok(())
            }
            fn read(&mut self, _: u16, _: u32, _: &mut [u8]) -> Result<usize, Self::Error> {
                Err("card removed")
            }
            fn erase_all(&mut self) -> Result<(), Self::Error> {
                Err("card removed")
            }
        }
        let mut service = LogService::new();
        service
            .handle(
                LogRequest::Data {
                    id: 1,
                    ofs: 0,
                    count: TO_THE_END,
                },
                &mut Failing,
                None,
            )
            .expect("the request is taken");
        assert_eq!(service.next(&mut Failing), Err("card removed"));
        assert!(!service.sending());
        assert_eq!(
            service.handle(LogRequest::Erase, &mut Failing, None),
            Err("card removed")
        );
    }
}
