//! The log's bytes between the control step and the task that stores them: the control step
//! builds each entry's ULog message in place in a window of a byte ring that never makes it
//! wait ([`LogRing`], [`StepWindow`]) and hands over a step's messages together; a message that finds no room is dropped and counted, and the first
//! message that fits after a loss is preceded by a ULog dropout saying how long the loss
//! lasted. Two marker messages, never written to a file, tell the storing side where a
//! mission's log starts and ends ([`Piece`], read back by [`Splitter`]).

use super::recorder::TEXT_CAPACITY;
use super::topics::{MESSAGE_BYTES, Record};
use crate::ulog::{LogLevel, MESSAGE_CAPACITY, Message, Packer};
use heapless::Vec;

/// Message type of the start marker (payload: the start time, us, `u64`).
const START: u8 = 0x01;
/// Message type of the end marker (no payload).
const END: u8 = 0x02;

/// Memory the writer builds messages in, in place: whole messages or nothing, never waiting.
pub trait LogSpace {
    /// The free bytes, contiguous, where the next message is built (no more than the ring
    /// behind has room for).
    fn space(&mut self) -> &mut [u8];
    /// Keeps the first `n` bytes of [`Self::space`] as written.
    fn commit(&mut self, n: usize);
}

/// The ring the control step writes to, never waiting: each step gets a window of the ring's
/// own memory, its messages are built there in place (nothing cleared or copied) and the
/// step hands over what it wrote when it ends.
pub trait LogRing {
    /// The step's window: free bytes, contiguous, at most [`super::session::STEP_BYTES`]
    /// (empty when the ring is full, or keeps no log).
    fn step_space(&mut self) -> &mut [u8];
    /// Hands the first `n` bytes of the step's window to the storing side; `ended`: the
    /// mission's log ended in this step (so what is held goes to storage now).
    fn commit_step(&mut self, n: usize, ended: bool);
}

/// A step's window of the ring, as the writer fills it.
#[derive(Debug)]
pub struct StepWindow<'a> {
    bytes: &'a mut [u8],
    len: usize,
}

impl<'a> StepWindow<'a> {
    /// An empty window over `bytes`.
    pub fn new(bytes: &'a mut [u8]) -> Self {
        Self { bytes, len: 0 }
    }

    /// Bytes written so far.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether nothing was written.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

impl LogSpace for StepWindow<'_> {
    #[inline]
    fn space(&mut self) -> &mut [u8] {
        let len = self.len.min(self.bytes.len());
        &mut self.bytes[len..]
    }
    #[inline]
    fn commit(&mut self, n: usize) {
        self.len = (self.len + n).min(self.bytes.len());
    }
}

/// No ring: nothing is ever logged (a build or a test that keeps no log).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoRing;

impl LogRing for NoRing {
    fn step_space(&mut self) -> &mut [u8] {
        &mut []
    }
    fn commit_step(&mut self, _: usize, _: bool) {}
}

/// The control step's side: what it wrote and lost.
#[derive(Clone, Debug, Default)]
pub struct LogWriter {
    /// A mission's log is being written.
    open: bool,
    /// When the loss under way began, us.
    lost_since: Option<u64>,
    /// Messages lost since the log started.
    lost: u32,
}

impl LogWriter {
    /// Nothing written yet.
    pub const fn new() -> Self {
        Self {
            open: false,
            lost_since: None,
            lost: 0,
        }
    }

    /// Whether a mission's log is open.
    pub fn is_open(&self) -> bool {
        self.open
    }

    /// Messages lost since the log started (the ring was full).
    pub fn lost(&self) -> u32 {
        self.lost
    }

    /// Starts a mission's log at `time_us`. The start marker is a few bytes; when even they
    /// find no room the log does not start (the next step tries again): returns whether it did.
    pub fn start(&mut self, out: &mut impl LogSpace, time_us: u64) -> bool {
        let Some(marker) = out.space().get_mut(..11) else {
            return false;
        };
        marker[..3].copy_from_slice(&[8, 0, START]);
        marker[3..].copy_from_slice(&time_us.to_le_bytes());
        out.commit(11);
        self.open = true;
        self.lost_since = None;
        self.lost = 0;
        true
    }

    /// Ends the mission's log; returns whether the end marker went in (when it did not, the
    /// next step tries again and the log stays open until then).
    pub fn end(&mut self, out: &mut impl LogSpace) -> bool {
        if !self.open {
            return true;
        }
        let Some(marker) = out.space().get_mut(..3) else {
            return false;
        };
        marker.copy_from_slice(&[0, 0, END]);
        out.commit(3);
        self.open = false;
        true
    }

    /// Writes one record at `now_us`, built in place (nothing while no log is open).
    #[inline]
    pub fn record(&mut self, out: &mut impl LogSpace, record: &Record, now_us: u64) {
        if !self.open {
            return;
        }
        let Some((at, space)) = self.after_dropout(out, MESSAGE_BYTES, now_us) else {
            return;
        };
        let window: Option<&mut [u8; MESSAGE_BYTES]> = space
            .get_mut(at..at + MESSAGE_BYTES)
            .and_then(|w| w.try_into().ok());
        if let Some(window) = window {
            let n = record.write_message(window);
            out.commit(at + n);
        }
    }

    /// Writes one logged string at `now_us` (cut to [`TEXT_CAPACITY`] bytes; nothing while no
    /// log is open).
    pub fn text(
        &mut self,
        out: &mut impl LogSpace,
        level: LogLevel,
        now_us: u64,
        text: core::fmt::Arguments<'_>,
    ) {
        match text.as_str() {
            Some(s) => self.text_str(out, level, now_us, s),
            None => self.logged(out, now_us, |window| {
                Packer::logged_string_in(window, level, now_us, text).finish()
            }),
        }
    }

    /// Writes one logged string already formatted (copied as it is, cut to [`TEXT_CAPACITY`]
    /// bytes; nothing while no log is open).
    pub fn text_str(&mut self, out: &mut impl LogSpace, level: LogLevel, now_us: u64, text: &str) {
        self.logged(out, now_us, |window| {
            Packer::logged_str_in(window, level, now_us, text).finish()
        });
    }

    /// Writes the logged string `build` makes in its window (its length).
    fn logged(
        &mut self,
        out: &mut impl LogSpace,
        now_us: u64,
        build: impl FnOnce(&mut [u8]) -> Option<usize>,
    ) {
        const MOST: usize = 12 + TEXT_CAPACITY;
        if !self.open {
            return;
        }
        let Some((at, space)) = self.after_dropout(out, MOST, now_us) else {
            return;
        };
        let Some(window) = space.get_mut(at..at + MOST) else {
            return;
        };
        if let Some(n) = build(window) {
            out.commit(at + n);
        }
    }

    /// Room for a message of at most `most` bytes, after a dropout message when messages
    /// were lost: the space and where the message goes in it. `None`, the message lost and
    /// counted, when there is no room.
    #[inline]
    fn after_dropout<'a>(
        &mut self,
        out: &'a mut impl LogSpace,
        most: usize,
        now_us: u64,
    ) -> Option<(usize, &'a mut [u8])> {
        let space = out.space();
        let Some(since) = self.lost_since else {
            if space.len() < most {
                self.lose(now_us);
                return None;
            }
            return Some((0, space));
        };
        let ms = (now_us.saturating_sub(since) / 1000).clamp(1, u64::from(u16::MAX));
        let dropout = Message::dropout(ms as u16);
        let d = dropout.as_bytes();
        if space.len() < d.len() + most {
            self.lose(now_us);
            return None;
        }
        space[..d.len()].copy_from_slice(d);
        self.lost_since = None;
        Some((d.len(), space))
    }

    /// Counts a lost message.
    fn lose(&mut self, now_us: u64) {
        self.lost += 1;
        self.lost_since.get_or_insert(now_us);
    }
}

/// What the storing side reads out of the ring.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Piece<'a> {
    /// A mission's log starts at this time, us: open a new file and write its definitions.
    Start(u64),
    /// One ULog message, whole: append it.
    Message(&'a [u8]),
    /// The mission's log ends: close the file.
    End,
}

/// Cuts the ring's bytes, read in any chunks, back into whole messages and markers.
#[derive(Clone, Debug, Default)]
pub struct Splitter {
    message: Vec<u8, MESSAGE_CAPACITY>,
    /// Bytes of a message too long to hold still to pass over (the writer makes none: only a
    /// corrupt ring has one).
    skip: usize,
}

impl Splitter {
    /// Nothing read yet.
    pub const fn new() -> Self {
        Self {
            message: Vec::new(),
            skip: 0,
        }
    }

    /// Takes `bytes` and gives each piece they complete to `each`.
    pub fn push(&mut self, mut bytes: &[u8], each: &mut impl FnMut(Piece<'_>)) {
        while !bytes.is_empty() {
            if self.skip > 0 {
                let n = self.skip.min(bytes.len());
                self.skip -= n;
                bytes = &bytes[n..];
                continue;
            }
            let wanted = if self.message.len() < 3 {
                3
            } else {
                3 + usize::from(u16::from_le_bytes([self.message[0], self.message[1]]))
            };
            if wanted > MESSAGE_CAPACITY {
                self.skip = wanted - self.message.len();
                self.message.clear();
                continue;
            }
            let take = (wanted - self.message.len()).min(bytes.len());
            // Within the capacity: checked above.
            let _ = self.message.extend_from_slice(&bytes[..take]);
            bytes = &bytes[take..];
            let size = |m: &[u8]| 3 + usize::from(u16::from_le_bytes([m[0], m[1]]));
            if self.message.len() < 3 || self.message.len() < size(&self.message) {
                continue;
            }
            match self.message[2] {
                START if self.message.len() == 11 => {
                    let mut t = [0u8; 8];
                    t.copy_from_slice(&self.message[3..11]);
                    each(Piece::Start(u64::from_le_bytes(t)));
                }
                END => each(Piece::End),
                _ => each(Piece::Message(&self.message)),
            }
            self.message.clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec as StdVec;

    /// A ring of `capacity` bytes read out by the test.
    struct TestRing {
        bytes: StdVec<u8>,
        capacity: usize,
        scratch: StdVec<u8>,
    }

    impl TestRing {
        fn new(capacity: usize) -> Self {
            Self {
                bytes: StdVec::new(),
                capacity,
                scratch: StdVec::new(),
            }
        }
    }

    impl LogSpace for TestRing {
        fn space(&mut self) -> &mut [u8] {
            self.scratch.clear();
            self.scratch.resize(self.capacity - self.bytes.len(), 0xA5);
            &mut self.scratch
        }
        fn commit(&mut self, n: usize) {
            assert!(n <= self.scratch.len(), "committed past the free room");
            self.bytes.extend_from_slice(&self.scratch[..n]);
        }
    }

    fn status(t: u64) -> Record {
        Record::VehicleStatus {
            timestamp: t,
            armed: false,
            nav_state: 3,
            mission_phase: 1,
        }
    }

    fn split(bytes: &[u8], chunk: usize) -> StdVec<(char, u64)> {
        let mut splitter = Splitter::new();
        let mut out = StdVec::new();
        for c in bytes.chunks(chunk) {
            splitter.push(c, &mut |p| {
                out.push(match p {
                    Piece::Start(t) => ('<', t),
                    Piece::End => ('>', 0),
                    Piece::Message(m) => (m[2] as char, m.len() as u64),
                })
            });
        }
        out
    }

    #[test]
    fn entries_between_the_markers_come_back_whole_in_any_chunks() {
        let mut ring = TestRing::new(10_000);
        let mut w = LogWriter::new();
        w.record(&mut ring, &status(1), 1);
        assert!(ring.bytes.is_empty(), "nothing before the start");
        assert!(w.start(&mut ring, 42));
        w.record(&mut ring, &status(2), 2);
        w.text(
            &mut ring,
            LogLevel::Info,
            3,
            format_args!("phase: lift: robots in place"),
        );
        assert!(w.end(&mut ring));
        w.record(&mut ring, &status(4), 4);
        for chunk in [1, 2, 7, 64, 10_000] {
            let pieces = split(&ring.bytes, chunk);
            assert_eq!(
                pieces,
                [('<', 42), ('D', 16), ('L', 3 + 9 + 28), ('>', 0)],
                "chunks of {chunk}"
            );
        }
    }

    #[test]
    fn a_full_ring_drops_whole_messages_and_says_how_long_in_a_dropout() {
        // Room for the start marker and one record; a record is built in a window of the
        // largest record's size, so after one there is no room for another.
        let mut ring = TestRing::new(11 + 16 + MESSAGE_BYTES - 1);
        let mut w = LogWriter::new();
        assert!(w.start(&mut ring, 0));
        w.record(&mut ring, &status(1_000), 1_000);
        // No room for another: lost, from 2 ms to 9 ms.
        w.record(&mut ring, &status(2_000), 2_000);
        w.record(&mut ring, &status(9_000), 9_000);
        assert_eq!(w.lost(), 2);
        assert_eq!(ring.bytes.len(), 27);
        // The reader empties the ring: the next message comes after a 9 ms dropout.
        let read: StdVec<u8> = ring.bytes.drain(..).collect();
        w.record(&mut ring, &status(11_000), 11_000);
        let mut all = read;
        all.extend_from_slice(&ring.bytes);
        assert_eq!(split(&all, 5), [('<', 0), ('D', 16), ('O', 5), ('D', 16)]);
        let dropout = &ring.bytes[..5];
        assert_eq!(u16::from_le_bytes([dropout[3], dropout[4]]), 9);
    }

    #[test]
    fn markers_wait_for_room_and_a_corrupt_length_is_skipped() {
        let mut ring = TestRing::new(5);
        let mut w = LogWriter::new();
        assert!(!w.start(&mut ring, 7));
        assert!(!w.is_open());
        ring.capacity = 20;
        assert!(w.start(&mut ring, 7));
        ring.capacity = ring.bytes.len() + 2;
        assert!(!w.end(&mut ring));
        assert!(w.is_open());
        // A message longer than any the writer makes is passed over; what follows is read.
        let mut bytes = StdVec::from([0xE8, 0x03, b'D']);
        bytes.extend_from_slice(&[7; 1000]);
        bytes.extend_from_slice(&[0, 0, END]);
        for chunk in [1, 8, 2000] {
            assert_eq!(split(&bytes, chunk), [('>', 0)], "chunks of {chunk}");
        }
    }
}
