//! The Pixhawk 6C's microSD card, where its flight logs are kept (docs/formats.md#flight-logs,
//! docs/firmware.md#memory): the embassy glue under `drivers::sd_logs`, which does the naming,
//! numbering and errors over `embedded-sdmmc`'s FAT.
//!
//! The card is on SDMMC2, 4 bits wide (PX4's fmu-v6c `board.h`: CK PD6, CMD PD7, D0 PB14,
//! D1 PB15, D2 PB3, D3 PB4), its kernel clock PLL1Q at 240 MHz, identified at 400 kHz and
//! then clocked at 24 MHz (PX4's divider of 5). The board has no card-detect line: a card is
//! missing when it does not answer, which the logs report at the first use ("no microSD
//! card"). A card that fails a transfer is identified again at the next access (pulled out
//! and pushed back in between flights).
//!
//! `embedded-sdmmc`'s block device is synchronous and embassy's SDMMC driver asynchronous:
//! each block transfer is run to its end with `embassy_futures::block_on`, which polls it
//! without sleeping. Only the logger task calls it, in thread mode at the lowest priority: a
//! transfer (about a millisecond, a card's busy time up to a few hundred) delays the
//! thread-mode jobs, never the control step or the link, which preempt it. The control step
//! meanwhile writes into the ring, which drops what does not fit.
//!
//! Everything here lives in the log memory (`.log_ram`, memory.x): the driver, its 512-byte
//! DMA block (SDMMC2's internal DMA reaches the AXI SRAM, not the DTCM) and the file
//! system's block cache.
//!
//! Not yet run on a board (docs/hardware.md): it builds, and its logic is host-tested.

use core::cell::RefCell;

use drivers::sd_logs::{Block, BlockCount, BlockDevice, BlockIdx, FixedTime, SdLogError, SdLogs};
use embassy_futures::block_on;
use embassy_stm32::sdmmc::sd::{Addressable, Card, CmdBlock, DataBlock, StorageDevice};
use embassy_stm32::sdmmc::{self, Sdmmc};
use embassy_stm32::time::Hertz;
use flight_log::keeper::LogStorage;

use super::LogRam;

/// The card's clock once identified: 240 MHz / (2 x 5), as PX4 clocks it.
pub const CARD_HZ: u32 = 24_000_000;

/// Why the card failed a transfer (embassy's SDMMC error).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CardError(sdmmc::Error);

impl core::fmt::Display for CardError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self.0 {
            sdmmc::Error::Timeout | sdmmc::Error::SoftwareTimeout => "no answer",
            sdmmc::Error::NoCard => "no card",
            sdmmc::Error::Crc => "CRC error",
            sdmmc::Error::UnsupportedCardVersion | sdmmc::Error::UnsupportedCardType => {
                "unsupported card"
            }
            sdmmc::Error::UnsupportedVoltage => "unsupported voltage",
            sdmmc::Error::Underrun => "FIFO underrun",
            _ => "SDMMC error",
        })
    }
}

impl core::error::Error for CardError {}

/// The card and the driver's buffers.
struct CardState {
    storage: StorageDevice<'static, 'static, Card>,
    /// Whether the card was identified and answered its last transfer.
    ready: bool,
    /// The DMA block every transfer goes through (embassy's driver wants it word-aligned).
    block: DataBlock,
    /// The DMA buffer of identification's data commands.
    command: CmdBlock,
}

impl CardState {
    /// Identifies the card if it is not ready.
    fn ready(&mut self) -> Result<(), CardError> {
        if !self.ready {
            block_on(self.storage.reacquire(&mut self.command, Hertz(CARD_HZ)))
                .map_err(CardError)?;
            self.ready = true;
        }
        Ok(())
    }

    /// A failed transfer: the card is identified again at the next.
    fn failed(&mut self, e: sdmmc::Error) -> CardError {
        self.ready = false;
        CardError(e)
    }
}

/// The card as `embedded-sdmmc`'s block device.
pub struct SdCard(RefCell<CardState>);

impl BlockDevice for SdCard {
    type Error = CardError;

    fn read(&self, blocks: &mut [Block], start: BlockIdx) -> Result<(), CardError> {
        let mut card = self.0.borrow_mut();
        card.ready()?;
        for (index, block) in (start.0..).zip(blocks.iter_mut()) {
            let state = &mut *card;
            block_on(state.storage.read_block(index, &mut state.block))
                .map_err(|e| state.failed(e))?;
            block.contents.copy_from_slice(&state.block[..]);
        }
        Ok(())
    }

    fn write(&self, blocks: &[Block], start: BlockIdx) -> Result<(), CardError> {
        let mut card = self.0.borrow_mut();
        card.ready()?;
        for (index, block) in (start.0..).zip(blocks.iter()) {
            let state = &mut *card;
            state.block.copy_from_slice(&block.contents);
            block_on(state.storage.write_block(index, &state.block))
                .map_err(|e| state.failed(e))?;
        }
        Ok(())
    }

    fn num_blocks(&self) -> Result<BlockCount, CardError> {
        let mut card = self.0.borrow_mut();
        card.ready()?;
        Ok(BlockCount(
            (card.storage.card().size() / Block::LEN as u64) as u32,
        ))
    }
}

/// The logs on the card.
type Logs = SdLogs<SdCard, FixedTime>;

#[unsafe(link_section = ".log_ram")]
static SDMMC: LogRam<Sdmmc<'static>> = LogRam::new();
#[unsafe(link_section = ".log_ram")]
static LOGS: LogRam<Logs> = LogRam::new();

/// The board's log storage: the logs on the card (a reference into the log memory, so the
/// logger task's future stays small).
pub struct SdStorage(&'static mut Logs);

/// Takes SDMMC2 for the logs (nothing is sent to the card until the first log operation).
pub fn open(sdmmc: Sdmmc<'static>) -> SdStorage {
    // SAFETY: `sdmmc` owns SDMMC2, which the board's `init` takes once: this runs once.
    let sdmmc = unsafe { SDMMC.init(sdmmc) };
    let card = SdCard(RefCell::new(CardState {
        storage: StorageDevice::new_uninit_sd_card(sdmmc),
        ready: false,
        block: DataBlock::new(),
        command: CmdBlock::new(),
    }));
    // SAFETY: as above, once.
    SdStorage(unsafe { LOGS.init(SdLogs::new(card, FixedTime)) })
}

impl LogStorage for SdStorage {
    type Error = SdLogError<CardError>;
    fn count(&mut self) -> Result<u16, Self::Error> {
        self.0.count()
    }
    fn size(&mut self, id: u16) -> Result<u32, Self::Error> {
        self.0.size(id)
    }
    fn create(&mut self) -> Result<u16, Self::Error> {
        self.0.create()
    }
    fn append(&mut self, bytes: &[u8]) -> Result<(), Self::Error> {
        self.0.append(bytes)
    }
    fn close(&mut self) -> Result<(), Self::Error> {
        self.0.close()
    }
    fn read(&mut self, id: u16, offset: u32, buf: &mut [u8]) -> Result<usize, Self::Error> {
        self.0.read(id, offset, buf)
    }
    fn erase_all(&mut self) -> Result<(), Self::Error> {
        self.0.erase_all()
    }
}
