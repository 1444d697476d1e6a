//! Parameter storage that survives a power cut at any instant: a
//! `sequential-storage` map over any NOR flash (`embedded-storage-async`), keyed by the
//! parameter's name, one item per changed parameter.
//!
//! `sequential-storage` writes each item with its own CRC and only ever appends; a page is
//! erased only after its live items were copied on. So a cut in the middle of a write leaves
//! the item it was writing unreadable (skipped: the older value is found) and a cut in an
//! erase leaves a page the next start repairs. Either way a parameter reads back as its old
//! or its new value, never anything else; the tests below cut the power at every write and
//! erase step of a long run of changes, partway through the operation, and check exactly that.
//!
//! Keys are names, not indices, so a firmware whose table gains or reorders parameters still
//! finds the stored ones; a stored value the current table refuses (a range that shrank) is
//! dropped in favour of the default and counted.

use core::ops::Range;

use crate::slots::Slots;
use embedded_storage_async::nor_flash::{NorFlash, NorFlashError, NorFlashErrorKind};
use link::signing::KEY_LEN;
use sequential_storage::cache::{Cache, Uncached};
use sequential_storage::map::{MapConfig, MapStorage};
use shared::mission::params::{NAME_LEN, ParamValues, TABLE};

/// Bytes of the work buffer: a key (16) and a value (4 for a parameter, 32 for the signing
/// key), rounded up to any flash's word (up to 32 bytes).
const BUFFER_LEN: usize = 96;

/// Why the store failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoreError {
    /// The flash range does not suit the flash (pages, alignment, at least two pages).
    BadRange,
    /// The flash itself reported an error.
    Flash(NorFlashErrorKind),
    /// No room left for the item (never with the ranges used: every parameter fits many
    /// times).
    Full,
    /// The stored data did not hold together even after repair; the range was erased.
    Corrupted,
    /// Any other error of the storage layer.
    Other,
    /// The board keeps no room for a payload description, or it is larger than a slot.
    NoRoom,
}

impl core::fmt::Display for StoreError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BadRange => write!(f, "the storage range does not fit the flash"),
            Self::Flash(kind) => write!(f, "flash error: {kind}"),
            Self::Full => write!(f, "parameter storage full"),
            Self::Corrupted => write!(f, "parameter storage corrupted; erased, defaults used"),
            Self::Other => write!(f, "parameter storage error"),
            Self::NoRoom => write!(f, "no storage room for the payload description"),
        }
    }
}

fn error<E: NorFlashError>(e: sequential_storage::Error<E>) -> StoreError {
    match e {
        sequential_storage::Error::Storage { value, .. } => StoreError::Flash(value.kind()),
        sequential_storage::Error::FullStorage => StoreError::Full,
        sequential_storage::Error::Corrupted { .. } => StoreError::Corrupted,
        _ => StoreError::Other,
    }
}

/// What [`ParamStore::load`] found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Loaded {
    /// Parameters restored from storage.
    pub restored: usize,
    /// Stored values the table refuses now (left at their defaults).
    pub refused: usize,
    /// A storage error (all parameters not yet read stay at their defaults).
    pub error: Option<StoreError>,
}

/// No cache: parameters are read once at start and written rarely.
type NoCache = Cache<Uncached, Uncached, Uncached, [u8; NAME_LEN]>;

/// The parameters' storage on a flash `F`.
pub struct ParamStore<F: NorFlash> {
    /// The map (it owns the flash; lent out, briefly, to the payload slots).
    map: Option<MapStorage<[u8; NAME_LEN], F, NoCache>>,
    config: Range<u32>,
    buffer: [u8; BUFFER_LEN],
    payload: Option<Slots>,
    mission: Option<Slots>,
}

/// Storage names of the signing key and timestamp (not parameter names: no parameter has
/// the `SIGN_` prefix, a test checks it).
const SIGNING_KEY: &str = "SIGN_KEY";
const SIGNING_TIMESTAMP: &str = "SIGN_TS";

fn named(name: &str) -> [u8; NAME_LEN] {
    let mut k = [0u8; NAME_LEN];
    let name = name.as_bytes();
    k[..name.len()].copy_from_slice(name);
    k
}

fn key(index: usize) -> [u8; NAME_LEN] {
    let mut k = [0u8; NAME_LEN];
    let name = TABLE[index].name.as_bytes();
    k[..name.len()].copy_from_slice(name);
    k
}

impl<F: NorFlash> ParamStore<F> {
    /// The store on `range` of `flash` (whole erase pages, at least two).
    pub fn new(flash: F, range: Range<u32>) -> Result<Self, StoreError> {
        let config = MapConfig::try_new(range.clone()).map_err(|_| StoreError::BadRange)?;
        Ok(Self {
            map: Some(MapStorage::new(flash, config, Cache::new_uncached())),
            config: range,
            buffer: [0; BUFFER_LEN],
            payload: None,
            mission: None,
        })
    }

    /// Keeps the payload description in `range` too (two slots of whole erase pages, apart
    /// from the parameters' range).
    pub fn with_payload(mut self, range: Range<u32>) -> Result<Self, StoreError> {
        let overlaps = range.start < self.config.end && self.config.start < range.end;
        let slots = Slots::new(range, F::ERASE_SIZE).ok_or(StoreError::BadRange)?;
        if overlaps {
            return Err(StoreError::BadRange);
        }
        self.payload = Some(slots);
        Ok(self)
    }

    /// Keeps the mission's items in `range` too (two slots of whole erase pages, apart from
    /// the parameters' and the payload description's ranges).
    pub fn with_mission(mut self, range: Range<u32>) -> Result<Self, StoreError> {
        let apart = |r: &Range<u32>| range.end <= r.start || r.end <= range.start;
        let payload = self.payload.as_ref().map(Slots::range);
        if !apart(&self.config) || payload.is_some_and(|p| !apart(&p)) {
            return Err(StoreError::BadRange);
        }
        self.mission = Some(Slots::new(range, F::ERASE_SIZE).ok_or(StoreError::BadRange)?);
        Ok(self)
    }

    /// Stores the mission's `bytes` (a power cut leaves the one before readable).
    pub async fn save_mission(&mut self, bytes: &[u8]) -> Result<(), StoreError> {
        let slots = self.mission.clone().ok_or(StoreError::NoRoom)?;
        self.save_in(slots, bytes).await
    }

    /// The stored mission that passes `valid`, read into `into`: its length.
    pub async fn load_mission(
        &mut self,
        into: &mut [u8],
        valid: impl Fn(&[u8]) -> bool,
    ) -> Result<Option<usize>, StoreError> {
        let Some(slots) = self.mission.clone() else {
            return Ok(None);
        };
        let mut flash = self.lend()?;
        let loaded = slots.load(&mut flash, into, valid).await;
        self.give_back(flash)?;
        loaded.map_err(|e| StoreError::Flash(e.kind()))
    }

    async fn save_in(&mut self, slots: Slots, bytes: &[u8]) -> Result<(), StoreError> {
        let mut flash = self.lend()?;
        let saved = slots.save(&mut flash, bytes).await;
        self.give_back(flash)?;
        match saved {
            Ok(true) => Ok(()),
            Ok(false) => Err(StoreError::NoRoom),
            Err(e) => Err(StoreError::Flash(e.kind())),
        }
    }

    /// The flash out of the map, for the payload slots; [`Self::give_back`] returns it.
    fn lend(&mut self) -> Result<F, StoreError> {
        Ok(self.map.take().ok_or(StoreError::Other)?.destroy().0)
    }

    fn give_back(&mut self, flash: F) -> Result<(), StoreError> {
        let config = MapConfig::try_new(self.config.clone()).map_err(|_| StoreError::BadRange)?;
        self.map = Some(MapStorage::new(flash, config, Cache::new_uncached()));
        Ok(())
    }

    /// Stores the payload description `bytes` (a power cut leaves the one before readable).
    pub async fn save_payload(&mut self, bytes: &[u8]) -> Result<(), StoreError> {
        let slots = self.payload.clone().ok_or(StoreError::NoRoom)?;
        self.save_in(slots, bytes).await
    }

    /// The stored payload description that passes `valid`, read into `into`: its length.
    pub async fn load_payload(
        &mut self,
        into: &mut [u8],
        valid: impl Fn(&[u8]) -> bool,
    ) -> Result<Option<usize>, StoreError> {
        let Some(slots) = self.payload.clone() else {
            return Ok(None);
        };
        let mut flash = self.lend()?;
        let loaded = slots.load(&mut flash, into, valid).await;
        self.give_back(flash)?;
        loaded.map_err(|e| StoreError::Flash(e.kind()))
    }

    /// Sets `values` from storage: every parameter stored and still acceptable.
    pub async fn load(&mut self, values: &mut ParamValues) -> Loaded {
        let mut loaded = Loaded::default();
        for index in 0..TABLE.len() {
            let Ok(map) = self.map.as_mut().ok_or(StoreError::Other) else {
                loaded.error = Some(StoreError::Other);
                break;
            };
            match map.fetch_item::<f32>(&mut self.buffer, &key(index)).await {
                Ok(Some(v)) => match values.set(index, v) {
                    Ok(()) => loaded.restored += 1,
                    Err(_) => loaded.refused += 1,
                },
                Ok(None) => {}
                Err(e) => {
                    let e = error(e);
                    if e == StoreError::Corrupted {
                        // Beyond repair: start over rather than fail on every start.
                        let _ = map.erase_all().await;
                    }
                    loaded.error = Some(e);
                    break;
                }
            }
        }
        loaded
    }

    /// Stores parameter `index` (of the table) as `value`.
    pub async fn save(&mut self, index: usize, value: f32) -> Result<(), StoreError> {
        if index >= TABLE.len() {
            return Err(StoreError::Other);
        }
        let buffer = &mut self.buffer;
        self.map
            .as_mut()
            .ok_or(StoreError::Other)?
            .store_item(buffer, &key(index), &value)
            .await
            .map_err(error)
    }

    /// Stores the signing key and the vehicle's signing timestamp (an all-zero key: signing
    /// off).
    pub async fn save_signing(
        &mut self,
        key: &[u8; KEY_LEN],
        timestamp: u64,
    ) -> Result<(), StoreError> {
        let map = self.map.as_mut().ok_or(StoreError::Other)?;
        map.store_item(&mut self.buffer, &named(SIGNING_KEY), key)
            .await
            .map_err(error)?;
        map.store_item(&mut self.buffer, &named(SIGNING_TIMESTAMP), &timestamp)
            .await
            .map_err(error)
    }

    /// The stored signing key and timestamp, if a key other than all zeros is stored.
    pub async fn load_signing(&mut self) -> Result<Option<([u8; KEY_LEN], u64)>, StoreError> {
        let map = self.map.as_mut().ok_or(StoreError::Other)?;
        let key = map
            .fetch_item::<[u8; KEY_LEN]>(&mut self.buffer, &named(SIGNING_KEY))
            .await
            .map_err(error)?;
        let timestamp = map
            .fetch_item::<u64>(&mut self.buffer, &named(SIGNING_TIMESTAMP))
            .await
            .map_err(error)?;
        Ok(match key {
            Some(k) if k != [0; KEY_LEN] => Some((k, timestamp.unwrap_or(0))),
            _ => None,
        })
    }

    /// The flash back (`None` only if a payload access was cut short by a flash error).
    pub fn into_flash(self) -> Option<F> {
        self.map.map(|m| m.destroy().0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use shared::mission::params::COUNT;
    use std::vec::Vec;
    use test_support::flash::{Cut, CutFlash, PAGE, block_on};
    use test_support::rng::Rng;

    const PAGES: usize = 4;

    /// The changes of a run: (parameter, value), all in range; few parameters, so pages fill
    /// and are collected many times.
    fn changes(seed: u64, n: usize) -> Vec<(usize, f32)> {
        let mut rng = Rng::new(seed | 1);
        (0..n)
            .map(|_| {
                let i = (rng.next_u64() % 6) as usize * 7 % COUNT;
                let spec = &TABLE[i];
                let t = (rng.next_u64() % 1000) as f32 / 1000.0;
                (i, spec.valid_value(t))
            })
            .collect()
    }

    /// Runs `changes` until the power dies after `budget` operations (with `partial` of the
    /// last one done), restarts, and checks every parameter is its last saved value or, for
    /// the one being saved at the cut, the new one. Returns whether the cut came before the
    /// end.
    fn run_with_cut(changes: &[(usize, f32)], budget: usize, partial: u8) -> bool {
        let mut flash = CutFlash::new(PAGES);
        flash.plan(Cut::AtOperation {
            after: budget,
            share: partial,
        });
        let mut saved = ParamValues::DEFAULT;
        let mut in_flight = None;
        let mut store = ParamStore::new(flash, 0..(PAGE * PAGES) as u32).expect("range");
        let mut cut = false;
        for &(i, v) in changes {
            match block_on(store.save(i, v)) {
                Ok(()) => saved.set(i, v).expect("in range"),
                Err(_) => {
                    in_flight = Some((i, v));
                    cut = true;
                    break;
                }
            }
        }
        let mut flash = store.into_flash().expect("the flash");
        flash.restart();
        let mut store = ParamStore::new(flash, 0..(PAGE * PAGES) as u32).expect("range");
        let mut after = ParamValues::DEFAULT;
        let loaded = block_on(store.load(&mut after));
        assert_eq!(loaded.error, None, "budget {budget}: {loaded:?}");
        assert_eq!(loaded.refused, 0);
        for (i, spec) in TABLE.iter().enumerate() {
            let got = after.get(i);
            let old = saved.get(i);
            let ok = got == old || in_flight.is_some_and(|(j, v)| j == i && got == Some(v));
            assert!(
                ok,
                "budget {budget} partial {partial}: {} read {got:?}, saved {old:?}, in flight {in_flight:?}",
                spec.name
            );
        }
        // The store still works after the cut.
        let (i, v) = changes[0];
        block_on(store.save(i, v)).expect("saves after restart");
        let mut again = ParamValues::DEFAULT;
        block_on(store.load(&mut again));
        assert_eq!(again.get(i), Some(v));
        cut
    }

    #[test]
    fn values_survive_a_restart() {
        let mut store =
            ParamStore::new(CutFlash::new(PAGES), 0..(PAGE * PAGES) as u32).expect("range");
        let mut values = ParamValues::DEFAULT;
        assert_eq!(block_on(store.load(&mut values)).restored, 0);
        block_on(store.save(3, 0.05)).expect("saved");
        block_on(store.save(3, 0.06)).expect("saved");
        let flash = store.into_flash().expect("the flash");
        let mut store = ParamStore::new(flash, 0..(PAGE * PAGES) as u32).expect("range");
        let loaded = block_on(store.load(&mut values));
        assert_eq!((loaded.restored, loaded.error), (1, None));
        assert_eq!(values.get(3), Some(0.06));
        assert_eq!(values.get(4), Some(TABLE[4].default_value()));
    }

    #[test]
    fn the_signing_key_survives_a_restart_beside_the_parameters() {
        assert!(!TABLE.iter().any(|p| p.name.starts_with("SIGN_")));
        let mut store =
            ParamStore::new(CutFlash::new(PAGES), 0..(PAGE * PAGES) as u32).expect("range");
        assert_eq!(block_on(store.load_signing()), Ok(None));
        block_on(store.save(3, 0.05)).expect("saved");
        block_on(store.save_signing(&[5; KEY_LEN], 123_456)).expect("saved");
        let flash = store.into_flash().expect("the flash");
        let mut store = ParamStore::new(flash, 0..(PAGE * PAGES) as u32).expect("range");
        assert_eq!(
            block_on(store.load_signing()),
            Ok(Some(([5; KEY_LEN], 123_456)))
        );
        let mut values = ParamValues::DEFAULT;
        let loaded = block_on(store.load(&mut values));
        assert_eq!((loaded.restored, loaded.error), (1, None));
        // An all-zero key is signing switched off.
        block_on(store.save_signing(&[0; KEY_LEN], 0)).expect("saved");
        assert_eq!(block_on(store.load_signing()), Ok(None));
    }

    #[test]
    fn a_stored_value_the_table_now_refuses_is_dropped() {
        let mut store =
            ParamStore::new(CutFlash::new(PAGES), 0..(PAGE * PAGES) as u32).expect("range");
        // Written as a firmware with a wider range might have.
        block_on(store.save(1, 1e6)).expect("saved");
        let mut values = ParamValues::DEFAULT;
        let loaded = block_on(store.load(&mut values));
        assert_eq!(loaded.refused, 1);
        assert_eq!(values.get(1), Some(TABLE[1].default_value()));
    }

    #[test]
    fn a_power_cut_at_every_step_leaves_old_or_new_values() {
        // 300 changes of six parameters: pages fill and are collected repeatedly.
        let run = changes(7, 300);
        let mut budget = 0;
        let mut trials = 0;
        // Every operation of the run is the one the power dies in, cut halfway through.
        while run_with_cut(&run, budget, 128) {
            budget += 1;
            trials += 1;
        }
        std::eprintln!("power cut at each of {trials} write/erase steps");
        assert!(trials > 600, "only {trials} steps: the run is too short");
    }

    #[test]
    fn random_power_cuts_leave_old_or_new_values() {
        let mut rng = Rng::new(0x5eed);
        for trial in 0..2000u64 {
            let run = changes(trial + 1, 120);
            let budget = (rng.next_u64() % 400) as usize;
            let partial = (rng.next_u64() % 256) as u8;
            run_with_cut(&run, budget, partial);
        }
    }

    /// Two payload slots of two pages each, after the parameters' pages.
    const PAYLOAD: Range<u32> = (PAGE * PAGES) as u32..(PAGE * (PAGES + 4)) as u32;

    fn with_payload(flash: CutFlash) -> ParamStore<CutFlash> {
        ParamStore::new(flash, 0..(PAGE * PAGES) as u32)
            .and_then(|s| s.with_payload(PAYLOAD))
            .expect("ranges")
    }

    /// A description as the test writes them: `len` bytes of `fill` (and a check for it).
    fn uniform(bytes: &[u8]) -> bool {
        bytes.iter().all(|&b| b == bytes[0])
    }

    #[test]
    fn the_payload_description_survives_a_restart_beside_the_parameters() {
        let mut store = with_payload(CutFlash::new(PAGES + 4));
        let mut into = [0u8; 2048];
        assert_eq!(block_on(store.load_payload(&mut into, uniform)), Ok(None));
        block_on(store.save(3, 0.05)).expect("saved");
        block_on(store.save_payload(&[7; 1500])).expect("saved");
        block_on(store.save_payload(&[9; 983])).expect("saved");
        let flash = store.into_flash().expect("the flash");
        let mut store = with_payload(flash);
        assert_eq!(
            block_on(store.load_payload(&mut into, uniform)),
            Ok(Some(983))
        );
        assert_eq!(into[..983], [9; 983]);
        let mut values = ParamValues::DEFAULT;
        assert_eq!(block_on(store.load(&mut values)).restored, 1);
        // Too large for a slot, or a range on the parameters: refused.
        assert_eq!(
            block_on(store.save_payload(&[1; 2 * PAGE])),
            Err(StoreError::NoRoom)
        );
        let flash = store.into_flash().expect("the flash");
        let overlapping = ParamStore::new(flash, 0..(PAGE * PAGES) as u32)
            .and_then(|s| s.with_payload(0..(4 * PAGE) as u32));
        assert_eq!(overlapping.err(), Some(StoreError::BadRange));
    }

    #[test]
    fn a_power_cut_at_every_step_of_a_payload_save_keeps_the_old_or_the_new() {
        let mut trials = 0;
        for partial in [0u8, 128, 255] {
            for budget in 0.. {
                let mut store = with_payload(CutFlash::new(PAGES + 4));
                block_on(store.save_payload(&[1; 1200])).expect("saved");
                block_on(store.save_payload(&[2; 900])).expect("saved");
                let mut flash = store.into_flash().expect("the flash");
                flash.plan(Cut::AtOperation {
                    after: budget,
                    share: partial,
                });
                let mut store = with_payload(flash);
                let finished = block_on(store.save_payload(&[3; 1000])).is_ok();
                let mut flash = match store.into_flash() {
                    Some(f) => f,
                    None => break,
                };
                flash.restart();
                let mut store = with_payload(flash);
                let mut into = [0u8; 2048];
                let got = block_on(store.load_payload(&mut into, uniform)).expect("read");
                let found = got.map(|n| (into[0], n));
                if finished {
                    assert_eq!(found, Some((3, 1000)), "budget {budget}");
                    break;
                }
                assert!(
                    found == Some((2, 900)) || found == Some((3, 1000)),
                    "cut at step {budget} ({partial}/256): read {found:?}"
                );
                trials += 1;
            }
        }
        std::eprintln!("payload save cut at each of {trials} steps");
        assert!(trials > 20, "only {trials} steps");
    }

    #[test]
    fn a_range_that_does_not_fit_the_flash_is_refused() {
        assert_eq!(
            ParamStore::new(CutFlash::new(PAGES), 0..PAGE as u32).err(),
            Some(StoreError::BadRange)
        );
        assert_eq!(
            ParamStore::new(CutFlash::new(PAGES), 100..(2 * PAGE) as u32).err(),
            Some(StoreError::BadRange)
        );
    }
}
