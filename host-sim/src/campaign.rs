//! A campaign (docs/commands.md#campaign): many missions, each on a random payload
//! ([`payload`]; or, with `--payloads paper`, one of the paper's six cases) with a plant drawn
//! from a dispersion of the `[plant]` departures (docs/formats.md#the-plant-section) and,
//! with `--faults`, maybe one injected fault ([`faults`]), in parallel (rayon), reproducible by
//! seed, and what came of them: delivered within [`DELIVERED_WITHIN`], dropped, aborted by
//! reason (every abort of a healthy vehicle is a false alarm), each fault found or missed, the
//! final error's median, 95th percentile and maximum.
//!
//! Trial `i`'s payload, plant and fault depend on the seed and `i` alone, so `--shard K/N` (the
//! trials whose index is `K - 1` modulo `N`) runs a disjoint slice of the same set, and the
//! shards' results merged ([`merge`]) give the report one run would have printed.

pub mod faults;
pub mod payload;
mod tally;

pub use tally::{ErrorSpread, FaultTally, Report, abort_kind, fault_kind, redraw_kind, report};

use std::collections::BTreeMap;

use anyhow::{Context, Result, anyhow, bail};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::inject::{self, Injection};
use crate::mission_run::{self, MissionSetup};
use crate::rotor_faults;
use crate::scenario_file::{self, LoadedScenario, PlantDepartures};
use shared::mission::AbortReason;

/// A mission delivered its payload when it landed this close to the target, m.
pub const DELIVERED_WITHIN: f32 = 0.1;
/// Most trials of one campaign (or one shard's campaign).
pub const MAX_TRIALS: usize = 100_000;

/// The paper's six cases, built in.
const CASES: [(&str, &str); 6] = [
    (
        "rect-ex1",
        include_str!("../../tests/scenarios/rect-ex1.toml"),
    ),
    (
        "rect-ex2",
        include_str!("../../tests/scenarios/rect-ex2.toml"),
    ),
    (
        "rect-sim1",
        include_str!("../../tests/scenarios/rect-sim1.toml"),
    ),
    (
        "rect-sim2",
        include_str!("../../tests/scenarios/rect-sim2.toml"),
    ),
    ("L-sim1", include_str!("../../tests/scenarios/L-sim1.toml")),
    ("L-sim2", include_str!("../../tests/scenarios/L-sim2.toml")),
];

/// The range each departure is drawn from, uniformly (low, high).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Dispersion {
    /// `rotor_efficiency_spread`.
    pub rotor_efficiency_spread: [f32; 2],
    /// `motor_time_constant`, s.
    pub motor_time_constant: [f32; 2],
    /// `inertia_scale`.
    pub inertia_scale: [f32; 2],
    /// `robot_mass_scale`.
    pub robot_mass_scale: [f32; 2],
    /// `mocap_latency`, s.
    pub mocap_latency: [f32; 2],
    /// `mocap_dropout`.
    pub mocap_dropout: [f32; 2],
    /// Each component of `wind`, m/s.
    pub wind: [f32; 2],
    /// `gust`, m/s RMS.
    pub gust: [f32; 2],
    /// `imu_vibration`, m/s^2 RMS.
    pub imu_vibration: [f32; 2],
    /// `gyro_vibration`, rad/s RMS.
    pub gyro_vibration: [f32; 2],
    /// `battery_sag`, Ohm.
    pub battery_sag: [f32; 2],
    /// The share of trials flown with `ground_effect` on, 0 to 1.
    pub ground_effect: f32,
}

impl Dispersion {
    /// The defaults (docs/commands.md#campaign): what a vehicle of this kind meets indoors and
    /// in a light breeze.
    pub const DEFAULT: Self = Self {
        rotor_efficiency_spread: [0.0, 0.05],
        motor_time_constant: [0.015, 0.04],
        inertia_scale: [0.7, 1.5],
        robot_mass_scale: [0.9, 1.15],
        mocap_latency: [0.005, 0.03],
        mocap_dropout: [0.0, 0.05],
        wind: [-1.0, 1.0],
        gust: [0.0, 0.3],
        imu_vibration: [0.0, 15.0],
        gyro_vibration: [0.0, 0.3],
        battery_sag: [0.0, 0.01],
        ground_effect: 0.5,
    };

    /// A dispersion file (TOML: each key a `[low, high]` range, the defaults for what it does
    /// not give); an unknown key, a range that is not low to high or a value outside the
    /// `[plant]` key's own range is an error naming it.
    pub fn load(path: &std::path::Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read the dispersion file {}", path.display()))?;
        let d: Self = toml::from_str(&text)
            .map_err(|e| anyhow!("{}: {}", path.display(), e.message().trim()))?;
        d.check()
            .map_err(|why| anyhow!("{}: {why}", path.display()))?;
        Ok(d)
    }

    /// Every range low to high, and both ends valid `[plant]` values.
    pub fn check(&self) -> Result<(), String> {
        for (name, [lo, hi]) in self.ranges() {
            if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                return Err(format!(
                    "{name}: [{lo}, {hi}] is not a range from low to high"
                ));
            }
        }
        let share = self.ground_effect;
        if !(0.0..=1.0).contains(&share) {
            return Err(format!(
                "ground_effect: {share} is not a share of the trials from 0 to 1"
            ));
        }
        for end in [0, 1] {
            let plant = self.at(end == 1, |[lo, hi]| if end == 0 { lo } else { hi });
            let text = plant_toml(&plant);
            let probe = format!("{}\n[plant]\n{text}", CASES[0].1);
            scenario_file::parse(&probe, std::path::Path::new("dispersion"))
                .map_err(|e| format!("{:#}", e).replace("dispersion: ", ""))?;
        }
        Ok(())
    }

    fn ranges(&self) -> [(&'static str, [f32; 2]); 11] {
        [
            ("rotor_efficiency_spread", self.rotor_efficiency_spread),
            ("motor_time_constant", self.motor_time_constant),
            ("inertia_scale", self.inertia_scale),
            ("robot_mass_scale", self.robot_mass_scale),
            ("mocap_latency", self.mocap_latency),
            ("mocap_dropout", self.mocap_dropout),
            ("wind", self.wind),
            ("gust", self.gust),
            ("imu_vibration", self.imu_vibration),
            ("gyro_vibration", self.gyro_vibration),
            ("battery_sag", self.battery_sag),
        ]
    }

    /// The departures with each value `pick(range)` (both wind components alike) and ground
    /// effect on or off.
    fn at(&self, ground_effect: bool, mut pick: impl FnMut([f32; 2]) -> f32) -> PlantDepartures {
        let wind = pick(self.wind);
        PlantDepartures {
            rotor_efficiency_spread: pick(self.rotor_efficiency_spread),
            motor_time_constant: pick(self.motor_time_constant),
            inertia_scale: pick(self.inertia_scale),
            robot_mass_scale: pick(self.robot_mass_scale),
            mocap_latency: pick(self.mocap_latency),
            mocap_dropout: pick(self.mocap_dropout),
            wind: [wind, pick(self.wind)],
            gust: pick(self.gust),
            imu_vibration: pick(self.imu_vibration),
            gyro_vibration: pick(self.gyro_vibration),
            battery_sag: pick(self.battery_sag),
            ground_effect,
        }
    }

    /// A plant drawn from the dispersion with `rng`.
    pub fn draw(&self, rng: &mut ChaCha8Rng) -> PlantDepartures {
        let ground_effect = rng.random::<f32>() < self.ground_effect;
        self.at(ground_effect, |[lo, hi]| {
            if hi > lo {
                rng.random_range(lo..=hi)
            } else {
                lo
            }
        })
    }
}

impl Default for Dispersion {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The drawn values of `plant` by name, as the trials' `plant` and the figure give them: the
/// dispersion's keys, the wind as its speed, m/s.
pub fn plant_values(p: &PlantDepartures) -> BTreeMap<String, f32> {
    [
        ("rotor_efficiency_spread", p.rotor_efficiency_spread),
        ("motor_time_constant", p.motor_time_constant),
        ("inertia_scale", p.inertia_scale),
        ("robot_mass_scale", p.robot_mass_scale),
        ("mocap_latency", p.mocap_latency),
        ("mocap_dropout", p.mocap_dropout),
        ("wind", p.wind[0].hypot(p.wind[1])),
        ("gust", p.gust),
        ("imu_vibration", p.imu_vibration),
        ("gyro_vibration", p.gyro_vibration),
        ("battery_sag", p.battery_sag),
        ("ground_effect", f32::from(u8::from(p.ground_effect))),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

/// `plant` as the keys of a `[plant]` section.
fn plant_toml(p: &PlantDepartures) -> String {
    format!(
        "rotor_efficiency_spread = {}\nmotor_time_constant = {}\ninertia_scale = {}\nrobot_mass_scale = {}\nmocap_latency = {}\nmocap_dropout = {}\nwind = [{}, {}]\ngust = {}\nimu_vibration = {}\ngyro_vibration = {}\nbattery_sag = {}\nground_effect = {}\n",
        p.rotor_efficiency_spread,
        p.motor_time_constant,
        p.inertia_scale,
        p.robot_mass_scale,
        p.mocap_latency,
        p.mocap_dropout,
        p.wind[0],
        p.wind[1],
        p.gust,
        p.imu_vibration,
        p.gyro_vibration,
        p.battery_sag,
        p.ground_effect
    )
}

/// What the trials fly.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum PayloadSource {
    /// A payload drawn for each trial ([`payload`]).
    #[default]
    Random,
    /// The paper's six cases in turn (trial `i` flies case `i` modulo 6).
    Paper,
}

/// What one campaign runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CampaignSetup {
    /// Trials in the whole campaign.
    pub trials: usize,
    /// The campaign's seed.
    pub seed: u64,
    /// The plants' dispersion.
    pub dispersion: Dispersion,
    /// What the trials fly.
    pub payloads: PayloadSource,
    /// About half the trials get one fault ([`faults::draw`]).
    pub faults: bool,
    /// This run's shard, `(k, n)`: the trials whose index is `k - 1` modulo `n` (`(1, 1)`: all).
    pub shard: (usize, usize),
}

/// How a trial came out.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrialResult {
    /// The trial's index in the campaign.
    pub trial: usize,
    /// The payload flown: a paper case's name, or `random-<seed>-<trial>`.
    pub scenario: String,
    /// Robots on its rail.
    pub robots: usize,
    /// Its footprint's vertices.
    pub vertices: usize,
    /// Its true mass, kg.
    pub payload_mass_kg: f32,
    /// The plant drawn ([`plant_values`]).
    pub plant: BTreeMap<String, f32>,
    /// The seed its mission flew with (`mission --seed`).
    pub mission_seed: u64,
    /// The fault injected, as `mission --inject` takes it.
    pub fault: Option<String>,
    /// Whether the vehicle stopped or landed for that fault's reason.
    pub fault_found: Option<bool>,
    /// Whether the fault's time came before the flight ended ([`fault_reached`]): one timed
    /// after a take-off that never came, or after the landing, met nothing to find.
    #[serde(default)]
    pub fault_reached: Option<bool>,
    /// For a rotor stopped: whether the rotors left can hold the payload in a level hover at
    /// all (`rotor_faults::holdable_without`, the formation flown, the true COM and mass).
    #[serde(default)]
    pub fault_holdable: Option<bool>,
    /// `delivered`, `not delivered`, `dropped`, `refused` (the vehicle refused to take off
    /// for want of margin: [`refused`]) or `aborted`.
    pub outcome: String,
    /// A refused trial flown again with the refusal off: how that went (`delivered`, `not
    /// delivered`, `dropped`, `aborted`), to show whether the refusal was right.
    #[serde(default)]
    pub flown_anyway: Option<String>,
    /// Why it aborted, as the vehicle said it.
    pub aborted: Option<String>,
    /// Distance from the target where it ended, m (none when dropped).
    pub final_error_m: Option<f32>,
    /// Why each payload drawn before this one was refused (the vehicle's pre-flight checks
    /// among them; empty for the paper's cases).
    #[serde(default)]
    pub redrawn: Vec<String>,
}

/// A trial's own random stream: the campaign's seed and the trial's index, nothing else.
fn trial_rng(seed: u64, trial: usize) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed ^ (trial as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

/// Mixed into the seed of a trial's fault stream, so that the payloads and plants are the same
/// with `--faults` and without.
const FAULT_STREAM: u64 = 0xFA17_0000_0000_0001;

/// One trial, drawn.
#[derive(Clone, Debug)]
pub struct Trial {
    /// The payload, checked, with its plant.
    pub loaded: LoadedScenario,
    /// The payload's scenario file, without its `[plant]` section.
    pub scenario_toml: String,
    /// Its footprint's vertices.
    pub vertices: usize,
    /// The seed its mission flies with.
    pub mission_seed: u64,
    /// The fault injected, if one is.
    pub fault: Option<Injection>,
    /// Why each payload drawn before this one was refused.
    pub redrawn: Vec<String>,
}

/// Trial `trial` of `setup`: its payload, plant, mission seed and fault.
pub fn trial_of(setup: &CampaignSetup, trial: usize) -> Result<Trial> {
    let mut rng = trial_rng(setup.seed, trial);
    let (mut loaded, scenario_toml, vertices, redrawn) = match setup.payloads {
        PayloadSource::Paper => {
            let (name, text) = CASES[trial % CASES.len()];
            let loaded = scenario_file::parse(text, std::path::Path::new(name))?;
            let vertices = loaded.scenario.payload.footprint.len();
            (loaded, text.to_string(), vertices, Vec::new())
        }
        PayloadSource::Random => {
            let name = format!("random-{}-{trial}", setup.seed);
            let drawn = payload::draw(&name, &mut rng)
                .with_context(|| format!("trial {trial}: drawing its payload"))?;
            (drawn.loaded, drawn.toml, drawn.vertices, drawn.redrawn)
        }
    };
    loaded.plant = setup.dispersion.draw(&mut rng);
    let mission_seed: u64 = rng.random();
    let fault = if setup.faults {
        let mut rng = trial_rng(setup.seed ^ FAULT_STREAM, trial);
        faults::draw(&mut rng, loaded.scenario.robots.count())
    } else {
        None
    };
    Ok(Trial {
        loaded,
        scenario_toml,
        vertices,
        mission_seed,
        fault,
        redrawn,
    })
}

/// Trial `trial` as a scenario file `mission --scenario` flies as the campaign did: the
/// payload, its `[plant]`, and the command line (seed, fault) in a comment at the top.
pub fn trial_file(setup: &CampaignSetup, trial: usize) -> Result<String> {
    let t = trial_of(setup, trial)?;
    let inject = t.fault.map_or(String::new(), |f| format!(" --inject {f}"));
    Ok(format!(
        "# Campaign seed {}, trial {trial}: host-sim mission --scenario <this file> --seed {}{inject}\n{}\n[plant]\n{}",
        setup.seed,
        t.mission_seed,
        t.scenario_toml.trim_end(),
        plant_toml(&t.loaded.plant)
    ))
}

/// Whether the vehicle refused to take off because no one could fly the payload as
/// estimated: the heaviest payload the estimate allows needs more than the allowed share of
/// thrust, or the formation cannot hold the flight's design torque
/// (docs/failures.md#refused-before-take-off). Neither a failure nor a false alarm.
pub fn refused(reason: &AbortReason) -> bool {
    matches!(
        reason,
        AbortReason::ThrustMarginTooSmall { .. } | AbortReason::FormationTooWeak { .. }
    )
}

/// How a mission came out, as the campaign counts it.
fn outcome_of(o: &mission_run::MissionOutcome) -> &'static str {
    if o.dropped {
        "dropped"
    } else if o.aborted.as_ref().is_some_and(refused) {
        "refused"
    } else if o.aborted.is_some() {
        "aborted"
    } else if o.delivered && o.final_position_error_m <= DELIVERED_WITHIN {
        "delivered"
    } else {
        "not delivered"
    }
}

/// Whether `injection`'s time came before the flight ended: a fault timed from a take-off that
/// never came (`takeoff_at` none: the mission stopped before it), or due after the vehicle had
/// landed and disarmed (the first `disarmed` or `aborted` of `phases`, each a name and its
/// time, after the take-off; `simulated_s` if none), was never met.
pub fn fault_reached(
    injection: &Injection,
    takeoff_at: Option<f32>,
    phases: &[(String, f32)],
    simulated_s: f32,
) -> bool {
    let at = match injection.since {
        inject::Since::Takeoff => match takeoff_at {
            Some(t) => t + injection.after,
            None => return false,
        },
        inject::Since::Start => injection.after,
    };
    let began = takeoff_at.unwrap_or(0.0);
    let ended = phases
        .iter()
        .find(|(name, t)| (name == "disarmed" || name == "aborted") && *t > began)
        .map_or(simulated_s, |&(_, t)| t);
    at < ended
}

/// Runs trial `trial`; a refused one is flown again with the refusals off.
pub fn run_trial(setup: &CampaignSetup, trial: usize) -> Result<TrialResult> {
    let t = trial_of(setup, trial)?;
    let loaded = t.loaded;
    let mission_setup = MissionSetup {
        seed: t.mission_seed,
        plant: loaded.plant,
        ..MissionSetup::default()
    };
    let mission_setup = match &t.fault {
        Some(f) => inject::apply(std::slice::from_ref(f), mission_setup),
        None => mission_setup,
    };
    let (o, _) = mission_run::run(&loaded.scenario, &mission_setup, &mut |_, _, _| {})?;
    let fault_found = t.fault.map(|f| {
        !o.dropped
            && (o.aborted.is_some_and(|r| faults::found(&f.fault, &r))
                || o.notices.iter().any(|(_, n)| faults::said(&f.fault, n)))
    });
    let fault_reached = t
        .fault
        .map(|f| fault_reached(&f, o.takeoff_at, &o.phases, o.simulated_s));
    let fault_holdable = match (t.fault.map(|f| f.fault), &o.positions) {
        (Some(inject::Fault::RotorOut(robot)), Some(positions)) => {
            rotor_faults::holdable_without(&loaded.scenario, positions, &[robot]).ok()
        }
        _ => None,
    };
    let outcome = outcome_of(&o);
    let flown_anyway = if outcome == "refused" {
        let mut anyway = mission_setup.clone();
        anyway.config.refuse_weak_formation = false;
        anyway.config.max_hover_fraction = 1.0;
        let (again, _) = mission_run::run(&loaded.scenario, &anyway, &mut |_, _, _| {})?;
        Some(outcome_of(&again).to_string())
    } else {
        None
    };
    Ok(TrialResult {
        trial,
        scenario: loaded.name,
        robots: loaded.scenario.robots.count(),
        vertices: t.vertices,
        payload_mass_kg: loaded.scenario.truth.map_or(f32::NAN, |tr| tr.mass),
        plant: plant_values(&loaded.plant),
        mission_seed: t.mission_seed,
        fault: t.fault.map(|f| f.to_string()),
        fault_found,
        fault_reached,
        fault_holdable,
        outcome: outcome.to_string(),
        flown_anyway,
        aborted: o.aborted.map(|r| r.to_string()),
        final_error_m: (!o.dropped).then_some(o.final_position_error_m),
        redrawn: t.redrawn,
    })
}

/// The trials of `setup`'s shard, run in parallel; `progress` sees each as it ends.
pub fn run(setup: &CampaignSetup, progress: &(dyn Fn() + Sync)) -> Result<Vec<TrialResult>> {
    let (k, n) = setup.shard;
    if n == 0 || k == 0 || k > n {
        bail!("--shard {k}/{n}: K runs from 1 to N");
    }
    if setup.trials == 0 || setup.trials > MAX_TRIALS {
        bail!("--trials {}: 1 to {MAX_TRIALS}", setup.trials);
    }
    let mut results: Vec<TrialResult> = (0..setup.trials)
        .filter(|i| i % n == k - 1)
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|i| {
            let r = run_trial(setup, i);
            progress();
            r
        })
        .collect::<Result<_>>()?;
    results.sort_by_key(|r| r.trial);
    Ok(results)
}

/// One run's (or shard's) output as `campaign --json` prints it: the set-up, the report and
/// every trial.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CampaignOutput {
    /// Trials in the whole campaign.
    pub campaign_trials: usize,
    /// The campaign's seed.
    pub seed: u64,
    /// The dispersion.
    pub dispersion: Dispersion,
    /// What the trials flew.
    pub payloads: PayloadSource,
    /// Whether faults were injected (`--faults`).
    pub fault_injection: bool,
    /// The shard, `[k, n]`.
    pub shard: [usize; 2],
    /// What this run found.
    #[serde(flatten)]
    pub report: Report,
    /// Each trial.
    pub results: Vec<TrialResult>,
}

/// The shards' outputs as one campaign's: they must be of one campaign (seed, trials,
/// dispersion, shard count), each shard once, and hold every trial.
pub fn merge(parts: &[CampaignOutput]) -> Result<CampaignOutput> {
    let Some(first) = parts.first() else {
        bail!("no shard to merge");
    };
    let n = first.shard[1];
    let mut seen = vec![false; n.max(1)];
    for p in parts {
        if p.seed != first.seed
            || p.campaign_trials != first.campaign_trials
            || p.dispersion != first.dispersion
            || p.payloads != first.payloads
            || p.fault_injection != first.fault_injection
            || p.shard[1] != n
        {
            bail!(
                "shard {}/{} is of another campaign (its seed, trials, dispersion, payloads, faults or shard count differ)",
                p.shard[0],
                p.shard[1]
            );
        }
        let k = p.shard[0];
        if k == 0 || k > n || std::mem::replace(&mut seen[k - 1], true) {
            bail!("shard {k}/{n} given twice or out of range");
        }
    }
    if let Some(missing) = seen.iter().position(|s| !s) {
        bail!("shard {}/{n} is missing", missing + 1);
    }
    let mut results: Vec<TrialResult> = parts.iter().flat_map(|p| p.results.clone()).collect();
    results.sort_by_key(|r| r.trial);
    if results.len() != first.campaign_trials
        || results.iter().enumerate().any(|(i, r)| r.trial != i)
    {
        bail!("the shards do not hold each of the campaign's trials once");
    }
    Ok(CampaignOutput {
        campaign_trials: first.campaign_trials,
        seed: first.seed,
        dispersion: first.dispersion,
        payloads: first.payloads,
        fault_injection: first.fault_injection,
        shard: [1, 1],
        report: report(&results),
        results,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_trials_plant_depends_on_the_seed_and_its_index_alone() {
        let setup = CampaignSetup {
            trials: 10,
            seed: 4,
            dispersion: Dispersion::DEFAULT,
            payloads: PayloadSource::Paper,
            faults: false,
            shard: (1, 1),
        };
        let a = trial_of(&setup, 7).expect("a trial");
        let a = (a.loaded, a.mission_seed);
        let b = trial_of(
            &CampaignSetup {
                shard: (2, 3),
                ..setup
            },
            7,
        )
        .expect("a trial");
        let b = (b.loaded, b.mission_seed);
        assert_eq!((a.0.plant, a.1), (b.0.plant, b.1));
        assert_eq!(a.0.name, "rect-ex2", "trial 7: the second case of six");
        let c = trial_of(&setup, 8).expect("a trial");
        assert_ne!(a.0.plant, c.loaded.plant);
        let d = Dispersion::DEFAULT;
        let p = a.0.plant;
        assert!((d.inertia_scale[0]..=d.inertia_scale[1]).contains(&p.inertia_scale));
        assert!((d.battery_sag[0]..=d.battery_sag[1]).contains(&p.battery_sag));
    }

    #[test]
    fn ground_effect_is_on_in_its_share_of_the_trials() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let share = |d: Dispersion, rng: &mut ChaCha8Rng| {
            (0..400).filter(|_| d.draw(rng).ground_effect).count()
        };
        let never = Dispersion {
            ground_effect: 0.0,
            ..Dispersion::DEFAULT
        };
        let always = Dispersion {
            ground_effect: 1.0,
            ..Dispersion::DEFAULT
        };
        assert_eq!(share(never, &mut rng), 0);
        assert_eq!(share(always, &mut rng), 400);
        let half = share(Dispersion::DEFAULT, &mut rng);
        assert!((160..240).contains(&half), "{half} of 400");
    }

    #[test]
    fn a_fault_timed_after_the_flight_or_before_a_take_off_that_never_came_is_not_met() {
        let injection = Injection::parse("rotor-out:3@4.5").expect("valid");
        let phases = vec![
            ("takeoff".to_string(), 30.0),
            ("landing".to_string(), 44.0),
            ("disarmed".to_string(), 47.0),
        ];
        // 34.5 s, in the flight.
        assert!(fault_reached(&injection, Some(30.0), &phases, 48.0));
        // 47.5 s: disarmed at 47 s.
        assert!(!fault_reached(&injection, Some(43.0), &phases, 48.0));
        // No take-off: the mission stopped before it.
        let refused = vec![("aborted".to_string(), 12.0)];
        assert!(!fault_reached(&injection, None, &refused, 12.0));
        // Still flying when the run ended.
        assert!(fault_reached(&injection, Some(30.0), &phases[..1], 40.0));
    }

    #[test]
    fn a_lost_link_or_pack_said_while_landing_is_found() {
        let gcs = Injection::parse("gcs-loss@9.5").expect("valid").fault;
        assert!(faults::said(
            &gcs,
            "ground link lost: no ground-station heartbeat for 5.0 s"
        ));
        assert!(!faults::said(&gcs, "battery critical: 13.19 V"));
        let rotor = Injection::parse("rotor-out:2@3").expect("valid").fault;
        assert!(!faults::said(&rotor, "ground link lost"));
    }

    #[test]
    fn percentiles_are_nearest_rank_and_outcomes_are_counted() {
        let r = |trial, outcome: &str, e| TrialResult {
            trial,
            scenario: "x".into(),
            robots: 8,
            vertices: 4,
            payload_mass_kg: 3.0,
            plant: BTreeMap::new(),
            mission_seed: 1,
            fault: None,
            fault_found: None,
            fault_reached: None,
            fault_holdable: None,
            outcome: outcome.into(),
            flown_anyway: (outcome == "refused").then(|| "dropped".into()),
            aborted: match outcome {
                "aborted" => Some("position lost".into()),
                "refused" => Some("formation too weak: ...".into()),
                _ => None,
            },
            final_error_m: e,
            redrawn: if trial == 0 {
                vec![
                    "the rail runs too close to the footprint".into(),
                    "robots.pair_size: no group of 2 adjacent robots can tip the grid's heaviest payload: 7.5 kg with its COM at (0.1, -0.05) m needs 15.2 N".into(),
                    "robots.pair_size: no group of 3 adjacent robots can tip the grid's heaviest payload: 8 kg with its COM at (0.2, 0.05) m needs 14.9 N".into(),
                ]
            } else {
                Vec::new()
            },
        };
        let results: Vec<_> = (0..20)
            .map(|i| r(i, "delivered", Some(i as f32 * 0.01)))
            .chain([
                r(20, "aborted", Some(0.5)),
                r(21, "dropped", None),
                r(22, "refused", Some(0.3)),
            ])
            .collect();
        let rep = report(&results);
        assert_eq!(
            (rep.trials, rep.delivered, rep.dropped, rep.false_alarms),
            (23, 20, 1, 1)
        );
        assert_eq!((rep.refused, rep.refused_flown_failed), (1, [1, 1]));
        assert_eq!(
            rep.aborted.len(),
            1,
            "a refusal is no abort: {:?}",
            rep.aborted
        );
        assert_eq!(rep.redrawn.values().sum::<usize>(), 3);
        assert_eq!(rep.redrawn.len(), 2, "two kinds: {:?}", rep.redrawn);
        assert_eq!(rep.aborted.get("position lost"), Some(&1));
        assert_eq!(
            abort_kind("rotor 11 stopped in flight: flying on the other rotors"),
            "rotor # stopped in flight"
        );
        assert_eq!(
            abort_kind("take-off failed: the payload did not leave the ground (0.005 m)"),
            "take-off failed"
        );
        // 21 finite errors: 0.00..0.19 and 0.5.
        // The 11th of 21: trial 10's 0.10 m.
        assert_eq!(rep.final_error_m.p50, Some(10.0 * 0.01));
        assert_eq!(rep.final_error_m.max, Some(0.5));
    }

    #[test]
    fn a_dispersion_out_of_order_or_out_of_range_is_refused_naming_it() {
        let mut d = Dispersion::DEFAULT;
        d.gust = [0.5, 0.1];
        assert!(d.check().expect_err("refused").contains("gust"));
        let mut d = Dispersion::DEFAULT;
        d.inertia_scale = [0.5, 50.0];
        assert!(d.check().expect_err("refused").contains("inertia_scale"));
        let mut d = Dispersion::DEFAULT;
        d.battery_sag = [0.0, 0.5];
        let said = d.check().expect_err("refused");
        assert!(said.contains("battery_sag"), "{said}");
        let mut d = Dispersion::DEFAULT;
        d.ground_effect = 1.5;
        assert!(d.check().expect_err("refused").contains("ground_effect"));
        assert_eq!(Dispersion::DEFAULT.check(), Ok(()));
        let e = toml::from_str::<Dispersion>("wind_speed = [0.0, 1.0]").expect_err("refused");
        assert!(e.message().contains("wind_speed"));
    }
}
