//! The parameter store over many power cuts in one flash's life ("the parameter
//! store keeps the old or the new value after a power cut at any write step, over thousands
//! of random cuts").
//!
//! `onboard::store`'s own tests cut the power once in a fresh flash (at each step of a run, and
//! at 2,000 random steps). Here the same flash lives on through thousands of cuts: writes of
//! any parameter and of the signing key, a cut at a random byte of any write or erase, a
//! restart whose load may itself be cut (a glitch while the store repairs what the last cut
//! left), and writes again on whatever the cuts left. Some cuts come just after a write's last
//! byte, before its acknowledgement: the new value must then be the one read back. After every restart each parameter
//! must read back as its last acknowledged value or, for the one being written at the cut,
//! the new one; a value once read must read the same at every later start; and the store must
//! take a write at once.
//!
//! The flash is `test_support::flash::CutFlash`, the model of the Pixhawk's parameter memory
//! (the SPI FRAM on which the board emulates a NOR flash), here cut at a chosen byte.

use link::signing::KEY_LEN;
use onboard::store::ParamStore;
use shared::mission::params::{COUNT, ParamValues, TABLE};
use test_support::flash::{Cut, CutFlash, PAGE, block_on};
use test_support::rng::Rng;

/// The Pixhawk's parameter range: 8 pages of its FRAM (`PARAM_RANGE` of its board).
const PAGES: usize = 8;
const RANGE: core::ops::Range<u32> = 0..(PAGE * PAGES) as u32;

/// A random write: a parameter (any of the table, in its range) or the signing key.
#[derive(Clone, Copy, Debug)]
enum Write {
    Param(usize, f32),
    Signing([u8; KEY_LEN], u64),
}

fn random_write(rng: &mut Rng) -> Write {
    if rng.below(10) == 0 {
        let key = [1 + rng.below(250) as u8; KEY_LEN];
        return Write::Signing(key, rng.next_u64() >> 16);
    }
    // A few parameters often (pages fill with their old items and are collected), any other
    // sometimes.
    let index = if rng.below(2) == 0 {
        rng.below(4) as usize * 11
    } else {
        rng.below(COUNT as u64) as usize
    };
    let spec = &TABLE[index];
    let t = rng.below(1001) as f32 / 1000.0;
    Write::Param(index, spec.valid_value(t))
}

/// The signing key and timestamp as stored (none: signing off).
type Signing = Option<([u8; KEY_LEN], u64)>;

/// What the store must hold: every parameter's durable value and the signing key's.
#[derive(Clone)]
struct Durable {
    params: ParamValues,
    signing: Signing,
}

/// Loads the store after a restart, the load itself possibly cut (then restarted, until a
/// load runs through): what it read.
fn restart_and_load(
    mut flash: CutFlash,
    rng: &mut Rng,
    cut_loads: &mut usize,
) -> (ParamStore<CutFlash>, ParamValues, Signing) {
    loop {
        flash.restart();
        // Sometimes the power fails again during the start (a repair may write).
        if rng.below(2) == 0 {
            flash.plan(Cut::AfterBytes(rng.below(64) as usize));
        }
        let before = flash.cuts();
        let mut store = ParamStore::new(flash, RANGE).expect("range");
        let mut values = ParamValues::DEFAULT;
        let loaded = block_on(store.load(&mut values));
        let signing = block_on(store.load_signing());
        flash = store.into_flash().expect("the flash");
        if flash.cuts() > before {
            *cut_loads += 1;
            continue;
        }
        assert_eq!(loaded.error, None, "{loaded:?}");
        assert_eq!(loaded.refused, 0, "{loaded:?}");
        let signing = signing.expect("the signing key reads");
        flash.restart();
        let store = ParamStore::new(flash, RANGE).expect("range");
        return (store, values, signing);
    }
}

/// One flash's life of `cycles` runs of random writes, each ended by a cut at a random byte
/// (or, sometimes, by a clean restart); returns the cuts during writes and during loads, and
/// counts in `kept_new` the cut writes whose new value was read back.
fn life(seed: u64, cycles: usize, kept_new: &mut usize) -> (usize, usize) {
    let mut rng = Rng::new(seed | 1);
    let mut durable = Durable {
        params: ParamValues::DEFAULT,
        signing: None,
    };
    let mut flash = CutFlash::new(PAGES);
    let mut cut_loads = 0;
    let mut cut_writes = 0;
    for cycle in 0..cycles {
        // A cut within the next few dozen items (an erase is a page, an item about 32 bytes).
        if rng.below(8) != 0 {
            flash.plan(Cut::AfterBytes(rng.below(3000) as usize));
        }
        let mut store = ParamStore::new(flash, RANGE).expect("range");
        let mut in_flight = None;
        for _ in 0..1 + rng.below(80) {
            let w = random_write(&mut rng);
            let result = match w {
                Write::Param(i, v) => block_on(store.save(i, v)),
                Write::Signing(key, ts) => block_on(store.save_signing(&key, ts)),
            };
            match result {
                // The last step of a write: its bytes are all in, and the power dies before
                // the store's answer reaches the ground (no PARAM_VALUE went out). The value
                // is still in flight; the new one must be what the next start reads.
                Ok(()) if rng.below(12) == 0 => {
                    let mut flash_cut = store.into_flash().expect("the flash");
                    flash_cut.cut_now();
                    store = ParamStore::new(flash_cut, RANGE).expect("range");
                    in_flight = Some(w);
                    cut_writes += 1;
                    break;
                }
                Ok(()) => match w {
                    Write::Param(i, v) => durable.params.set(i, v).expect("in range"),
                    Write::Signing(key, ts) => durable.signing = Some((key, ts)),
                },
                Err(e) => {
                    let flash_cut = store.into_flash().expect("the flash");
                    assert!(
                        flash_cut.is_dead(),
                        "seed {seed} cycle {cycle}: {e} without a cut"
                    );
                    store = ParamStore::new(flash_cut, RANGE).expect("range");
                    in_flight = Some(w);
                    cut_writes += 1;
                    break;
                }
            }
        }
        flash = store.into_flash().expect("the flash");

        let (store, read, signing) = restart_and_load(flash, &mut rng, &mut cut_loads);
        let context = || format!("seed {seed} cycle {cycle}, in flight {in_flight:?}");
        for (i, spec) in TABLE.iter().enumerate() {
            let (got, old) = (read.get(i), durable.params.get(i));
            let new = match in_flight {
                Some(Write::Param(j, v)) if j == i => Some(v),
                _ => None,
            };
            assert!(
                got == old || (new.is_some() && got == new),
                "{}: {} read {got:?}, durable {old:?}",
                context(),
                spec.name
            );
        }
        let allowed = match in_flight {
            // The key is written before the timestamp: the new key may come with the old
            // timestamp (0 if none was stored).
            Some(Write::Signing(key, ts)) => vec![
                durable.signing,
                Some((key, durable.signing.map_or(0, |s| s.1))),
                Some((key, ts)),
            ],
            _ => vec![durable.signing],
        };
        assert!(
            allowed.contains(&signing),
            "{}: signing read {signing:?}, allowed {allowed:?}",
            context()
        );
        if let Some(Write::Param(i, v)) = in_flight
            && read.get(i) == Some(v)
            && durable.params.get(i) != Some(v)
        {
            *kept_new += 1;
        }
        // What was read is what the store holds now: later starts must read the same.
        durable.params = read;
        durable.signing = signing;

        // It takes a write at once (tried on a copy, so the life goes on from the cut).
        let mut copy = store.into_flash().expect("the flash");
        let probe = copy.clone();
        let mut trial = ParamStore::new(probe, RANGE).expect("range");
        let i = rng.below(COUNT as u64) as usize;
        let v = TABLE[i].max;
        block_on(trial.save(i, v)).unwrap_or_else(|e| panic!("{}: save {e}", context()));
        let mut again = ParamValues::DEFAULT;
        let loaded = block_on(trial.load(&mut again));
        assert_eq!(loaded.error, None, "{}", context());
        assert_eq!(again.get(i), Some(v), "{}", context());
        copy.restart();
        flash = copy;
    }
    (cut_writes, cut_loads)
}

#[test]
fn thousands_of_random_power_cuts_in_one_flash_life_leave_old_or_new_values() {
    let started = std::time::Instant::now();
    let mut writes = 0;
    let mut loads = 0;
    let mut kept_new = 0;
    for seed in 1..=4 {
        let (w, l) = life(seed * 0x9E37_79B9, 900, &mut kept_new);
        writes += w;
        loads += l;
    }
    eprintln!(
        "{writes} cuts during writes ({kept_new} kept the new value), {loads} during the \
         loads after them, in {:.1} s",
        started.elapsed().as_secs_f32()
    );
    assert!(writes >= 2500, "only {writes} cuts during writes");
    // Cuts after a write's last byte keep the new value (the branch a cut inside the write
    // never reaches: the store's item is valid only once its last byte is in).
    assert!(kept_new >= 50, "only {kept_new} cuts kept the new value");
    assert!(loads >= 100, "only {loads} cuts during loads");
    // (A load writes only to repair what a cut left, so few of its cuts land.)
}
