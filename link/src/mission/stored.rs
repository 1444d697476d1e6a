//! The mission's items as stored beside the payload description (two power-cut-safe slots,
//! `onboard::slots`; docs/ground-link.md#missions): a magic word, the count, the items
//! ([`WireItem::to_bytes`]) and a CRC-32 of all before it, so a torn or foreign slot is never
//! read as a mission.

use heapless::Vec;
use shared::mission::params::metadata::crc32;

use crate::mission::MAX_ITEMS;
use crate::mission::wire::{ITEM_BYTES, WireItem};

const MAGIC: [u8; 4] = *b"MIS1";
/// Bytes of a stored mission of `MAX_ITEMS` items.
pub const MAX_STORED_LEN: usize = 4 + 2 + MAX_ITEMS * ITEM_BYTES + 4;

/// `items` as stored: their bytes in `out`, returns the length.
pub fn encode(items: &[WireItem], out: &mut [u8; MAX_STORED_LEN]) -> usize {
    let items = &items[..items.len().min(MAX_ITEMS)];
    out[..4].copy_from_slice(&MAGIC);
    out[4..6].copy_from_slice(&(items.len() as u16).to_le_bytes());
    let mut at = 6;
    for item in items {
        out[at..at + ITEM_BYTES].copy_from_slice(&item.to_bytes());
        at += ITEM_BYTES;
    }
    let crc = crc32(&out[..at]);
    out[at..at + 4].copy_from_slice(&crc.to_le_bytes());
    at + 4
}

/// The items of stored `bytes`, or `None` when they are not a whole mission.
pub fn decode(bytes: &[u8]) -> Option<Vec<WireItem, MAX_ITEMS>> {
    let count = usize::from(u16::from_le_bytes([*bytes.get(4)?, *bytes.get(5)?]));
    let end = 6 + count.checked_mul(ITEM_BYTES)?;
    if bytes.get(..4)? != MAGIC || count > MAX_ITEMS || bytes.len() != end + 4 {
        return None;
    }
    let crc = u32::from_le_bytes(bytes[end..end + 4].try_into().ok()?);
    if crc32(&bytes[..end]) != crc {
        return None;
    }
    let mut items = Vec::new();
    for chunk in bytes[6..end].chunks_exact(ITEM_BYTES) {
        let item: &[u8; ITEM_BYTES] = chunk.try_into().ok()?;
        items.push(WireItem::from_bytes(item)).ok()?;
    }
    Some(items)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stored_mission_reads_back_and_a_damaged_one_does_not() {
        let items: std::vec::Vec<WireItem> = (0..MAX_ITEMS)
            .map(|i| WireItem {
                command: 16,
                frame: 6,
                x: i as i32,
                z: 0.5,
                ..Default::default()
            })
            .collect();
        let mut buf = [0u8; MAX_STORED_LEN];
        let n = encode(&items, &mut buf);
        assert_eq!(n, MAX_STORED_LEN);
        let back = decode(&buf[..n]).expect("whole");
        assert_eq!(back.len(), MAX_ITEMS);
        assert_eq!(back[7].x, 7);
        for i in 0..n {
            let mut torn = buf;
            torn[i] ^= 0x40;
            assert!(decode(&torn[..n]).is_none(), "byte {i} changed");
        }
        assert!(decode(&buf[..n - 1]).is_none());
        let n = encode(&[], &mut buf);
        assert_eq!(decode(&buf[..n]).map(|v| v.len()), Some(0));
    }
}
