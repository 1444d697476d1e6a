//! Reads a ULog flight log (docs/formats.md#flight-logs; PX4's "ULog File Format" page) for
//! `host-sim plot`: the formats, information, parameters, subscriptions, data and logged
//! strings of any ULog file, the firmware's, the simulator's or PX4's.
//!
//! Written here rather than taken from crates.io: `px4-ulog` 0.6 indexes messages without
//! checking their length (a corrupt log panics it) and `yule_log` 0.4 brings a logger, regex
//! and their dependencies into the simulator's build. Nothing here panics on any input: every
//! length is checked before it is used.
//!
//! A log that cannot be read at all (a missing or empty file, not ULog, an incompatible
//! version of the format) is an error. A log that stops making sense part way (cut short, as a
//! crashed vehicle's log is, or corrupt) is read up to there: [`Ulog::stop`] says where and
//! why. A corrupt stretch followed by a sync message is skipped and counted.

use std::collections::HashMap;
use std::format;
use std::ops::Range;
use std::path::Path;
use std::string::{String, ToString};
use std::vec::Vec;

use anyhow::{Context, Result, bail};

/// The file magic: "ULog" and three fixed bytes.
const MAGIC: [u8; 7] = [0x55, 0x4C, 0x6F, 0x67, 0x01, 0x12, 0x35];
/// The sync message's magic.
const SYNC_MAGIC: [u8; 8] = [0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12];
/// The largest log read, bytes (a day of this vehicle's logging is under 8 GB; a real flight
/// is minutes).
pub const MAX_LOG_BYTES: u64 = 4 << 30;
/// How deep formats may nest (a format whose field is another format).
const MAX_NESTING: usize = 8;

/// A field's base type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Base {
    /// `int8_t`.
    I8,
    /// `uint8_t`, `bool` or `char`.
    U8,
    /// `int16_t`.
    I16,
    /// `uint16_t`.
    U16,
    /// `int32_t`.
    I32,
    /// `uint32_t`.
    U32,
    /// `int64_t`.
    I64,
    /// `uint64_t`.
    U64,
    /// `float`.
    F32,
    /// `double`.
    F64,
}

impl Base {
    fn of(name: &str) -> Option<Self> {
        Some(match name {
            "int8_t" => Self::I8,
            "uint8_t" | "bool" | "char" => Self::U8,
            "int16_t" => Self::I16,
            "uint16_t" => Self::U16,
            "int32_t" => Self::I32,
            "uint32_t" => Self::U32,
            "int64_t" => Self::I64,
            "uint64_t" => Self::U64,
            "float" => Self::F32,
            "double" => Self::F64,
            _ => return None,
        })
    }

    /// Its size, bytes.
    pub fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::I64 | Self::U64 | Self::F64 => 8,
        }
    }

    /// The value at the start of `b` (`None` when `b` is too short).
    fn read(self, b: &[u8]) -> Option<f64> {
        let b = b.get(..self.size())?;
        Some(match self {
            Self::I8 => f64::from(b[0] as i8),
            Self::U8 => f64::from(b[0]),
            Self::I16 => f64::from(i16::from_le_bytes(b.try_into().ok()?)),
            Self::U16 => f64::from(u16::from_le_bytes(b.try_into().ok()?)),
            Self::I32 => f64::from(i32::from_le_bytes(b.try_into().ok()?)),
            Self::U32 => f64::from(u32::from_le_bytes(b.try_into().ok()?)),
            Self::I64 => i64::from_le_bytes(b.try_into().ok()?) as f64,
            Self::U64 => u64::from_le_bytes(b.try_into().ok()?) as f64,
            Self::F32 => f64::from(f32::from_le_bytes(b.try_into().ok()?)),
            Self::F64 => f64::from_le_bytes(b.try_into().ok()?),
        })
    }
}

/// One field of a format as written: its type's name, how many (1 unless an array), name.
#[derive(Clone, Debug)]
struct FieldDef {
    kind: String,
    count: usize,
    name: String,
}

/// Where a field of a basic type lies in a record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Field {
    /// Its byte offset in the record (the timestamp's is 0).
    pub offset: usize,
    /// Its type.
    pub base: Base,
    /// Its length: 1, or the array's.
    pub count: usize,
}

impl Field {
    /// Value `index` of the field in `record` (`None` past the array or the record's end, as
    /// where PX4 left out a record's trailing padding).
    pub fn get(&self, record: &[u8], index: usize) -> Option<f64> {
        if index >= self.count {
            return None;
        }
        let at = self
            .offset
            .checked_add(index.checked_mul(self.base.size())?)?;
        self.base.read(record.get(at..)?)
    }
}

/// Why reading stopped before the end of the file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Stop {
    /// The file ends inside a message: the log was cut short.
    Truncated {
        /// Where the unfinished message begins, byte.
        at: usize,
    },
    /// A message that makes no sense, with no sync message after it to go on from.
    Corrupt {
        /// Where it begins, byte.
        at: usize,
        /// What is wrong with it.
        why: String,
    },
}

/// A logged string.
#[derive(Clone, Debug, PartialEq)]
pub struct LoggedString {
    /// Its level, 0 emergency to 7 debug (the syslog scale).
    pub level: u8,
    /// When, us.
    pub timestamp_us: u64,
    /// What it says.
    pub text: String,
}

/// A ULog file as read.
#[derive(Debug, Default)]
pub struct Ulog {
    bytes: Vec<u8>,
    /// The header's start time, us.
    pub start_us: u64,
    /// Each format's fields, by its name.
    formats: HashMap<String, Vec<FieldDef>>,
    /// Each subscription's topic and instance, by message id.
    subscriptions: HashMap<u16, (String, u8)>,
    /// Each data message's payload after its message id, by message id, in file order.
    data: HashMap<u16, Vec<Range<usize>>>,
    /// Data messages whose id has no subscription.
    pub unsubscribed: usize,
    /// Each information: key (without its type) and value as text.
    pub info: Vec<(String, String)>,
    /// Each parameter: name and value (the last given, where it changes in flight).
    pub parameters: Vec<(String, f64)>,
    /// Logged strings, in file order.
    pub strings: Vec<LoggedString>,
    /// Dropouts: how many, and their total duration, ms.
    pub dropouts: (usize, u64),
    /// Bytes skipped as corrupt (up to a sync message).
    pub skipped: usize,
    /// Bytes read (the whole file, unless [`Self::stop`]).
    pub read: usize,
    /// Why reading stopped early, if it did.
    pub stop: Option<Stop>,
}

/// A topic's records and where its fields lie.
#[derive(Debug)]
pub struct TopicData<'a> {
    fields: Vec<(String, Field)>,
    /// Each record's bytes, in file order.
    pub records: Vec<&'a [u8]>,
}

impl TopicData<'_> {
    /// The field called `name` (`position` or, in an array, `output`), if the format has
    /// one of a basic type.
    pub fn field(&self, name: &str) -> Option<Field> {
        self.fields.iter().find(|(n, _)| n == name).map(|(_, f)| *f)
    }
}

/// Reads the file at `path`.
pub fn read_file(path: &Path) -> Result<Ulog> {
    let meta =
        std::fs::metadata(path).with_context(|| format!("cannot read {}", path.display()))?;
    if !meta.is_file() {
        bail!("{} is not a file", path.display());
    }
    if meta.len() > MAX_LOG_BYTES {
        bail!(
            "{} is {} bytes, more than the {} a flight log may have",
            path.display(),
            meta.len(),
            MAX_LOG_BYTES
        );
    }
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    parse(bytes).with_context(|| format!("{} is not a flight log this tool reads", path.display()))
}

/// Reads a log from its bytes.
pub fn parse(bytes: Vec<u8>) -> Result<Ulog> {
    if bytes.is_empty() {
        bail!("the file is empty");
    }
    if bytes.len() < 16 {
        if MAGIC.starts_with(&bytes[..bytes.len().min(7)]) {
            bail!(
                "the file ends after {} bytes, inside the 16-byte ULog header",
                bytes.len()
            );
        }
        bail!("it does not begin with ULog's magic bytes");
    }
    if bytes[..7] != MAGIC {
        bail!("it does not begin with ULog's magic bytes");
    }
    let mut log = Ulog {
        start_us: u64_at(&bytes, 8).unwrap_or(0),
        ..Ulog::default()
    };
    let mut at = 16;
    let mut end = bytes.len();
    let mut first = true;
    while at < end {
        let Some(header) = bytes.get(at..at + 3) else {
            log.stop = Some(Stop::Truncated { at });
            break;
        };
        let size = usize::from(u16::from_le_bytes([header[0], header[1]]));
        let kind = header[2];
        let Some(payload) = bytes
            .get(at + 3..at + 3 + size)
            .filter(|_| at + 3 + size <= end)
        else {
            log.stop = Some(Stop::Truncated { at });
            break;
        };
        let range = at + 3..at + 3 + size;
        match log.message(kind, payload, range, first) {
            Ok(Some(appended)) => end = end.min(appended),
            Ok(None) => {}
            Err(why) if first => bail!("{why}"),
            Err(why) => match find_sync(&bytes, at + 1, end) {
                Some(next) => {
                    log.skipped += next - at;
                    at = next;
                    continue;
                }
                None => {
                    log.stop = Some(Stop::Corrupt { at, why });
                    break;
                }
            },
        }
        first = false;
        at += 3 + size;
    }
    log.read = match &log.stop {
        Some(Stop::Truncated { at } | Stop::Corrupt { at, .. }) => *at,
        None => at.min(bytes.len()),
    };
    log.bytes = bytes;
    Ok(log)
}

/// Where the message after the first sync magic at or after `from` begins.
fn find_sync(bytes: &[u8], from: usize, end: usize) -> Option<usize> {
    let hay = bytes.get(from..end)?;
    hay.windows(SYNC_MAGIC.len())
        .position(|w| w == SYNC_MAGIC)
        .map(|p| from + p + SYNC_MAGIC.len())
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

fn text(b: &[u8]) -> Result<&str, String> {
    std::str::from_utf8(b).map_err(|_| "a name that is not text".to_string())
}

/// A key `type name` as (type, name).
fn typed_key(key: &str) -> Result<(&str, &str), String> {
    key.split_once(' ')
        .filter(|(t, n)| !t.is_empty() && !n.is_empty())
        .ok_or_else(|| format!("a key `{key}` without a type"))
}

/// A type `base` or `base[N]` as (base, N).
fn split_array(kind: &str) -> Result<(&str, usize), String> {
    match kind.split_once('[') {
        Some((base, rest)) => {
            let n = rest
                .strip_suffix(']')
                .and_then(|n| n.parse::<usize>().ok())
                .filter(|&n| n > 0 && n <= 65535)
                .ok_or_else(|| format!("a type `{kind}` with a bad array length"))?;
            Ok((base, n))
        }
        None => Ok((kind, 1)),
    }
}

/// A format's text: its name and fields.
fn parse_format(description: &str) -> Result<(String, Vec<FieldDef>), String> {
    let (name, fields) = description
        .split_once(':')
        .filter(|(n, _)| !n.is_empty())
        .ok_or_else(|| "a format without a name".to_string())?;
    let mut defs = Vec::new();
    for field in fields.split(';').filter(|f| !f.is_empty()) {
        let (kind, field_name) = typed_key(field)?;
        let (base, count) = split_array(kind)?;
        defs.push(FieldDef {
            kind: base.to_string(),
            count,
            name: field_name.to_string(),
        });
    }
    if defs.is_empty() {
        return Err(format!("a format `{name}` without fields"));
    }
    Ok((name.to_string(), defs))
}

impl Ulog {
    /// Takes one message; `Ok(Some(offset))` when its flag bits say data is appended at that
    /// offset (where the log proper ends).
    fn message(
        &mut self,
        kind: u8,
        p: &[u8],
        range: Range<usize>,
        first: bool,
    ) -> Result<Option<usize>, String> {
        match kind {
            b'B' => {
                if p.len() < 40 {
                    return Err("flag bits shorter than 40 bytes".to_string());
                }
                // Incompatible flag bit 0: data appended; any other means a format this
                // reader does not know.
                if p[8] & !1 != 0 || p[9..16].iter().any(|&b| b != 0) {
                    return Err("the log uses a ULog feature this reader does not know (an \
                                incompatible flag)"
                        .to_string());
                }
                if p[8] & 1 != 0 {
                    let first_offset = u64_at(p, 16).unwrap_or(0);
                    if first_offset > 0 {
                        return Ok(Some(usize::try_from(first_offset).unwrap_or(usize::MAX)));
                    }
                }
            }
            _ if first && !b"FIMPQA".contains(&kind) => {
                return Err(format!(
                    "the first message after the header is of unknown type {kind}"
                ));
            }
            b'F' => {
                let (name, fields) = parse_format(text(p)?)?;
                self.formats.insert(name, fields);
            }
            b'I' | b'M' | b'P' | b'Q' => {
                // Multi information and default parameters carry a byte before the key.
                let skip = usize::from(kind == b'M' || kind == b'Q');
                let key_len = usize::from(*p.get(skip).ok_or("an empty key")?);
                let key = p
                    .get(skip + 1..skip + 1 + key_len)
                    .ok_or("a key past the message's end")?;
                let (kind_name, name) = typed_key(text(key)?)?;
                let value = &p[skip + 1 + key_len..];
                if kind == b'P' {
                    let (base, _) = split_array(kind_name)?;
                    let v = Base::of(base)
                        .and_then(|b| b.read(value))
                        .ok_or_else(|| format!("a parameter {name} of an unknown type"))?;
                    match self.parameters.iter_mut().find(|(n, _)| n == name) {
                        Some(slot) => slot.1 = v,
                        None => self.parameters.push((name.to_string(), v)),
                    }
                } else if kind == b'I' {
                    let shown = if kind_name.starts_with("char") {
                        String::from_utf8_lossy(value).into_owned()
                    } else {
                        let (base, _) = split_array(kind_name)?;
                        Base::of(base)
                            .and_then(|b| b.read(value))
                            .map_or_else(String::new, |v| v.to_string())
                    };
                    self.info.push((name.to_string(), shown));
                }
            }
            b'A' => {
                if p.len() < 4 {
                    return Err("a subscription shorter than 4 bytes".to_string());
                }
                let id = u16::from_le_bytes([p[1], p[2]]);
                self.subscriptions
                    .insert(id, (text(&p[3..])?.to_string(), p[0]));
            }
            b'R' => {}
            b'D' => {
                if p.len() < 2 {
                    return Err("a data message without its id".to_string());
                }
                let id = u16::from_le_bytes([p[0], p[1]]);
                if self.subscriptions.contains_key(&id) {
                    self.data
                        .entry(id)
                        .or_default()
                        .push(range.start + 2..range.end);
                } else {
                    self.unsubscribed += 1;
                }
            }
            b'L' | b'C' => {
                // A tagged string has a 2-byte tag after its level.
                let tag = if kind == b'C' { 2 } else { 0 };
                let timestamp_us = u64_at(p, 1 + tag).ok_or("a logged string without its time")?;
                let level = p[0].saturating_sub(b'0');
                self.strings.push(LoggedString {
                    level,
                    timestamp_us,
                    text: String::from_utf8_lossy(&p[9 + tag..]).into_owned(),
                });
            }
            b'O' => {
                let ms = p.get(..2).ok_or("a dropout without its duration")?;
                self.dropouts.0 += 1;
                self.dropouts.1 += u64::from(u16::from_le_bytes([ms[0], ms[1]]));
            }
            b'S' => {
                if p != SYNC_MAGIC {
                    return Err("a sync message without the sync magic".to_string());
                }
            }
            other => return Err(format!("a message of unknown type {other}")),
        }
        Ok(None)
    }

    /// The file's length, bytes.
    pub fn len(&self) -> usize {
        self.bytes.len()
    }

    /// Whether the file is empty (never: an empty file is not read).
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }

    /// Data messages read, of every topic.
    pub fn data_messages(&self) -> usize {
        self.data.values().map(Vec::len).sum()
    }

    /// The information `key`, if the log has it.
    pub fn info(&self, key: &str) -> Option<&str> {
        self.info
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// Topic `name`'s first instance: its fields (from its format) and its records, if the
    /// log subscribed to it. Its records are there even when its format is missing or
    /// broken (then it has no fields).
    pub fn topic(&self, name: &str) -> Option<TopicData<'_>> {
        let mut ids: Vec<u16> = self
            .subscriptions
            .iter()
            .filter(|(_, (topic, multi))| topic == name && *multi == 0)
            .map(|(id, _)| *id)
            .collect();
        if ids.is_empty() {
            return None;
        }
        ids.sort_unstable();
        let mut ranges: Vec<&Range<usize>> = ids
            .iter()
            .filter_map(|id| self.data.get(id))
            .flatten()
            .collect();
        ranges.sort_by_key(|r| r.start);
        let mut fields = Vec::new();
        self.flatten(name, "", 0, 0, &mut fields);
        Some(TopicData {
            fields,
            records: ranges
                .into_iter()
                .filter_map(|r| self.bytes.get(r.clone()))
                .collect(),
        })
    }

    /// The fields of format `name` from `offset` on, nested formats' fields named
    /// `outer.inner` (an array of them `outer[0].inner`); returns the format's size (`None`
    /// when a type is unknown or nesting runs too deep: the fields after it cannot be placed).
    fn flatten(
        &self,
        name: &str,
        prefix: &str,
        offset: usize,
        depth: usize,
        out: &mut Vec<(String, Field)>,
    ) -> Option<usize> {
        let defs = self.formats.get(name)?;
        if depth > MAX_NESTING {
            return None;
        }
        let mut at = offset;
        for def in defs {
            // No record is longer than a message: a format that is (nested arrays of arrays)
            // is not placed, nor its fields counted.
            if at > usize::from(u16::MAX) {
                return None;
            }
            let full = format!("{prefix}{}", def.name);
            match Base::of(&def.kind) {
                Some(base) => {
                    out.push((
                        full,
                        Field {
                            offset: at,
                            base,
                            count: def.count,
                        },
                    ));
                    at = at.checked_add(base.size().checked_mul(def.count)?)?;
                }
                None => {
                    for k in 0..def.count {
                        let inner = if def.count == 1 {
                            format!("{full}.")
                        } else {
                            format!("{full}[{k}].")
                        };
                        let size = self.flatten(&def.kind, &inner, at, depth + 1, out)?;
                        at = at.checked_add(size)?;
                    }
                }
            }
        }
        Some(at - offset)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec;

    fn message(kind: u8, payload: &[u8]) -> Vec<u8> {
        let mut m = (payload.len() as u16).to_le_bytes().to_vec();
        m.push(kind);
        m.extend_from_slice(payload);
        m
    }

    fn log_with(messages: &[Vec<u8>]) -> Vec<u8> {
        let mut b = MAGIC.to_vec();
        b.push(1);
        b.extend_from_slice(&7u64.to_le_bytes());
        b.extend(message(b'B', &[0; 40]));
        for m in messages {
            b.extend_from_slice(m);
        }
        b
    }

    fn data(id: u16, fields: &[u8]) -> Vec<u8> {
        let mut p = id.to_le_bytes().to_vec();
        p.extend_from_slice(fields);
        message(b'D', &p)
    }

    #[test]
    fn arrays_nested_formats_strings_and_parameters_are_read() {
        let mut record = 5u64.to_le_bytes().to_vec();
        for v in [1.5f32, -2.0] {
            record.extend_from_slice(&v.to_le_bytes());
        }
        record.extend_from_slice(&[7, 0]); // inner.a, inner.b (uint8_t)
        let mut param = vec![11];
        param.extend_from_slice(b"float MPC_P");
        param.extend_from_slice(&0.25f32.to_le_bytes());
        let mut info = vec![16];
        info.extend_from_slice(b"char[3] sys_name");
        info.extend_from_slice(b"PX4");
        let mut string = vec![b'4'];
        string.extend_from_slice(&9u64.to_le_bytes());
        string.extend_from_slice(b"battery low");
        let mut sub = vec![0, 3, 0];
        sub.extend_from_slice(b"t");
        let log = parse(log_with(&[
            message(b'F', b"in:uint8_t a;uint8_t b"),
            message(b'F', b"t:uint64_t timestamp;float[2] x;in inner"),
            message(b'I', &info),
            message(b'P', &param),
            message(b'A', &sub),
            data(3, &record),
            message(b'L', &string),
            message(b'O', &300u16.to_le_bytes()),
            data(9, &record),
        ]))
        .expect("reads");
        assert_eq!(log.stop, None);
        assert_eq!(log.read, log.len());
        assert_eq!(log.start_us, 7);
        assert_eq!(log.info("sys_name"), Some("PX4"));
        assert_eq!(log.parameters, vec![("MPC_P".to_string(), 0.25)]);
        assert_eq!(log.strings[0].text, "battery low");
        assert_eq!((log.strings[0].level, log.strings[0].timestamp_us), (4, 9));
        assert_eq!(log.dropouts, (1, 300));
        assert_eq!(log.unsubscribed, 1);
        let t = log.topic("t").expect("subscribed");
        assert_eq!(t.records.len(), 1);
        let x = t.field("x").expect("x");
        assert_eq!(x.get(t.records[0], 1), Some(-2.0));
        assert_eq!(x.get(t.records[0], 2), None);
        let b = t.field("inner.b").expect("nested");
        assert_eq!((b.offset, b.get(t.records[0], 0)), (17, Some(0.0)));
        assert!(log.topic("other").is_none());
    }

    #[test]
    fn a_format_nested_without_end_or_past_any_record_is_not_placed() {
        let mut sub = vec![0, 1, 0];
        sub.extend_from_slice(b"t");
        let log = parse(log_with(&[
            message(b'F', b"d:uint8_t[65535] z"),
            message(b'F', b"c:d[65535] y"),
            message(b'F', b"t:uint64_t timestamp;c[65535] x;uint8_t after"),
            message(b'F', b"s:uint64_t timestamp;s[2] again"),
            message(b'A', &sub),
        ]))
        .expect("reads");
        let t = log.topic("t").expect("subscribed");
        assert!(t.field("timestamp").is_some() && t.field("after").is_none());
        let mut fields = Vec::new();
        assert_eq!(log.flatten("s", "", 0, 0, &mut fields), None);
    }

    #[test]
    fn a_cut_or_corrupt_log_keeps_what_came_before() {
        let mut sub = vec![0, 1, 0];
        sub.extend_from_slice(b"t");
        let whole = log_with(&[
            message(b'F', b"t:uint64_t timestamp"),
            message(b'A', &sub),
            data(1, &1u64.to_le_bytes()),
            data(1, &2u64.to_le_bytes()),
        ]);
        let cut = parse(whole[..whole.len() - 3].to_vec()).expect("reads");
        let at = whole.len() - 13;
        assert_eq!(cut.stop, Some(Stop::Truncated { at }));
        assert_eq!(cut.read, at);
        assert_eq!(cut.topic("t").expect("t").records.len(), 1);

        let mut bad = whole.clone();
        bad[at + 2] = b'?';
        let corrupt = parse(bad.clone()).expect("reads");
        assert!(matches!(corrupt.stop, Some(Stop::Corrupt { at: a, .. }) if a == at));
        // A sync message after the corrupt one: reading goes on after it.
        bad.extend(message(b'S', &SYNC_MAGIC));
        bad.extend(data(1, &3u64.to_le_bytes()));
        let synced = parse(bad).expect("reads");
        assert_eq!(synced.stop, None);
        assert_eq!(synced.topic("t").expect("t").records.len(), 2);
        assert!(synced.skipped > 0);
    }

    #[test]
    fn what_is_not_a_log_is_refused_by_name() {
        let err = |b: &[u8]| parse(b.to_vec()).expect_err("refused").to_string();
        assert_eq!(err(b""), "the file is empty");
        assert!(err(b"ULog\x01").contains("inside the 16-byte ULog header"));
        assert!(err(b"hello, this is not a log").contains("magic"));
        let mut b = MAGIC.to_vec();
        b.extend_from_slice(&[1; 9]);
        b.extend(message(b'B', &[0xff; 40]));
        assert!(err(&b).contains("incompatible flag"));
    }
}
