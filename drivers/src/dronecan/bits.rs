//! DroneCAN's (UAVCAN v0's) bit packing of a message's fields (DroneCAN specification,
//! "Data structure description language", section "Serialization"): fields follow each other
//! with no padding, bits written most significant first. A field wider than a byte is cut into
//! its little-endian bytes; each whole byte goes in as eight bits, and a last partial byte of
//! `n` bits goes in as that byte's low `n` bits. So an `int14` of 100 (0x0064) is the eight
//! bits of 0x64 followed by the low six bits of 0x00. libcanard's `canardEncodeScalar` and
//! pydronecan pack the same way; the tests hold this code to pydronecan's bytes.

/// A field did not fit in the buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OutOfRoom;

/// Writes fields into a byte buffer, most significant bit first.
pub struct BitWriter<'a> {
    buffer: &'a mut [u8],
    bit: usize,
}

impl<'a> BitWriter<'a> {
    /// A writer at the start of `buffer`; the buffer is cleared.
    pub fn new(buffer: &'a mut [u8]) -> Self {
        buffer.fill(0);
        Self { buffer, bit: 0 }
    }

    /// Bits written so far.
    pub fn bits(&self) -> usize {
        self.bit
    }

    /// Bytes the written bits take (the last one padded with zeros).
    pub fn bytes(&self) -> usize {
        self.bit.div_ceil(8)
    }

    /// Writes the low `width` bits (1 to 64) of `value` as one field.
    pub fn write(&mut self, value: u64, width: u32) -> Result<(), OutOfRoom> {
        if width == 0 || width > 64 || self.bit + width as usize > self.buffer.len() * 8 {
            return Err(OutOfRoom);
        }
        let bytes = value.to_le_bytes();
        let whole = (width / 8) as usize;
        for &byte in &bytes[..whole] {
            self.push(byte, 8);
        }
        let rest = width % 8;
        if rest > 0 {
            self.push(bytes[whole], rest);
        }
        Ok(())
    }

    /// Writes a signed value's low `width` bits (two's complement).
    pub fn write_signed(&mut self, value: i64, width: u32) -> Result<(), OutOfRoom> {
        self.write(value as u64, width)
    }

    /// Writes the low `count` bits of `byte`, most significant first.
    fn push(&mut self, byte: u8, count: u32) {
        for k in (0..count).rev() {
            if byte >> k & 1 == 1 {
                self.buffer[self.bit / 8] |= 0x80 >> (self.bit % 8);
            }
            self.bit += 1;
        }
    }
}

/// Reads fields from a byte buffer the way [`BitWriter`] writes them.
pub struct BitReader<'a> {
    buffer: &'a [u8],
    bit: usize,
}

impl<'a> BitReader<'a> {
    /// A reader at the start of `buffer`.
    pub fn new(buffer: &'a [u8]) -> Self {
        Self { buffer, bit: 0 }
    }

    /// Bits not read yet.
    pub fn remaining(&self) -> usize {
        self.buffer.len() * 8 - self.bit
    }

    /// Reads a field of `width` bits (1 to 64), unsigned.
    pub fn read(&mut self, width: u32) -> Result<u64, OutOfRoom> {
        if width == 0 || width > 64 || width as usize > self.remaining() {
            return Err(OutOfRoom);
        }
        let mut bytes = [0u8; 8];
        let whole = (width / 8) as usize;
        for byte in &mut bytes[..whole] {
            *byte = self.pull(8);
        }
        let rest = width % 8;
        if rest > 0 {
            bytes[whole] = self.pull(rest);
        }
        Ok(u64::from_le_bytes(bytes))
    }

    /// Reads a field of `width` bits as a two's-complement signed value.
    pub fn read_signed(&mut self, width: u32) -> Result<i64, OutOfRoom> {
        let raw = self.read(width)?;
        let shift = 64 - width;
        Ok(((raw << shift) as i64) >> shift)
    }

    /// The next `count` bits as the low bits of a byte.
    fn pull(&mut self, count: u32) -> u8 {
        let mut byte = 0u8;
        for _ in 0..count {
            let bit = self.buffer[self.bit / 8] >> (7 - self.bit % 8) & 1;
            byte = byte << 1 | bit;
            self.bit += 1;
        }
        byte
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fourteen_bit_fields_pack_as_pydronecan_packs_them() {
        // uavcan.equipment.esc.RawCommand cmd = [0, 100, 8191, -8192], pydronecan 1.0.27.
        let mut buffer = [0u8; 7];
        let mut w = BitWriter::new(&mut buffer);
        for v in [0i64, 100, 8191, -8192] {
            w.write_signed(v, 14).expect("room");
        }
        assert_eq!(w.bits(), 56);
        assert_eq!(buffer, [0x00, 0x01, 0x90, 0x0f, 0xf7, 0xc0, 0x20]);
        let mut r = BitReader::new(&buffer);
        for v in [0i64, 100, 8191, -8192] {
            assert_eq!(r.read_signed(14), Ok(v));
        }
        assert_eq!(r.remaining(), 0);
        assert_eq!(r.read(1), Err(OutOfRoom));
    }

    #[test]
    fn every_width_reads_back_what_was_written() {
        let mut buffer = [0u8; 64];
        let mut w = BitWriter::new(&mut buffer);
        let values: [(u64, u32); 8] = [
            (1, 1),
            (5, 3),
            (0x1ff, 9),
            (0xdead, 16),
            (0x2_beef, 18),
            (0xffff_ffff, 32),
            (0x1234_5678_9abc_def0, 64),
            (0x7f, 7),
        ];
        for (v, width) in values {
            w.write(v, width).expect("room");
        }
        let mut r = BitReader::new(&buffer);
        for (v, width) in values {
            assert_eq!(r.read(width), Ok(v), "{width} bits");
        }
    }

    #[test]
    fn a_field_past_the_buffer_is_refused_and_writes_nothing() {
        let mut buffer = [0u8; 2];
        let mut w = BitWriter::new(&mut buffer);
        w.write(0x3ff, 10).expect("room");
        assert_eq!(w.write(0x7f, 7), Err(OutOfRoom));
        assert_eq!(w.write(1, 0), Err(OutOfRoom));
        assert_eq!(w.bits(), 10);
    }
}
