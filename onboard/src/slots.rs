//! The payload description's storage ("stored the same way" as the parameters): two
//! slots on a NOR flash, written in turn, so a power cut at any instant leaves the last whole
//! description readable.
//!
//! A save erases the slot not holding the newest description, writes the bytes, then the
//! header (length, sequence number, and a magic word last): until the header is whole the slot
//! reads as empty. A load reads the slot with the higher sequence number first and takes it
//! if the caller's check holds (the description carries its own CRC-32), the other one
//! otherwise. The tests cut the power at every write and erase, partway through.

use core::ops::Range;

use embedded_storage_async::nor_flash::NorFlash;

/// Bytes of a slot's header: length, sequence number, magic (written last).
pub const HEADER_LEN: usize = 12;
const MAGIC: u32 = u32::from_le_bytes(*b"PLD1");
/// Bytes written per flash write (a multiple of every flash's write size used here).
const CHUNK: usize = 32;

/// Two slots in a flash range.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Slots {
    start: u32,
    slot_len: u32,
}

impl Slots {
    /// The flash range the two slots take.
    pub fn range(&self) -> Range<u32> {
        self.start..self.start + 2 * self.slot_len
    }

    /// Two slots splitting `range` (whole erase pages of `erase_size` each); `None` when the
    /// range cannot be split so.
    pub fn new(range: Range<u32>, erase_size: usize) -> Option<Self> {
        let len = range.end.checked_sub(range.start)?;
        let erase = u32::try_from(erase_size).ok()?;
        let slot_len = len / 2;
        let aligned =
            erase > 0 && range.start.is_multiple_of(erase) && slot_len.is_multiple_of(erase);
        (aligned && slot_len as usize > HEADER_LEN).then_some(Self {
            start: range.start,
            slot_len,
        })
    }

    /// Largest description a slot holds, bytes.
    pub fn capacity(&self) -> usize {
        self.slot_len as usize - HEADER_LEN
    }

    fn offset(&self, slot: u32) -> u32 {
        self.start + slot * self.slot_len
    }

    /// Slot `slot`'s sequence number and length, if its header is whole.
    async fn header<F: NorFlash>(
        &self,
        flash: &mut F,
        slot: u32,
    ) -> Result<Option<(u32, usize)>, F::Error> {
        let mut h = [0u8; HEADER_LEN];
        flash.read(self.offset(slot), &mut h).await?;
        let word = |i: usize| u32::from_le_bytes([h[i], h[i + 1], h[i + 2], h[i + 3]]);
        let len = word(0) as usize;
        Ok((word(8) == MAGIC && len <= self.capacity()).then_some((word(4), len)))
    }

    /// The newest description that passes `valid`, read into `into`: its length, or `None`
    /// when no slot holds one (or it does not fit `into`).
    pub async fn load<F: NorFlash>(
        &self,
        flash: &mut F,
        into: &mut [u8],
        valid: impl Fn(&[u8]) -> bool,
    ) -> Result<Option<usize>, F::Error> {
        let a = self.header(flash, 0).await?;
        let b = self.header(flash, 1).await?;
        let mut order = [(0, a), (1, b)];
        if newer(b, a) {
            order.swap(0, 1);
        }
        for (slot, header) in order {
            let Some((_, len)) = header else { continue };
            if len > into.len() {
                continue;
            }
            flash
                .read(self.offset(slot) + HEADER_LEN as u32, &mut into[..len])
                .await?;
            if valid(&into[..len]) {
                return Ok(Some(len));
            }
        }
        Ok(None)
    }

    /// Saves `bytes` as the newest description. `Ok(false)` when they do not fit a slot.
    pub async fn save<F: NorFlash>(&self, flash: &mut F, bytes: &[u8]) -> Result<bool, F::Error> {
        if bytes.len() > self.capacity() {
            return Ok(false);
        }
        let a = self.header(flash, 0).await?;
        let b = self.header(flash, 1).await?;
        let (slot, newest) = if newer(b, a) { (0, b) } else { (1, a) };
        let seq = newest.map_or(1, |(s, _)| s.wrapping_add(1));
        let at = self.offset(slot);
        flash.erase(at, at + self.slot_len).await?;
        let mut chunk = [0xFF_u8; CHUNK];
        for (i, part) in bytes.chunks(CHUNK).enumerate() {
            chunk.fill(0xFF);
            chunk[..part.len()].copy_from_slice(part);
            // A whole chunk (padded with erased bytes), so every write is aligned.
            let offset = at + (HEADER_LEN + i * CHUNK) as u32;
            let end = (self.slot_len - (HEADER_LEN + i * CHUNK) as u32).min(CHUNK as u32) as usize;
            flash.write(offset, &chunk[..end]).await?;
        }
        let mut header = [0u8; HEADER_LEN];
        header[0..4].copy_from_slice(&(bytes.len() as u32).to_le_bytes());
        header[4..8].copy_from_slice(&seq.to_le_bytes());
        header[8..12].copy_from_slice(&MAGIC.to_le_bytes());
        flash.write(at, &header).await?;
        Ok(true)
    }
}

/// Whether header `x` is of a newer save than `y` (sequence numbers wrap).
fn newer(x: Option<(u32, usize)>, y: Option<(u32, usize)>) -> bool {
    match (x, y) {
        (Some((a, _)), Some((b, _))) => (a.wrapping_sub(b) as i32) > 0,
        (Some(_), None) => true,
        _ => false,
    }
}
