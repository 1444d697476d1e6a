//! A NOR flash in memory whose power fails at a chosen point, for the parameter store's
//! power-cut tests.
//!
//! It follows the Pixhawk's parameter memory, the SPI FRAM on which the board emulates a NOR
//! flash (`firmware/src/board/fram.rs`): writes and erases go byte by byte in address order,
//! and a cut leaves the operation's first bytes done and the rest untouched. A write only
//! clears bits, as on NOR flash (the FRAM stores the bytes as given: the two differ only where
//! a write would set a cleared bit), and an erase sets bytes to `0xFF`. Once the power is cut,
//! every operation fails until [`CutFlash::restart`].

use embedded_storage_async::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};

/// The erase size, bytes (a page of the store).
pub const PAGE: usize = 1024;

/// Where the next power cut comes, counted from when it is planned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cut {
    /// In the write or erase after `after` more of them; `share` / 256 of its bytes happen.
    AtOperation { after: usize, share: u8 },
    /// After `bytes` more bytes written or erased: the operation they end in stops there (a
    /// cut that falls just after an operation's last byte fails the next one, with nothing
    /// done).
    AfterBytes(usize),
}

/// The error of every operation from the cut until the restart.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PowerCut;

impl NorFlashError for PowerCut {
    fn kind(&self) -> NorFlashErrorKind {
        NorFlashErrorKind::Other
    }
}

/// A byte-serial NOR flash that loses power where it is told to.
#[derive(Clone, Debug)]
pub struct CutFlash {
    bytes: Vec<u8>,
    cut: Option<Cut>,
    dead: bool,
    cuts: usize,
}

impl CutFlash {
    /// An erased flash of `pages` pages, no cut planned.
    pub fn new(pages: usize) -> Self {
        Self {
            bytes: vec![0xFF; PAGE * pages],
            cut: None,
            dead: false,
            cuts: 0,
        }
    }

    /// Plans the next power cut (replacing any planned one).
    pub fn plan(&mut self, cut: Cut) {
        self.cut = Some(cut);
    }

    /// The power dies now, between two operations (after the last one's bytes are all in).
    pub fn cut_now(&mut self) {
        if !self.dead {
            self.dead = true;
            self.cuts += 1;
        }
        self.cut = None;
    }

    /// Power back, no cut planned.
    pub fn restart(&mut self) {
        self.dead = false;
        self.cut = None;
    }

    /// Whether the power is off (a cut happened since the last restart).
    pub fn is_dead(&self) -> bool {
        self.dead
    }

    /// How many cuts happened in the flash's life.
    pub fn cuts(&self) -> usize {
        self.cuts
    }

    /// The flash's contents.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// Of an operation of `len` bytes, how many happen: `Err` with that count when the power
    /// dies in it.
    fn take(&mut self, len: usize) -> Result<usize, usize> {
        if self.dead {
            return Err(0);
        }
        let (done, next) = match self.cut {
            None => return Ok(len),
            Some(Cut::AtOperation { after: 0, share }) => {
                (Err(len * usize::from(share) / 256), None)
            }
            Some(Cut::AtOperation { after, share }) => (
                Ok(len),
                Some(Cut::AtOperation {
                    after: after - 1,
                    share,
                }),
            ),
            Some(Cut::AfterBytes(left)) if left < len => (Err(left), None),
            Some(Cut::AfterBytes(left)) => (Ok(len), Some(Cut::AfterBytes(left - len))),
        };
        self.cut = next;
        if done.is_err() {
            self.dead = true;
            self.cuts += 1;
        }
        done
    }
}

impl ErrorType for CutFlash {
    type Error = PowerCut;
}

impl ReadNorFlash for CutFlash {
    const READ_SIZE: usize = 1;

    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), PowerCut> {
        if self.dead {
            return Err(PowerCut);
        }
        let at = offset as usize;
        bytes.copy_from_slice(&self.bytes[at..at + bytes.len()]);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.bytes.len()
    }
}

impl NorFlash for CutFlash {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = PAGE;

    async fn erase(&mut self, from: u32, to: u32) -> Result<(), PowerCut> {
        let (from, to) = (from as usize, to as usize);
        let (done, result) = match self.take(to - from) {
            Ok(n) => (n, Ok(())),
            Err(n) => (n, Err(PowerCut)),
        };
        self.bytes[from..from + done].fill(0xFF);
        result
    }

    async fn write(&mut self, offset: u32, data: &[u8]) -> Result<(), PowerCut> {
        let at = offset as usize;
        let (done, result) = match self.take(data.len()) {
            Ok(n) => (n, Ok(())),
            Err(n) => (n, Err(PowerCut)),
        };
        for (cell, &b) in self.bytes[at..at + done].iter_mut().zip(data) {
            // NOR: a write only clears bits.
            *cell &= b;
        }
        result
    }
}

/// Runs a future to its end on this thread (the store's operations never wait on anything
/// but the flash, which is ready at once).
pub use embassy_futures::block_on;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cut_at_an_operation_does_its_share_and_fails_everything_after() {
        let mut flash = CutFlash::new(2);
        flash.plan(Cut::AtOperation {
            after: 1,
            share: 128,
        });
        assert_eq!(block_on(flash.write(0, &[0; 8])), Ok(()));
        assert_eq!(block_on(flash.write(8, &[0; 8])), Err(PowerCut));
        assert_eq!(flash.bytes()[8..16], [0, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0xFF]);
        assert!(flash.is_dead());
        assert_eq!(block_on(flash.erase(0, PAGE as u32)), Err(PowerCut));
        let mut read = [1; 4];
        assert_eq!(block_on(flash.read(0, &mut read)), Err(PowerCut));
        flash.restart();
        assert_eq!(block_on(flash.read(0, &mut read)), Ok(()));
        assert_eq!((read, flash.cuts()), ([0; 4], 1));
    }

    #[test]
    fn a_cut_after_bytes_stops_inside_the_operation_they_end_in() {
        let mut flash = CutFlash::new(1);
        flash.plan(Cut::AfterBytes(6));
        assert_eq!(block_on(flash.write(0, &[0x0F; 4])), Ok(()));
        assert_eq!(block_on(flash.write(4, &[0x00; 4])), Err(PowerCut));
        assert_eq!(
            flash.bytes()[..8],
            [0x0F, 0x0F, 0x0F, 0x0F, 0, 0, 0xFF, 0xFF]
        );
        // Exactly at an operation's end: that one completes, the next does nothing.
        flash.restart();
        flash.plan(Cut::AfterBytes(4));
        assert_eq!(block_on(flash.write(8, &[0xF0; 4])), Ok(()));
        assert_eq!(block_on(flash.write(12, &[0; 4])), Err(PowerCut));
        assert_eq!(
            flash.bytes()[8..16],
            [0xF0, 0xF0, 0xF0, 0xF0, 0xFF, 0xFF, 0xFF, 0xFF]
        );
        // A write only clears bits; an erase sets them again.
        flash.restart();
        assert_eq!(block_on(flash.write(0, &[0xF0; 4])), Ok(()));
        assert_eq!(flash.bytes()[0], 0x00);
        assert_eq!(block_on(flash.erase(0, PAGE as u32)), Ok(()));
        assert!(flash.bytes().iter().all(|&b| b == 0xFF));
        assert_eq!(flash.cuts(), 2);
    }
}
