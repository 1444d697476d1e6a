//! DroneCAN transfers on CAN 2.0B frames (DroneCAN specification, "CAN bus transport layer"):
//! the 29-bit identifier of a message, the tail byte, and a transfer cut into frames and put
//! back together.
//!
//! - A message's identifier is `priority` (5 bits, 0 highest) | data type ID (16) | 0 (a
//!   message, not a service) | source node ID (7, 1 to 127).
//! - Every frame ends with a tail byte: start of transfer, end of transfer, toggle, and the
//!   transfer ID (5 bits, counting up per data type and source).
//! - A payload of up to 7 bytes is one frame. A longer one is prefixed with the transfer CRC
//!   (CRC-16-CCITT-FALSE over the data type's 64-bit signature, little-endian, then the
//!   payload; low byte first) and cut into 7-byte pieces, the toggle bit alternating from 0.
//!
//! The receiving side ([`Reassembler`]) keeps one transfer in progress per source and data
//! type and hands over only a payload whose frames came in order, with the toggles expected
//! and the CRC checking; everything else is counted by what was wrong with it.

use crc::{CRC_16_IBM_3740, Crc};

/// CRC-16-CCITT-FALSE (also called CRC-16/IBM-3740): polynomial 0x1021, initial 0xFFFF.
const TRANSFER_CRC: Crc<u16> = Crc::<u16>::new(&CRC_16_IBM_3740);

/// Bytes of payload one frame carries (eight data bytes less the tail byte).
pub const FRAME_PAYLOAD: usize = 7;

/// The largest payload this node sends or takes, bytes (RawCommand's twenty 14-bit commands
/// are 35).
pub const MAX_PAYLOAD: usize = 64;

/// One CAN 2.0B frame with an extended (29-bit) identifier.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CanFrame {
    /// The 29-bit identifier.
    pub id: u32,
    /// Data bytes; the first `len` count.
    pub data: [u8; 8],
    /// Data length, 1 to 8.
    pub len: u8,
}

impl CanFrame {
    /// The frame's data bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.data[..usize::from(self.len.min(8))]
    }
}

/// The parts of a message frame's identifier.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MessageId {
    /// Priority, 0 (highest) to 31.
    pub priority: u8,
    /// The message's data type ID.
    pub data_type: u16,
    /// The sending node, 1 to 127.
    pub source: u8,
}

impl MessageId {
    /// The 29-bit identifier.
    pub fn to_can_id(self) -> u32 {
        u32::from(self.priority & 0x1f) << 24
            | u32::from(self.data_type) << 8
            | u32::from(self.source & 0x7f)
    }

    /// The message a frame's identifier names; `None` for a service frame or an anonymous one
    /// (source 0), which this node neither sends nor takes.
    pub fn from_can_id(id: u32) -> Option<Self> {
        let source = (id & 0x7f) as u8;
        if id & 0x80 != 0 || source == 0 {
            return None;
        }
        Some(Self {
            priority: (id >> 24 & 0x1f) as u8,
            data_type: (id >> 8) as u16,
            source,
        })
    }
}

/// The transfer CRC of a multi-frame transfer.
pub fn transfer_crc(signature: u64, payload: &[u8]) -> u16 {
    let mut digest = TRANSFER_CRC.digest();
    digest.update(&signature.to_le_bytes());
    digest.update(payload);
    digest.finalize()
}

/// The frames of one transfer, in order.
pub struct Frames<'a> {
    id: u32,
    transfer_id: u8,
    payload: &'a [u8],
    crc: Option<[u8; 2]>,
    offset: usize,
    index: usize,
    done: bool,
}

/// The frames that carry `payload` as message `id` with transfer ID `transfer_id` (its low
/// five bits); `signature` is the data type's, for the CRC of a multi-frame transfer.
pub fn frames(id: MessageId, signature: u64, transfer_id: u8, payload: &[u8]) -> Frames<'_> {
    let crc =
        (payload.len() > FRAME_PAYLOAD).then(|| transfer_crc(signature, payload).to_le_bytes());
    Frames {
        id: id.to_can_id(),
        transfer_id: transfer_id & 0x1f,
        payload,
        crc,
        offset: 0,
        index: 0,
        done: false,
    }
}

/// The number of frames a payload of `len` bytes takes.
pub fn frame_count(len: usize) -> usize {
    if len <= FRAME_PAYLOAD {
        1
    } else {
        (len + 2).div_ceil(FRAME_PAYLOAD)
    }
}

impl Iterator for Frames<'_> {
    type Item = CanFrame;

    fn next(&mut self) -> Option<CanFrame> {
        if self.done {
            return None;
        }
        let mut data = [0u8; 8];
        let mut len = 0;
        if self.index == 0
            && let Some(crc) = self.crc
        {
            data[..2].copy_from_slice(&crc);
            len = 2;
        }
        let take = (FRAME_PAYLOAD - len).min(self.payload.len() - self.offset);
        data[len..len + take].copy_from_slice(&self.payload[self.offset..self.offset + take]);
        len += take;
        self.offset += take;
        let start = self.index == 0;
        let end = self.offset == self.payload.len();
        let toggle = self.index % 2 == 1;
        data[len] =
            u8::from(start) << 7 | u8::from(end) << 6 | u8::from(toggle) << 5 | self.transfer_id;
        self.index += 1;
        self.done = end;
        Some(CanFrame {
            id: self.id,
            data,
            len: (len + 1) as u8,
        })
    }
}

/// A transfer received whole.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Transfer {
    /// Who sent it and what it is.
    pub id: MessageId,
    /// Its transfer ID.
    pub transfer_id: u8,
    /// Payload bytes; the first `len` count.
    pub payload: [u8; MAX_PAYLOAD],
    /// Payload length.
    pub len: usize,
}

impl Transfer {
    /// The payload.
    pub fn payload(&self) -> &[u8] {
        &self.payload[..self.len]
    }
}

/// Why a frame was not taken.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameError {
    /// No data bytes (no tail byte).
    Empty,
    /// A service frame or an anonymous one.
    NotAMessage,
    /// A frame in the middle of a transfer whose start was not seen (or was dropped).
    NoStart,
    /// The toggle bit was not the one expected next: a frame lost or repeated.
    Toggle,
    /// The transfer ID changed in the middle of a transfer.
    TransferId,
    /// More payload than [`MAX_PAYLOAD`].
    TooLong,
    /// The first frame of a multi-frame transfer had no room for the CRC.
    Short,
    /// The transfer CRC did not check.
    Crc,
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Empty => "a frame without data",
            Self::NotAMessage => "a service or anonymous frame",
            Self::NoStart => "a frame of a transfer whose start was not seen",
            Self::Toggle => "a frame out of order (toggle bit)",
            Self::TransferId => "a frame of another transfer in the middle of one",
            Self::TooLong => "a transfer longer than the node takes",
            Self::Short => "a multi-frame transfer's first frame too short for its CRC",
            Self::Crc => "a transfer whose CRC does not check",
        })
    }
}

#[derive(Clone, Copy)]
struct Slot<const PAYLOAD: usize> {
    key: Option<(u8, u16)>,
    transfer_id: u8,
    toggle: bool,
    crc: u16,
    payload: [u8; PAYLOAD],
    len: usize,
    last_us: u64,
}

impl<const PAYLOAD: usize> Slot<PAYLOAD> {
    const EMPTY: Self = Self {
        key: None,
        transfer_id: 0,
        toggle: false,
        crc: 0,
        payload: [0; PAYLOAD],
        len: 0,
        last_us: 0,
    };
}

/// Puts multi-frame transfers back together: up to `SLOTS` at once, one per source and data
/// type (the oldest is given up for a new one past that), each of at most `PAYLOAD` bytes
/// (at most [`MAX_PAYLOAD`]; a node that reads only short transfers keeps smaller slots).
pub struct Reassembler<const SLOTS: usize, const PAYLOAD: usize = MAX_PAYLOAD> {
    slots: [Slot<PAYLOAD>; SLOTS],
}

impl<const SLOTS: usize, const PAYLOAD: usize> Default for Reassembler<SLOTS, PAYLOAD> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const SLOTS: usize, const PAYLOAD: usize> Reassembler<SLOTS, PAYLOAD> {
    /// Nothing in progress.
    pub const fn new() -> Self {
        const { assert!(SLOTS > 0, "a reassembler needs a slot") };
        const {
            assert!(
                PAYLOAD <= MAX_PAYLOAD,
                "a transfer holds at most MAX_PAYLOAD"
            )
        };
        Self {
            slots: [Slot::EMPTY; SLOTS],
        }
    }

    /// Takes one frame received at `now_us`, of a data type whose signature is `signature`.
    /// A whole transfer when this frame ends one; `Ok(None)` in the middle of one.
    pub fn accept(
        &mut self,
        frame: &CanFrame,
        signature: u64,
        now_us: u64,
    ) -> Result<Option<Transfer>, FrameError> {
        let bytes = frame.bytes();
        let Some((&tail, data)) = bytes.split_last() else {
            return Err(FrameError::Empty);
        };
        let id = MessageId::from_can_id(frame.id).ok_or(FrameError::NotAMessage)?;
        let (start, end, toggle) = (tail & 0x80 != 0, tail & 0x40 != 0, tail & 0x20 != 0);
        let transfer_id = tail & 0x1f;
        let key = (id.source, id.data_type);
        if start && end {
            let mut payload = [0u8; MAX_PAYLOAD];
            payload[..data.len()].copy_from_slice(data);
            return Ok(Some(Transfer {
                id,
                transfer_id,
                payload,
                len: data.len(),
            }));
        }
        if start {
            if toggle {
                return Err(FrameError::Toggle);
            }
            let [lo, hi, rest @ ..] = data else {
                return Err(FrameError::Short);
            };
            if rest.len() > PAYLOAD {
                return Err(FrameError::TooLong);
            }
            let slot = self.slot_for(key);
            *slot = Slot {
                key: Some(key),
                transfer_id,
                toggle: true,
                crc: u16::from_le_bytes([*lo, *hi]),
                payload: [0; PAYLOAD],
                len: rest.len(),
                last_us: now_us,
            };
            slot.payload[..rest.len()].copy_from_slice(rest);
            return Ok(None);
        }
        let Some(slot) = self.slots.iter_mut().find(|s| s.key == Some(key)) else {
            return Err(FrameError::NoStart);
        };
        let fault = if transfer_id != slot.transfer_id {
            Some(FrameError::TransferId)
        } else if toggle != slot.toggle {
            Some(FrameError::Toggle)
        } else if slot.len + data.len() > PAYLOAD {
            Some(FrameError::TooLong)
        } else {
            None
        };
        if let Some(fault) = fault {
            slot.key = None;
            return Err(fault);
        }
        slot.payload[slot.len..slot.len + data.len()].copy_from_slice(data);
        slot.len += data.len();
        slot.toggle = !slot.toggle;
        slot.last_us = now_us;
        if !end {
            return Ok(None);
        }
        slot.key = None;
        if transfer_crc(signature, &slot.payload[..slot.len]) != slot.crc {
            return Err(FrameError::Crc);
        }
        let mut payload = [0u8; MAX_PAYLOAD];
        payload[..slot.len].copy_from_slice(&slot.payload[..slot.len]);
        Ok(Some(Transfer {
            id,
            transfer_id,
            payload,
            len: slot.len,
        }))
    }

    /// The slot of `key`, else a free one, else the one heard from longest ago.
    fn slot_for(&mut self, key: (u8, u16)) -> &mut Slot<PAYLOAD> {
        let index = self
            .slots
            .iter()
            .position(|s| s.key == Some(key))
            .or_else(|| self.slots.iter().position(|s| s.key.is_none()))
            .or_else(|| (0..SLOTS).min_by_key(|&i| self.slots[i].last_us))
            .unwrap_or(0);
        &mut self.slots[index]
    }
}
