//! ULog, PX4's flight log format (docs/formats.md#flight-logs; PX4's own description is its
//! "ULog File Format" page): the encoder of each message, `no_std` and without allocation.
//!
//! A log is the 16-byte [`file_header`], the definitions (the [`Message::flag_bits`] first,
//! then [`Message::format`]s, [`Message::info`]s and [`Message::parameter_f32`]s) and the data
//! ([`Message::add_subscription`], data and logged strings built in place by [`Packer`],
//! [`Message::dropout`], [`Message::sync`]). Every message is a 3-byte header (payload size,
//! type) and its payload, little endian. A message is built whole in a fixed buffer; the
//! caller writes its bytes wherever the log goes.

use core::fmt::Write as _;
use heapless::{String, Vec};

/// The most bytes one message takes, header included (formats are the longest).
pub const MESSAGE_CAPACITY: usize = 768;

/// The header's file magic, "ULog" and three fixed bytes.
const MAGIC: [u8; 7] = [0x55, 0x4C, 0x6F, 0x67, 0x01, 0x12, 0x35];
/// The format version written (1: the flag bits message follows the header).
const VERSION: u8 = 1;
/// The sync message's magic.
const SYNC_MAGIC: [u8; 8] = [0x2F, 0x73, 0x13, 0x20, 0x25, 0x0C, 0xBB, 0x12];

/// The file header: the magic, the version and the log's start time, us.
pub fn file_header(timestamp_us: u64) -> [u8; 16] {
    let mut h = [0u8; 16];
    h[..7].copy_from_slice(&MAGIC);
    h[7] = VERSION;
    h[8..].copy_from_slice(&timestamp_us.to_le_bytes());
    h
}

/// Why a message could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UlogError {
    /// The message would exceed [`MESSAGE_CAPACITY`] bytes.
    TooLong,
    /// A name (topic, field, parameter or info key) is empty or longer than 255 bytes.
    BadName,
}

impl core::fmt::Display for UlogError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::TooLong => write!(f, "a log message longer than {MESSAGE_CAPACITY} bytes"),
            Self::BadName => write!(f, "a log name that is empty or over 255 bytes"),
        }
    }
}

/// A logged string's level, PX4's (the syslog levels, written as the digits '0' to '7').
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogLevel {
    /// The system is unusable.
    Emergency,
    /// Action must be taken at once.
    Alert,
    /// Critical.
    Critical,
    /// An error.
    Error,
    /// A warning.
    Warning,
    /// Normal but significant.
    Notice,
    /// Information.
    Info,
    /// Debugging.
    Debug,
}

impl LogLevel {
    /// The level as ULog writes it.
    fn byte(self) -> u8 {
        b'0' + self as u8
    }

    /// The level of a MAVLink `STATUSTEXT` severity (0 emergency to 7 debug: the same scale).
    pub fn from_mav_severity(severity: u8) -> Self {
        match severity {
            0 => Self::Emergency,
            1 => Self::Alert,
            2 => Self::Critical,
            3 => Self::Error,
            4 => Self::Warning,
            5 => Self::Notice,
            6 => Self::Info,
            _ => Self::Debug,
        }
    }
}

/// One ULog message, header and payload, ready to write.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Message {
    bytes: Vec<u8, MESSAGE_CAPACITY>,
}

impl Message {
    /// An empty message of `kind` (its size is filled in by [`Self::done`]).
    fn begin(kind: u8) -> Self {
        let mut bytes = Vec::new();
        // Three bytes fit any capacity.
        let _ = bytes.extend_from_slice(&[0, 0, kind]);
        Self { bytes }
    }

    fn put(mut self, more: &[u8]) -> Result<Self, UlogError> {
        self.bytes
            .extend_from_slice(more)
            .map_err(|_| UlogError::TooLong)?;
        Ok(self)
    }

    /// Writes the payload's size into the header.
    fn done(mut self) -> Self {
        let size = (self.bytes.len() - 3) as u16;
        self.bytes[..2].copy_from_slice(&size.to_le_bytes());
        self
    }

    /// The flag bits ('B'): no compatible or incompatible flags, no appended data.
    pub fn flag_bits() -> Self {
        let mut m = Self::begin(b'B');
        // 8 + 8 flag bytes and three u64 offsets: 40 bytes, inside any capacity.
        let _ = m.bytes.extend_from_slice(&[0; 40]);
        m.done()
    }

    /// A format ('F'): `topic:type name;type name;...`, the first field `uint64_t timestamp`.
    pub fn format(description: &str) -> Result<Self, UlogError> {
        Ok(Self::begin(b'F').put(description.as_bytes())?.done())
    }

    /// An information ('I'): `key` as ULog types it (`char[3] sys_name`) and its value's
    /// bytes.
    pub fn info(key: &str, value: &[u8]) -> Result<Self, UlogError> {
        let len = name_len(key)?;
        Ok(Self::begin(b'I')
            .put(&[len])?
            .put(key.as_bytes())?
            .put(value)?
            .done())
    }

    /// A text information: `char[len] name` with `value`.
    pub fn info_text(name: &str, value: &str) -> Result<Self, UlogError> {
        let key = typed_key("char", Some(value.len()), name)?;
        Self::info(&key, value.as_bytes())
    }

    /// An unsigned 32-bit information (`uint32_t name`), as PX4 writes `ver_sw_release`.
    pub fn info_u32(name: &str, value: u32) -> Result<Self, UlogError> {
        let key = typed_key("uint32_t", None, name)?;
        Self::info(&key, &value.to_le_bytes())
    }

    /// A parameter ('P') of type `float`.
    pub fn parameter_f32(name: &str, value: f32) -> Result<Self, UlogError> {
        let key = typed_key("float", None, name)?;
        Self::parameter(&key, &value.to_le_bytes())
    }

    /// A parameter ('P') of type `int32_t`.
    pub fn parameter_i32(name: &str, value: i32) -> Result<Self, UlogError> {
        let key = typed_key("int32_t", None, name)?;
        Self::parameter(&key, &value.to_le_bytes())
    }

    fn parameter(key: &str, value: &[u8]) -> Result<Self, UlogError> {
        let len = name_len(key)?;
        Ok(Self::begin(b'P')
            .put(&[len])?
            .put(key.as_bytes())?
            .put(value)?
            .done())
    }

    /// A subscription ('A'): data of `topic` (instance `multi_id`) comes as `msg_id`.
    pub fn add_subscription(multi_id: u8, msg_id: u16, topic: &str) -> Result<Self, UlogError> {
        name_len(topic)?;
        Ok(Self::begin(b'A')
            .put(&[multi_id])?
            .put(&msg_id.to_le_bytes())?
            .put(topic.as_bytes())?
            .done())
    }

    /// A dropout ('O'): data lost for `duration_ms`.
    pub fn dropout(duration_ms: u16) -> Self {
        let mut m = Self::begin(b'O');
        let _ = m.bytes.extend_from_slice(&duration_ms.to_le_bytes());
        m.done()
    }

    /// A sync message ('S'): a reader that lost its place finds the next message after it.
    pub fn sync() -> Self {
        let mut m = Self::begin(b'S');
        let _ = m.bytes.extend_from_slice(&SYNC_MAGIC);
        m.done()
    }

    /// The message's bytes.
    pub fn as_bytes(&self) -> &[u8] {
        &self.bytes
    }
}

/// A name's length as its one-byte prefix.
fn name_len(name: &str) -> Result<u8, UlogError> {
    match name.len() {
        1..=255 => Ok(name.len() as u8),
        _ => Err(UlogError::BadName),
    }
}

/// `type name` or `type[len] name`.
fn typed_key(kind: &str, len: Option<usize>, name: &str) -> Result<String<280>, UlogError> {
    name_len(name)?;
    let mut key = String::new();
    let written = match len {
        Some(n) => write!(key, "{kind}[{n}] {name}"),
        None => write!(key, "{kind} {name}"),
    };
    written.map_err(|_| UlogError::BadName)?;
    Ok(key)
}

/// Packs a data message's fields, little endian, in the order the format lists them, into a
/// fixed buffer (a field that does not fit marks the whole overflowed). The buffer is its own
/// (`Packer<[u8; N]>`) or borrowed: a window of the log's ring, so the control step builds its
/// messages where they are stored.
#[derive(Clone, Debug)]
pub struct Packer<B> {
    bytes: B,
    len: usize,
    overflow: bool,
}

impl<const N: usize> Default for Packer<[u8; N]> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Packer<[u8; N]> {
    /// Nothing packed yet, in a buffer of its own.
    pub const fn new() -> Self {
        Self {
            bytes: [0; N],
            len: 0,
            overflow: false,
        }
    }

    /// A data message's start ('D', `msg_id`) in a buffer of its own.
    pub fn data(msg_id: u16) -> Self {
        Self::data_in([0; N], msg_id)
    }

    /// A logged string in a buffer of its own (see [`Packer::logged_string_in`]).
    pub fn logged_string(
        level: LogLevel,
        timestamp_us: u64,
        text: core::fmt::Arguments<'_>,
    ) -> Self {
        Self::logged_string_in([0; N], level, timestamp_us, text)
    }
}

impl<B: AsMut<[u8]>> Packer<B> {
    /// Nothing packed yet, into `bytes`.
    pub fn over(bytes: B) -> Self {
        Self {
            bytes,
            len: 0,
            overflow: false,
        }
    }

    /// A data message's start ('D', `msg_id`) in `bytes`; [`Self::message`] fills in its size.
    pub fn data_in(bytes: B, msg_id: u16) -> Self {
        let mut p = Self::over(bytes);
        p.put([0, 0, b'D']).u16(msg_id);
        p
    }

    /// A logged string ('L') of `level` at `timestamp_us` saying `text` in `bytes`, cut at a
    /// character boundary where they end; [`Self::message`] fills in its size.
    pub fn logged_string_in(
        bytes: B,
        level: LogLevel,
        timestamp_us: u64,
        text: core::fmt::Arguments<'_>,
    ) -> Self {
        let mut p = Self::over(bytes);
        p.put([0, 0, b'L', level.byte()]).u64(timestamp_us);
        let _ = core::fmt::Write::write_fmt(&mut Cut(&mut p), text);
        p
    }

    /// A logged string of `level` at `timestamp_us` saying `text` (already formatted: copied,
    /// with no formatting machinery) in `bytes`, cut at a character boundary where they end.
    pub fn logged_str_in(bytes: B, level: LogLevel, timestamp_us: u64, text: &str) -> Self {
        let mut p = Self::over(bytes);
        p.put([0, 0, b'L', level.byte()]).u64(timestamp_us);
        p.str_cut(text);
        p
    }

    /// Appends whole characters of `s` while they fit; the rest is dropped.
    fn str_cut(&mut self, s: &str) {
        let bytes = self.bytes.as_mut();
        let room = bytes.len().saturating_sub(self.len);
        let mut n = s.len().min(room);
        while !s.is_char_boundary(n) {
            n -= 1;
        }
        bytes[self.len..self.len + n].copy_from_slice(&s.as_bytes()[..n]);
        self.len += n;
    }

    /// Appends `b`, whose length the compiler knows (so a field is a plain store).
    #[inline(always)]
    fn put<const K: usize>(&mut self, b: [u8; K]) -> &mut Self {
        match self.bytes.as_mut().get_mut(self.len..self.len + K) {
            Some(to) => {
                to.copy_from_slice(&b);
                self.len += K;
            }
            None => self.overflow = true,
        }
        self
    }

    /// A `uint64_t`.
    #[inline(always)]
    pub fn u64(&mut self, v: u64) -> &mut Self {
        self.put(v.to_le_bytes())
    }

    /// A `uint32_t`.
    #[inline(always)]
    pub fn u32(&mut self, v: u32) -> &mut Self {
        self.put(v.to_le_bytes())
    }

    /// An `int32_t`.
    #[inline(always)]
    pub fn i32(&mut self, v: i32) -> &mut Self {
        self.put(v.to_le_bytes())
    }

    /// A `uint16_t`.
    #[inline(always)]
    pub fn u16(&mut self, v: u16) -> &mut Self {
        self.put(v.to_le_bytes())
    }

    /// A `uint8_t` (or a `bool`, 0 or 1).
    #[inline(always)]
    pub fn u8(&mut self, v: u8) -> &mut Self {
        self.put([v])
    }

    /// A `float`.
    #[inline(always)]
    pub fn f32(&mut self, v: f32) -> &mut Self {
        self.put(v.to_le_bytes())
    }

    /// A `float[K]`.
    #[inline(always)]
    pub fn f32s<const K: usize>(&mut self, v: &[f32; K]) -> &mut Self {
        for x in v {
            self.f32(*x);
        }
        self
    }

    /// The packed bytes (`None` if they overflowed the buffer).
    pub fn bytes(&mut self) -> Option<&[u8]> {
        let len = self.len;
        (!self.overflow).then_some(&self.bytes.as_mut()[..len])
    }

    /// A message started by [`Self::data_in`] or [`Self::logged_string_in`]: its size written
    /// into its header; its length (`None` if it overflowed the buffer).
    #[inline(always)]
    pub fn finish(&mut self) -> Option<usize> {
        if self.overflow || self.len < 3 {
            return None;
        }
        let size = (self.len - 3) as u16;
        self.bytes.as_mut()[..2].copy_from_slice(&size.to_le_bytes());
        Some(self.len)
    }

    /// A message started by [`Self::data_in`] or [`Self::logged_string_in`]: its size written
    /// into its header, its bytes.
    pub fn message(&mut self) -> Option<&[u8]> {
        let len = self.finish()?;
        Some(&self.bytes.as_mut()[..len])
    }
}

/// Writes text into a packer, whole characters while they fit, the rest dropped.
struct Cut<'a, B>(&'a mut Packer<B>);

impl<B: AsMut<[u8]>> core::fmt::Write for Cut<'_, B> {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        self.0.str_cut(s);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_header_carries_the_magic_the_version_and_the_start_time() {
        let h = file_header(0x0102_0304_0506_0708);
        assert_eq!(&h[..4], b"ULog");
        assert_eq!(h[7], 1);
        assert_eq!(
            u64::from_le_bytes(h[8..].try_into().unwrap()),
            0x0102_0304_0506_0708
        );
    }

    #[test]
    fn each_message_starts_with_its_payload_size_and_type() {
        let f = Message::format("t:uint64_t timestamp;float x").unwrap();
        let b = f.as_bytes();
        assert_eq!(b[2], b'F');
        assert_eq!(u16::from_le_bytes([b[0], b[1]]) as usize, b.len() - 3);
        assert_eq!(&b[3..], b"t:uint64_t timestamp;float x");

        let flags = Message::flag_bits();
        assert_eq!(flags.as_bytes().len(), 43);
        assert_eq!(flags.as_bytes()[2], b'B');

        let s = Message::sync();
        assert_eq!(s.as_bytes()[..3], [8, 0, b'S']);
        assert_eq!(Message::dropout(300).as_bytes(), &[2, 0, b'O', 44, 1]);
    }

    #[test]
    fn infos_and_parameters_name_their_type() {
        let i = Message::info_text("sys_name", "PX4").unwrap();
        let b = i.as_bytes();
        assert_eq!(b[2], b'I');
        let key_len = b[3] as usize;
        assert_eq!(&b[4..4 + key_len], b"char[3] sys_name");
        assert_eq!(&b[4 + key_len..], b"PX4");

        let p = Message::parameter_f32("MPC_XY_P", 0.95).unwrap();
        let b = p.as_bytes();
        assert_eq!(b[2], b'P');
        let key_len = b[3] as usize;
        assert_eq!(&b[4..4 + key_len], b"float MPC_XY_P");
        assert_eq!(
            f32::from_le_bytes(b[4 + key_len..].try_into().unwrap()),
            0.95
        );

        let p = Message::parameter_i32("COM_MOT_TEST_EN", -3).unwrap();
        assert!(p.as_bytes().ends_with(&(-3i32).to_le_bytes()));
    }

    #[test]
    fn subscriptions_data_and_strings_carry_their_ids_and_times() {
        let a = Message::add_subscription(0, 7, "sensor_combined").unwrap();
        assert_eq!(&a.as_bytes()[2..6], &[b'A', 0, 7, 0]);
        assert_eq!(&a.as_bytes()[6..], b"sensor_combined");

        let mut d = Packer::<[u8; 32]>::data(7);
        d.u64(42).f32(1.5);
        let d = d.message().unwrap();
        assert_eq!(d[..5], [14, 0, b'D', 7, 0]);
        assert_eq!(u64::from_le_bytes(d[5..13].try_into().unwrap()), 42);
        assert_eq!(f32::from_le_bytes(d[13..].try_into().unwrap()), 1.5);

        let mut l =
            Packer::<[u8; 64]>::logged_string(LogLevel::Warning, 99, format_args!("battery low"));
        let b = l.message().unwrap();
        assert_eq!(u16::from_le_bytes([b[0], b[1]]) as usize, b.len() - 3);
        assert_eq!((b[2], b[3]), (b'L', b'4'));
        assert_eq!(u64::from_le_bytes(b[4..12].try_into().unwrap()), 99);
        assert_eq!(&b[12..], b"battery low");
        assert_eq!(LogLevel::from_mav_severity(4), LogLevel::Warning);
        assert_eq!(LogLevel::from_mav_severity(200), LogLevel::Debug);
    }

    #[test]
    fn too_long_or_badly_named_messages_are_refused() {
        let long = [b'x'; MESSAGE_CAPACITY];
        let text = core::str::from_utf8(&long).unwrap();
        assert_eq!(Message::format(text), Err(UlogError::TooLong));
        assert_eq!(Message::parameter_f32("", 1.0), Err(UlogError::BadName));
        assert_eq!(
            Message::add_subscription(0, 1, &text[..300]),
            Err(UlogError::BadName)
        );
        assert!(Packer::<[u8; 4]>::new().u64(1).bytes().is_none());
        // A text is cut at a character boundary where the buffer ends.
        let mut t =
            Packer::<[u8; 16]>::logged_string(LogLevel::Info, 5, format_args!("h\u{e9}llo"));
        assert_eq!(&t.message().unwrap()[12..], b"h\xc3\xa9l");
        assert!(Packer::<[u8; 6]>::data(1).u64(1).message().is_none());
    }
}
