//! What the vehicle tells people and tools: `STATUSTEXT` for events (every mission transition,
//! refusals naming the key), `NAMED_VALUE_FLOAT`/`NAMED_VALUE_INT` for numbers (issue 11,
//! section 3), so any MAVLink tool can show them.
//!
//! A text longer than one `STATUSTEXT` (50 bytes) goes out in chunks sharing a non-zero `id`,
//! numbered by `chunk_seq`; the last chunk is shorter than 50 bytes (an empty one follows a
//! text that fills its last chunk exactly), as the MAVLink spec has it. [`Reassembler`] puts
//! them back together on the ground side.
//!
//! Conventions the HIL plant reads (a ground station just shows them):
//! - a text starting with [`BOARD_PREFIX`] names the board the firmware runs on;
//! - a text starting with [`PHASE_PREFIX`] reports a mission transition (`phase: NAME: reason`).

use heapless::{String, Vec};

use crate::msg::{MavSeverity, NAMED_VALUE_FLOAT_DATA, NAMED_VALUE_INT_DATA, STATUSTEXT_DATA};

/// Bytes of text in one `STATUSTEXT`.
pub const CHUNK_LEN: usize = 50;
/// Longest text sent, bytes.
pub const MAX_TEXT_LEN: usize = 200;
/// Start of the text that names the board.
pub const BOARD_PREFIX: &str = "board: ";
/// Start of the text of a mission transition.
pub const PHASE_PREFIX: &str = "phase: ";
/// Longest name of a named value, bytes.
pub const NAME_LEN: usize = 10;

/// A text to send, with its severity.
pub type Text = String<MAX_TEXT_LEN>;

/// The `STATUSTEXT` messages of `text`; `id` numbers a multi-chunk text (never 0; a text of one
/// chunk goes with id 0). Bytes past [`MAX_TEXT_LEN`] are dropped.
pub fn chunks(
    text: &str,
    severity: MavSeverity,
    id: u16,
) -> Vec<STATUSTEXT_DATA, { MAX_TEXT_LEN / CHUNK_LEN + 1 }> {
    let bytes = &text.as_bytes()[..text.len().min(MAX_TEXT_LEN)];
    let mut out = Vec::new();
    let single = bytes.len() <= CHUNK_LEN;
    let id = if single { 0 } else { id.max(1) };
    let mut seq = 0u8;
    let mut rest = bytes;
    loop {
        let n = rest.len().min(CHUNK_LEN);
        let mut data = [0u8; CHUNK_LEN];
        data[..n].copy_from_slice(&rest[..n]);
        let _ = out.push(STATUSTEXT_DATA {
            severity,
            text: data.into(),
            id,
            chunk_seq: seq,
        });
        rest = &rest[n..];
        seq = seq.wrapping_add(1);
        // Stop after a short chunk; a text ending on a full chunk gets an empty one (multi-chunk
        // only: a single full chunk needs no terminator, its id is 0).
        if n < CHUNK_LEN || (single && rest.is_empty()) {
            break;
        }
    }
    out
}

/// A `NAMED_VALUE_FLOAT` (`name` cut to [`NAME_LEN`] bytes).
pub fn named_float(name: &str, value: f32, time_boot_ms: u32) -> NAMED_VALUE_FLOAT_DATA {
    NAMED_VALUE_FLOAT_DATA {
        time_boot_ms,
        value,
        name: name.into(),
    }
}

/// A `NAMED_VALUE_INT` (`name` cut to [`NAME_LEN`] bytes).
pub fn named_int(name: &str, value: i32, time_boot_ms: u32) -> NAMED_VALUE_INT_DATA {
    NAMED_VALUE_INT_DATA {
        time_boot_ms,
        value,
        name: name.into(),
    }
}

/// The text of a chunk (up to its first NUL).
pub fn chunk_text(m: &STATUSTEXT_DATA) -> &[u8] {
    let end = m.text.iter().position(|&b| b == 0).unwrap_or(CHUNK_LEN);
    &m.text[..end]
}

/// Puts chunked `STATUSTEXT`s back together (one text at a time, as the vehicle sends them).
#[derive(Default)]
pub struct Reassembler {
    id: u16,
    next_seq: u8,
    text: Vec<u8, MAX_TEXT_LEN>,
}

impl Reassembler {
    /// An empty reassembler.
    pub fn new() -> Self {
        Self::default()
    }

    /// Takes one `STATUSTEXT`; returns the whole text (lossy UTF-8 is the caller's) when this
    /// one completes it.
    pub fn push(&mut self, m: &STATUSTEXT_DATA) -> Option<Vec<u8, MAX_TEXT_LEN>> {
        let part = chunk_text(m);
        if m.id == 0 {
            return Vec::from_slice(part).ok();
        }
        if m.id != self.id || m.chunk_seq != self.next_seq {
            // A new text (or a lost chunk): start over from this chunk if it is a first one.
            self.text.clear();
            if m.chunk_seq != 0 {
                self.id = 0;
                return None;
            }
            self.id = m.id;
        }
        let _ = self.text.extend_from_slice(part);
        self.next_seq = m.chunk_seq.wrapping_add(1);
        if part.len() < CHUNK_LEN {
            self.id = 0;
            self.next_seq = 0;
            return Some(core::mem::take(&mut self.text));
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(text: &str) -> std::string::String {
        let mut r = Reassembler::new();
        let mut out = None;
        for c in chunks(text, MavSeverity::MAV_SEVERITY_INFO, 7) {
            if let Some(t) = r.push(&c) {
                assert!(out.is_none(), "one text comes out once");
                out = Some(std::string::String::from_utf8_lossy(&t).into_owned());
            }
        }
        out.expect("text completed")
    }

    #[test]
    fn short_and_long_texts_come_back_whole() {
        let short = "phase: checks: started";
        assert_eq!(chunks(short, MavSeverity::MAV_SEVERITY_INFO, 3)[0].id, 0);
        assert_eq!(round_trip(short), short);
        let long = "payload refused: robots.initial: robots 7 and the next are 0.1 m apart, closer than min_spacing 0.25 m";
        assert!(long.len() > CHUNK_LEN);
        assert_eq!(round_trip(long), long);
        let exact = "x".repeat(100);
        let c = chunks(&exact, MavSeverity::MAV_SEVERITY_INFO, 3);
        assert_eq!(c.len(), 3, "two full chunks and an empty terminator");
        assert_eq!(round_trip(&exact), exact);
        let fifty = "y".repeat(50);
        assert_eq!(chunks(&fifty, MavSeverity::MAV_SEVERITY_INFO, 3).len(), 1);
        assert_eq!(round_trip(&fifty), fifty);
    }

    #[test]
    fn a_lost_chunk_drops_that_text_but_not_the_next() {
        let mut r = Reassembler::new();
        let first = chunks(&"a".repeat(120), MavSeverity::MAV_SEVERITY_INFO, 1);
        assert!(r.push(&first[0]).is_none());
        // first[1] lost
        assert!(r.push(&first[2]).is_none());
        let second = chunks(&"b".repeat(60), MavSeverity::MAV_SEVERITY_INFO, 2);
        assert!(r.push(&second[0]).is_none());
        let t = r.push(&second[1]).expect("second text whole");
        assert_eq!(&t[..], "b".repeat(60).as_bytes());
    }

    #[test]
    fn named_values_cut_their_names() {
        let v = named_float("tick_instructions", 1.5, 10);
        assert_eq!(&v.name[..], b"tick_instr");
        assert_eq!(named_int("ticks", 3, 0).value, 3);
    }
}
