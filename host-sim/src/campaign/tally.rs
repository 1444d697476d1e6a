//! What a campaign found, counted from its trials (docs/commands.md#campaign): outcomes,
//! aborts and redraws by kind, faults found or missed, and the final error's spread.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::TrialResult;

/// The final error's spread, m (none without a mission that was not dropped).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorSpread {
    /// Median.
    pub p50: Option<f32>,
    /// 95th percentile.
    pub p95: Option<f32>,
    /// Largest.
    pub max: Option<f32>,
}

/// What came of the trials given one kind of fault.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct FaultTally {
    /// Trials given it.
    pub trials: usize,
    /// Stopped or landed for its reason, not dropped.
    pub found: usize,
    /// Dropped.
    pub dropped: usize,
    /// Of those dropped, a rotor stopped whose robots left cannot hold the payload in a level
    /// hover at all (no thrusts within their range make its weight with no torque).
    #[serde(default)]
    pub dropped_unholdable: usize,
    /// Neither: flew on, or aborted for another reason.
    pub missed: usize,
    /// Neither, and never met: the mission stopped before the take-off it was timed from, or
    /// the vehicle had landed before its time came.
    #[serde(default)]
    pub not_reached: usize,
}

/// The kind of a fault as a trial records it (`rotor-out:3@4.5`: `rotor-out`).
pub fn fault_kind(fault: &str) -> &str {
    fault.split([':', '@']).next().unwrap_or(fault)
}

/// What a campaign found.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Trials run.
    pub trials: usize,
    /// Delivered within [`super::DELIVERED_WITHIN`].
    pub delivered: usize,
    /// Ended without delivering there, neither dropped nor aborted.
    pub not_delivered: usize,
    /// Dropped.
    pub dropped: usize,
    /// Aborted, by the kind of reason ([`abort_kind`]; each trial keeps its whole reason).
    pub aborted: BTreeMap<String, usize>,
    /// Aborts of a healthy vehicle (one given no fault), refusals apart.
    pub false_alarms: usize,
    /// Refused before take-off for want of margin ([`refused`]; not among `aborted`, each
    /// trial keeps its reason).
    #[serde(default)]
    pub refused: usize,
    /// The refused trials flown anyway with the refusals off: how many of them did not
    /// deliver (the refusal was right), of how many.
    #[serde(default)]
    pub refused_flown_failed: [usize; 2],
    /// Trials given a fault.
    pub faulted: usize,
    /// By kind of fault, what came of the trials given it.
    pub faults: BTreeMap<String, FaultTally>,
    /// The final error of the missions that were not dropped.
    pub final_error_m: ErrorSpread,
    /// Payloads drawn again before the ones flown, by the kind of reason ([`redraw_kind`]):
    /// refused by a check of the scenario or the vehicle's pre-flight checks.
    #[serde(default)]
    pub redrawn: BTreeMap<String, usize>,
}

/// The nearest-rank `q` quantile of sorted `values` (none when there are none).
fn quantile(sorted: &[f32], q: f32) -> Option<f32> {
    if sorted.is_empty() {
        return None;
    }
    let rank = (q * sorted.len() as f32).ceil() as usize;
    Some(sorted[rank.clamp(1, sorted.len()) - 1])
}

/// The kind of an abort, for counting: what the vehicle said before its first colon (the
/// particulars after it, a COM or a height, differ trial to trial), each number in it as `#`
/// (`rotor 2 stopped in flight` and `rotor 11 ...` are one kind).
pub fn abort_kind(said: &str) -> String {
    numbers_as_hash(said.split(':').next().unwrap_or(said).trim())
}

/// The kind of a redraw's reason, for counting: the key and what is wrong with it, before the
/// particulars (`robots.pair_size: no group of # adjacent robots can tip ...`), each number
/// as `#`.
pub fn redraw_kind(said: &str) -> String {
    let mut parts = said.splitn(3, ':');
    let head = match (parts.next(), parts.next()) {
        (Some(key), Some(what)) => format!("{}:{what}", key.trim()),
        (Some(all), None) => all.to_string(),
        _ => said.to_string(),
    };
    numbers_as_hash(head.trim())
}

/// `head` with each run of digits (and the decimal points within it) as one `#`.
fn numbers_as_hash(head: &str) -> String {
    let mut kind = String::with_capacity(head.len());
    for c in head.chars() {
        if c.is_ascii_digit() || (c == '.' && kind.ends_with('#')) {
            if !kind.ends_with('#') {
                kind.push('#');
            }
        } else {
            kind.push(c);
        }
    }
    kind
}

/// The report of `results` (in any order).
pub fn report(results: &[TrialResult]) -> Report {
    let mut aborted = BTreeMap::new();
    let count = |what: &str| results.iter().filter(|r| r.outcome == what).count();
    for r in results.iter().filter(|r| r.outcome == "aborted") {
        let why = r
            .aborted
            .as_deref()
            .map_or_else(|| "unknown".to_string(), abort_kind);
        *aborted.entry(why).or_insert(0) += 1;
    }
    let mut errors: Vec<f32> = results
        .iter()
        .filter_map(|r| r.final_error_m)
        .filter(|e| e.is_finite())
        .collect();
    errors.sort_by(f32::total_cmp);
    let mut redrawn = BTreeMap::new();
    for why in results.iter().flat_map(|r| &r.redrawn) {
        *redrawn.entry(redraw_kind(why)).or_insert(0) += 1;
    }
    let mut faults: BTreeMap<String, FaultTally> = BTreeMap::new();
    for r in results {
        let Some(fault) = &r.fault else { continue };
        let tally = faults.entry(fault_kind(fault).to_string()).or_default();
        tally.trials += 1;
        if r.outcome == "dropped" {
            tally.dropped += 1;
            tally.dropped_unholdable += usize::from(r.fault_holdable == Some(false));
        } else if r.fault_found == Some(true) {
            tally.found += 1;
        } else if r.fault_reached == Some(false) {
            tally.not_reached += 1;
        } else {
            tally.missed += 1;
        }
    }
    Report {
        trials: results.len(),
        delivered: count("delivered"),
        not_delivered: count("not delivered"),
        dropped: count("dropped"),
        false_alarms: results
            .iter()
            .filter(|r| r.outcome == "aborted" && r.fault.is_none())
            .count(),
        refused: count("refused"),
        refused_flown_failed: {
            let flown: Vec<&String> = results
                .iter()
                .filter_map(|r| r.flown_anyway.as_ref())
                .collect();
            [
                flown.iter().filter(|o| o.as_str() != "delivered").count(),
                flown.len(),
            ]
        },
        faulted: results.iter().filter(|r| r.fault.is_some()).count(),
        faults,
        aborted,
        final_error_m: ErrorSpread {
            p50: quantile(&errors, 0.5),
            p95: quantile(&errors, 0.95),
            max: errors.last().copied(),
        },
        redrawn,
    }
}
