//! The mission summary's data read from a flight log (`host-sim plot`,
//! docs/formats.md#plotting-a-flight-log): the phases from `vehicle_status`, the lifts from
//! `lift`, and from take-off the height (`vehicle_local_position`), roll and pitch
//! (`vehicle_attitude`) and the rotors' commands (`actuator_outputs`), sampled at each
//! position record (100 Hz). Times are seconds from the log's start.
//!
//! What the log lacks is said, one sentence each, in [`LogSummary::notes`]: a missing topic
//! or field and the panel it leaves empty, a log cut short or corrupt and how much of it was
//! read, a mission that the log ends before it ended. The robots' maximum thrust and the
//! payload's truth are not in the log; with the scenario they come from, the thrusts are in
//! newtons and each lift stands beside the model's lift-off thrust.

use flight_log::reader::{Field, Stop, TopicData, Ulog};
use flight_log::recorder::phase_from_code;
use shared::scenario::Scenario;

use crate::figures::mission_summary::{LiftBar, MissionSummary, Span, SummarySample};
use crate::mission_run::model_lift;

/// The name of logged phase number `code` (`phase 99` for one this firmware does not have).
pub fn phase_name(code: u8) -> String {
    phase_from_code(code).map_or_else(|| format!("phase {code}"), |p| p.name().to_string())
}

/// The summary of a log and what it lacks.
#[derive(Clone, Debug, Default)]
pub struct LogSummary {
    /// The page's data.
    pub summary: MissionSummary,
    /// What the log lacks or how it was damaged, one sentence each.
    pub notes: Vec<String>,
    /// The log ends before the mission did (its last phase is neither disarmed nor aborted).
    pub cut_short: bool,
}

/// The log's clock: seconds from `t0`, us.
struct Clock {
    t0: u64,
}

impl Clock {
    fn s(&self, us: u64) -> f32 {
        (us.saturating_sub(self.t0) as f64 * 1e-6) as f32
    }
}

/// A topic's records and the fields wanted of it; a note for each that is missing.
struct Wanted<'a> {
    records: Vec<&'a [u8]>,
    fields: Vec<Option<Field>>,
}

impl Wanted<'_> {
    fn value(&self, record: &[u8], field: usize, index: usize) -> Option<f64> {
        self.fields.get(field)?.as_ref()?.get(record, index)
    }

    fn timestamp(&self, record: &[u8]) -> Option<u64> {
        // `timestamp` is field 0 of every topic asked for; read as the integer it is.
        let f = self.fields.first()?.as_ref()?;
        Some(u64::from_le_bytes(
            record.get(f.offset..f.offset + 8)?.try_into().ok()?,
        ))
    }
}

/// Topic `name` with `fields` (`timestamp` first), a note in `notes` for a missing topic or
/// field, saying what stays empty (`empties`). `None` when the topic or a field is missing.
fn wanted<'a>(
    log: &'a Ulog,
    name: &str,
    fields: &[&str],
    empties: &str,
    notes: &mut Vec<String>,
) -> Option<Wanted<'a>> {
    let Some(topic): Option<TopicData<'a>> = log.topic(name) else {
        notes.push(format!("the log has no {name} topic: {empties}"));
        return None;
    };
    let found: Vec<Option<Field>> = fields.iter().map(|f| topic.field(f)).collect();
    let missing: Vec<&str> = fields
        .iter()
        .zip(&found)
        .filter(|(_, f)| f.is_none())
        .map(|(n, _)| *n)
        .collect();
    if !missing.is_empty() {
        notes.push(format!(
            "the log's {name} has no field {}: {empties}",
            missing.join(", ")
        ));
        return None;
    }
    let mut w = Wanted {
        records: Vec::new(),
        fields: found,
    };
    let times: Vec<Option<u64>> = topic.records.iter().map(|r| w.timestamp(r)).collect();
    // A record out of time order with its neighbours (a corrupt timestamp) is left out: one
    // would stop the walk through the records at it.
    let in_order = |k: usize| {
        let t = times[k];
        let before = k.checked_sub(1).and_then(|j| times[j]);
        let after = times.get(k + 1).copied().flatten();
        t.is_some_and(|t| before.is_none_or(|b| b <= t) && after.is_none_or(|a| t <= a))
    };
    w.records = (0..topic.records.len())
        .filter(|&k| in_order(k))
        .map(|k| topic.records[k])
        .collect();
    let dropped = topic.records.len() - w.records.len();
    if dropped > 0 {
        notes.push(format!(
            "{dropped} {name} records out of time order were left out"
        ));
    }
    Some(w)
}

/// The summary of `log`, named `name`; with `scenario`, the thrusts in newtons and each
/// lift beside the model for its truth.
pub fn summarise(log: &Ulog, name: &str, scenario: Option<&Scenario>) -> LogSummary {
    let mut notes = damage(log);
    let status = wanted(
        log,
        "vehicle_status",
        &["timestamp", "mission_phase"],
        "the phase panel is empty",
        &mut notes,
    );
    let lift = wanted(
        log,
        "lift",
        &["timestamp", "pair", "lifted", "thrust_n"],
        "the lift panel is empty",
        &mut notes,
    );
    let position = wanted(
        log,
        "vehicle_local_position",
        &["timestamp", "z"],
        "the flight panels are empty",
        &mut notes,
    );
    let attitude = wanted(
        log,
        "vehicle_attitude",
        &["timestamp", "q"],
        "roll and pitch are drawn as zero",
        &mut notes,
    );
    let outputs = wanted(
        log,
        "actuator_outputs",
        &["timestamp", "noutputs", "output"],
        "the thrust panel is empty",
        &mut notes,
    );
    // Times from the header's start, unless a record comes before it (a corrupt header).
    let first = [&status, &position, &attitude]
        .iter()
        .filter_map(|w| w.as_ref())
        .filter_map(|w| w.records.first().and_then(|r| w.timestamp(r)))
        .min()
        .unwrap_or(log.start_us);
    let clock = Clock {
        t0: log.start_us.min(first),
    };
    let end_us = [&status, &lift, &position, &attitude, &outputs]
        .iter()
        .filter_map(|w| w.as_ref())
        .filter_map(|w| w.records.last().and_then(|r| w.timestamp(r)))
        .max()
        .unwrap_or(clock.t0);
    let end_s = clock.s(end_us);

    let entered = status
        .as_ref()
        .map(|s| phases(s, &clock))
        .unwrap_or_default();
    let spans = spans(&entered, end_s);
    if status.is_some() && spans.is_empty() {
        notes.push("the log has no vehicle_status records: the phase panel is empty".into());
    }
    let last = spans.last().map(|s| s.name.as_str());
    let cut_short = !matches!(last, Some("disarmed" | "aborted"));
    let verdict = match last {
        Some("disarmed") => "ended disarmed".to_string(),
        Some("aborted") => "aborted".to_string(),
        Some(other) => {
            notes.push(format!(
                "the log ends in phase {other}, before the mission ended (as a vehicle that \
                 lost power or crashed leaves its log)"
            ));
            format!("log ends in {other}")
        }
        None => "phases unknown".to_string(),
    };

    let lifts = lift
        .as_ref()
        .map(|l| lifts(l, scenario))
        .unwrap_or_default();
    if lift.is_some() && lifts.is_empty() {
        notes.push("the log has no lifts: the lift panel is empty".into());
    }
    let takeoff = spans.iter().find(|s| s.name == "takeoff").map(|s| s.start);
    let max_thrust = scenario.map(|s| s.robots.max_thrust);
    let series = match (&position, takeoff) {
        (Some(p), Some(takeoff)) => flight(
            p,
            attitude.as_ref(),
            outputs.as_ref(),
            &clock,
            takeoff,
            max_thrust,
            &mut notes,
        ),
        (Some(_), None) if !spans.is_empty() => {
            notes.push("the log has no take-off: the flight panels are empty".into());
            Vec::new()
        }
        _ => Vec::new(),
    };
    if scenario.is_none() {
        notes.push(
            "without --scenario the lifts have no model to compare with and the rotors' \
             commands are in percent of their maximum thrust"
                .into(),
        );
    }
    LogSummary {
        summary: MissionSummary {
            title: format!("{name}: the mission, {verdict} ({end_s:.1} s logged)"),
            end_s,
            phases: spans,
            lifts,
            max_thrust,
            series,
            thrust_in_newtons: max_thrust.is_some(),
            no_flight: "no flight in the log".to_string(),
        },
        notes,
        cut_short,
    }
}

/// What went wrong reading the file, as notes.
fn damage(log: &Ulog) -> Vec<String> {
    let mut notes = Vec::new();
    let read = format!("read {} of its {} bytes", log.read, log.len());
    match &log.stop {
        Some(Stop::Truncated { .. }) => notes.push(format!(
            "the log was cut short (its last message is unfinished): {read}"
        )),
        Some(Stop::Corrupt { at, why }) => {
            notes.push(format!("the log is corrupt from byte {at} ({why}): {read}"))
        }
        None => {}
    }
    if log.skipped > 0 {
        notes.push(format!(
            "{} corrupt bytes were skipped, up to the next sync message",
            log.skipped
        ));
    }
    if log.unsubscribed > 0 {
        notes.push(format!(
            "{} data messages belong to no subscription and were left out",
            log.unsubscribed
        ));
    }
    if log.dropouts.0 > 0 {
        notes.push(format!(
            "the logger lost data {} times ({} ms in all)",
            log.dropouts.0, log.dropouts.1
        ));
    }
    notes
}

/// Each phase entered (name, time): a record whose phase differs from the one before.
fn phases(status: &Wanted<'_>, clock: &Clock) -> Vec<(String, f32)> {
    let mut out = Vec::new();
    let mut now: Option<u8> = None;
    for r in &status.records {
        let (Some(t), Some(code)) = (status.timestamp(r), status.value(r, 1, 0)) else {
            continue;
        };
        let code = code as u8;
        if now != Some(code) {
            out.push((phase_name(code), clock.s(t)));
            now = Some(code);
        }
    }
    out
}

/// The phases entered as spans, each ending where the next begins, the last at `end`.
fn spans(entered: &[(String, f32)], end: f32) -> Vec<Span> {
    entered
        .iter()
        .enumerate()
        .map(|(k, (name, start))| Span {
            name: name.clone(),
            start: *start,
            end: entered.get(k + 1).map_or(end, |n| n.1).max(*start),
        })
        .collect()
}

/// Each lift record's pair and reading, with the model's lift-off thrust for the scenario's
/// truth.
fn lifts(lift: &Wanted<'_>, scenario: Option<&Scenario>) -> Vec<LiftBar> {
    lift.records
        .iter()
        .filter_map(|r| {
            let pair = lift.value(r, 1, 0)? as usize;
            let lifted = lift.value(r, 2, 0)? != 0.0;
            let thrust = lift.value(r, 3, 0)? as f32;
            Some(LiftBar {
                pair,
                reading: (lifted && thrust.is_finite()).then_some(thrust),
                model: scenario.and_then(|s| model_lift(s, pair)),
            })
        })
        .collect()
}

/// The latest record of `topic` at or before `t`, walking `at` forward.
fn latest<'a>(topic: &Wanted<'a>, at: &mut usize, t: u64) -> Option<&'a [u8]> {
    while let Some(next) = topic.records.get(*at + 1)
        && topic.timestamp(next).is_some_and(|n| n <= t)
    {
        *at += 1;
    }
    topic
        .records
        .get(*at)
        .copied()
        .filter(|r| topic.timestamp(r).is_some_and(|n| n <= t))
}

/// Roll and pitch, degrees, of quaternion `q` (w, x, y, z), as the simulator's plant
/// computes them.
fn roll_pitch_deg(q: [f64; 4]) -> [f32; 2] {
    let [w, x, y, z] = q;
    let roll = (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y));
    let pitch = (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin();
    [roll.to_degrees() as f32, pitch.to_degrees() as f32]
}

/// The flight from `takeoff` (s) on, one sample per position record; samples with a value
/// that is not a number are left out (with a note).
fn flight(
    position: &Wanted<'_>,
    attitude: Option<&Wanted<'_>>,
    outputs: Option<&Wanted<'_>>,
    clock: &Clock,
    takeoff: f32,
    max_thrust: Option<f32>,
    notes: &mut Vec<String>,
) -> Vec<SummarySample> {
    let z0 = position
        .records
        .iter()
        .filter_map(|r| position.value(r, 1, 0))
        .find(|z| z.is_finite())
        .unwrap_or(0.0);
    let scale = f64::from(max_thrust.unwrap_or(100.0));
    let (mut at_attitude, mut at_outputs) = (0, 0);
    let mut series = Vec::new();
    let mut bad = 0usize;
    for r in &position.records {
        let (Some(us), Some(z)) = (position.timestamp(r), position.value(r, 1, 0)) else {
            continue;
        };
        let t = clock.s(us);
        if t < takeoff {
            continue;
        }
        let roll_pitch = attitude
            .and_then(|a| {
                let rec = latest(a, &mut at_attitude, us)?;
                let q = [0, 1, 2, 3].map(|i| a.value(rec, 1, i).unwrap_or(f64::NAN));
                Some(roll_pitch_deg(q))
            })
            .unwrap_or([0.0; 2]);
        let thrust: Vec<f32> = outputs
            .and_then(|o| {
                let rec = latest(o, &mut at_outputs, us)?;
                let n = o.value(rec, 1, 0)?.clamp(0.0, 16.0) as usize;
                Some(
                    (0..n)
                        .map(|j| (o.value(rec, 2, j).unwrap_or(f64::NAN) * scale) as f32)
                        .collect(),
                )
            })
            .unwrap_or_default();
        let sample = SummarySample {
            t,
            height: (z0 - z) as f32,
            roll_pitch_deg: roll_pitch,
            thrust,
        };
        let finite = sample.t.is_finite()
            && sample.height.is_finite()
            && sample.roll_pitch_deg.iter().all(|v| v.is_finite())
            && sample.thrust.iter().all(|v| v.is_finite());
        if finite {
            series.push(sample);
        } else {
            bad += 1;
        }
    }
    if bad > 0 {
        notes.push(format!(
            "{bad} flight samples held a value that is not a number and were left out"
        ));
    }
    // Every sample draws as many rotors as the first (a corrupt count would change it).
    if let Some(n) = series.first().map(|s| s.thrust.len()) {
        for s in &mut series {
            s.thrust.resize(n, 0.0);
        }
    }
    series
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_phase_number_names_its_phase_and_an_unknown_one_says_so() {
        for code in 0..16 {
            let phase = phase_from_code(code).expect("a phase");
            assert_eq!(phase_name(code), phase.name());
        }
        assert_eq!(phase_name(99), "phase 99");
    }

    #[test]
    fn roll_and_pitch_follow_the_plants_convention() {
        let half = 10f64.to_radians() / 2.0;
        let [roll, pitch] = roll_pitch_deg([half.cos(), half.sin(), 0.0, 0.0]);
        assert!(
            (roll - 10.0).abs() < 1e-4 && pitch.abs() < 1e-4,
            "{roll} {pitch}"
        );
        let [roll, pitch] = roll_pitch_deg([half.cos(), 0.0, half.sin(), 0.0]);
        assert!(
            (pitch - 10.0).abs() < 1e-4 && roll.abs() < 1e-4,
            "{roll} {pitch}"
        );
    }

    #[test]
    fn a_log_without_any_topic_says_what_each_panel_lacks() {
        let log = Ulog::default();
        let s = summarise(&log, "x", None);
        for topic in ["vehicle_status", "lift", "vehicle_local_position"] {
            assert!(
                s.notes.iter().any(|n| n.contains(topic)),
                "{topic}: {:?}",
                s.notes
            );
        }
        assert!(s.summary.phases.is_empty() && s.summary.series.is_empty());
        assert!(s.cut_short);
    }
}
