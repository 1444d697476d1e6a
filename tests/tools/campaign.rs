//! `host-sim campaign` (docs/commands.md#campaign): random payloads reproducible by seed, each
//! passing the scenario checks, over 4 to 16 robots (drawn, not flown); faults drawn from the
//! simulator's injections; a small campaign's counts adding up, its figure and trial files; the
//! JSON keys other tools rely on, two shards merged giving exactly the unsharded run's report,
//! and bad shards and dispersions refused naming what is wrong.

use std::collections::BTreeSet;

use host_sim::campaign::{self, CampaignSetup, Dispersion, PayloadSource, faults, payload};
use host_sim::scenario_file;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use shared::geometry::polygon_contains;

use crate::common::host_sim;

fn setup(seed: u64, faults: bool) -> CampaignSetup {
    CampaignSetup {
        trials: 1000,
        seed,
        dispersion: Dispersion::DEFAULT,
        payloads: PayloadSource::Random,
        faults,
        shard: (1, 1),
    }
}

#[test]
fn random_payloads_are_reproducible_by_seed_and_differ_across_seeds_and_trials() {
    let a = campaign::trial_of(&setup(11, false), 3).expect("a trial");
    let again = campaign::trial_of(&setup(11, false), 3).expect("a trial");
    assert_eq!(a.scenario_toml, again.scenario_toml);
    assert_eq!(a.loaded.scenario, again.loaded.scenario);
    assert_eq!(
        (a.loaded.plant, a.mission_seed),
        (again.loaded.plant, again.mission_seed)
    );
    let other_seed = campaign::trial_of(&setup(12, false), 3).expect("a trial");
    let other_trial = campaign::trial_of(&setup(11, false), 4).expect("a trial");
    for other in [&other_seed, &other_trial] {
        assert_ne!(a.loaded.scenario.payload, other.loaded.scenario.payload);
        assert_ne!(a.loaded.plant, other.loaded.plant);
    }
    // A shard draws the same trial.
    let sharded = CampaignSetup {
        shard: (2, 4),
        ..setup(11, false)
    };
    let b = campaign::trial_of(&sharded, 3).expect("a trial");
    assert_eq!(a.scenario_toml, b.scenario_toml);
    // Faults come from a stream of their own: the payload and plant do not change with them.
    let faulted = campaign::trial_of(&setup(11, true), 3).expect("a trial");
    assert_eq!(a.scenario_toml, faulted.scenario_toml);
    assert_eq!(a.loaded.plant, faulted.loaded.plant);
}

#[test]
fn every_drawn_payload_passes_the_checks_and_the_robots_span_4_to_16() {
    let mut counts = BTreeSet::new();
    let mut vertices = BTreeSet::new();
    for seed in 0..300u64 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let drawn = payload::draw("drawn", &mut rng).expect("a payload");
        // The file it is reads back through every check to the same scenario.
        let again = scenario_file::parse(&drawn.toml, std::path::Path::new("drawn"))
            .unwrap_or_else(|e| panic!("seed {seed}: {e:#}\n{}", drawn.toml));
        let s = &again.scenario;
        assert_eq!(s, &drawn.loaded.scenario, "seed {seed}");
        let robots = s.robots.count();
        assert!(payload::ROBOTS.contains(&robots), "seed {seed}: {robots}");
        counts.insert(robots);
        vertices.insert(s.payload.footprint.len());
        let truth = s.truth.expect("a truth");
        let e = &s.estimation;
        assert!(
            polygon_contains(&s.payload.footprint, truth.com),
            "seed {seed}: COM off the footprint"
        );
        let on_grid = |axis: usize, v: f32| (e.grid_min[axis]..=e.grid_max[axis]).contains(&v);
        assert!(
            on_grid(0, truth.com.x) && on_grid(1, truth.com.y) && on_grid(2, truth.mass),
            "seed {seed}: the truth off its grid"
        );
        // The heaviest payload of the grid leaves the robots a margin, as the paper's cases.
        let weight = (e.grid_max[2] + robots as f32 * s.robots.mass) * 9.81;
        assert!(
            weight < 0.5 * robots as f32 * s.robots.max_thrust,
            "seed {seed}"
        );
        assert!(drawn.redrawn.len() < payload::MAX_ATTEMPTS);
    }
    assert_eq!(
        counts,
        payload::ROBOTS.collect::<BTreeSet<_>>(),
        "every robot count from 4 to 16 drawn"
    );
    assert_eq!(vertices, payload::VERTICES.collect::<BTreeSet<_>>());
}

#[test]
fn faults_are_the_simulators_injections_on_about_half_the_trials() {
    let s = setup(5, true);
    let mut kinds = BTreeSet::new();
    let mut faulted = 0;
    let trials = 200;
    for i in 0..trials {
        let t = campaign::trial_of(&s, i).expect("a trial");
        let Some(f) = t.fault else { continue };
        faulted += 1;
        let text = f.to_string();
        // Each one as `mission --inject` takes it.
        let parsed = host_sim::inject::Injection::parse(&text).expect("a valid injection");
        assert_eq!(parsed.fault, f.fault, "{text}");
        let robots = t.loaded.scenario.robots.count();
        assert!(
            host_sim::inject::check_robots(&[f], &t.loaded).is_ok(),
            "{text} on {robots} robots"
        );
        kinds.insert(faults::kind(&f.fault));
    }
    assert_eq!(kinds, faults::KINDS.into_iter().collect::<BTreeSet<_>>());
    let share = faulted as f64 / trials as f64;
    assert!(
        (faults::FAULT_SHARE - 0.15..=faults::FAULT_SHARE + 0.15).contains(&share),
        "{faulted} of {trials} faulted"
    );
    let none = setup(5, false);
    assert!((0..20).all(|i| {
        campaign::trial_of(&none, i)
            .expect("a trial")
            .fault
            .is_none()
    }));
}

fn json(args: &[&str]) -> serde_json::Value {
    let out = host_sim(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        matches!(out.status.code(), Some(0 | 3 | 4 | 5)),
        "{args:?}: {stderr}"
    );
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{args:?}: {e}: {stderr}"))
}

#[test]
fn two_shards_merged_give_exactly_the_unsharded_campaigns_report() {
    let dir = std::env::temp_dir().join(format!("campaign-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    let out = dir.join("figures");
    let out_text = out.to_string_lossy().to_string();
    let whole = json(&[
        "campaign", "--trials", "6", "--seed", "5", "--faults", "--jobs", "2", "--output",
        &out_text, "--json",
    ]);
    for key in [
        "trials",
        "delivered",
        "dropped",
        "aborted",
        "false_alarms",
        "final_error_m",
    ] {
        assert!(whole.get(key).is_some(), "no `{key}` in {whole}");
    }
    for key in ["p50", "p95", "max"] {
        assert!(
            whole["final_error_m"].get(key).is_some(),
            "no final_error_m.{key}"
        );
    }
    assert_eq!(whole["trials"], 6);
    // The counts add up, over the trials and over the faults.
    let n = |v: &serde_json::Value| v.as_u64().expect("a count");
    let results = whole["results"].as_array().expect("the trials");
    let aborted: u64 = whole["aborted"]
        .as_object()
        .expect("reasons")
        .values()
        .map(n)
        .sum();
    assert_eq!(
        n(&whole["delivered"]) + n(&whole["not_delivered"]) + n(&whole["dropped"]) + aborted,
        6
    );
    let healthy_aborts = results
        .iter()
        .filter(|r| r["outcome"] == "aborted" && r["fault"].is_null())
        .count() as u64;
    assert_eq!(n(&whole["false_alarms"]), healthy_aborts);
    let faulted = results.iter().filter(|r| !r["fault"].is_null()).count() as u64;
    assert_eq!(n(&whole["faulted"]), faulted);
    let mut tallied = 0;
    for (kind, t) in whole["faults"].as_object().expect("faults") {
        assert!(faults::KINDS.contains(&kind.as_str()), "{kind}");
        assert_eq!(
            n(&t["found"]) + n(&t["dropped"]) + n(&t["missed"]) + n(&t["not_reached"]),
            n(&t["trials"]),
            "{kind}"
        );
        tallied += n(&t["trials"]);
    }
    assert_eq!(tallied, faulted);
    for r in results {
        assert!(payload::ROBOTS.contains(&(n(&r["robots"]) as usize)), "{r}");
        assert!(
            r["scenario"]
                .as_str()
                .is_some_and(|s| s.starts_with("random-5-"))
        );
    }
    // The figure, and each trial not delivered (or delivered on a fault never found) as a
    // file `mission` flies as the campaign did.
    for file in ["campaign-outcomes.png", "campaign-outcomes.svg"] {
        let len = std::fs::metadata(out.join(file)).map_or(0, |m| m.len());
        assert!(len > 1000, "{file}: {len} bytes");
    }
    for r in results {
        let path = out.join(format!("trial-{}.toml", r["trial"]));
        assert_eq!(
            path.exists(),
            r["outcome"] != "delivered" || r["fault_found"] == false,
            "{}",
            path.display()
        );
        if let Ok(text) = std::fs::read_to_string(&path) {
            let loaded = scenario_file::parse(&text, &path).expect("a valid scenario");
            assert_eq!(loaded.name, r["scenario"].as_str().unwrap_or_default());
            assert!(text.contains(&format!("--seed {}", r["mission_seed"])));
        }
    }
    let mut files = Vec::new();
    for shard in ["1/2", "2/2"] {
        let part = json(&[
            "campaign", "--trials", "6", "--seed", "5", "--faults", "--shard", shard, "--json",
        ]);
        assert_eq!(part["trials"], 3, "shard {shard}");
        let path = dir.join(format!("shard-{}.json", &shard[..1]));
        std::fs::write(&path, part.to_string()).expect("written");
        files.push(path.to_string_lossy().to_string());
    }
    let mut args = vec!["campaign", "merge"];
    args.extend(files.iter().map(String::as_str));
    args.push("--json");
    let merged = json(&args);
    assert_eq!(merged, whole, "the merged shards are the whole campaign");
    // A trial's file flies again as the campaign flew it.
    let first = &results[0];
    let file = dir.join("trial-0.toml");
    let text = campaign::trial_file(
        &CampaignSetup {
            trials: 6,
            ..setup(5, true)
        },
        0,
    )
    .expect("trial 0's file");
    std::fs::write(&file, text).expect("written");
    let seed = first["mission_seed"].to_string();
    let mut args = vec![
        "mission",
        "--scenario",
        file.to_str().expect("a path"),
        "--seed",
        &seed,
        "--json",
    ];
    if let Some(fault) = first["fault"].as_str() {
        args.extend(["--inject", fault]);
    }
    let again = json(&args);
    assert_eq!(again["aborted"], first["aborted"], "{again}");
    if let Some(error) = first["final_error_m"].as_f64() {
        let replayed = again["final_position_error_m"].as_f64().expect("an error");
        assert!(
            (replayed - error).abs() < 1e-6,
            "{replayed} m, was {error} m"
        );
    }
    // The same shard twice is not the campaign.
    let twice = host_sim(&["campaign", "merge", &files[0], &files[0]]);
    assert_eq!(twice.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&twice.stderr).contains("given twice"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bad_shard_or_dispersion_is_refused_naming_it() {
    let out = host_sim(&["campaign", "--shard", "3/2"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("K runs from 1 to N"));
    let dir = std::env::temp_dir().join(format!("dispersion-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    let path = dir.join("d.toml");
    std::fs::write(&path, "wind_speed = [0.0, 1.0]\n").expect("written");
    let out = host_sim(&["campaign", "--dispersion", &path.to_string_lossy()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("wind_speed"));
    std::fs::write(&path, "gust = [2.0, 1.0]\n").expect("written");
    let out = host_sim(&["campaign", "--dispersion", &path.to_string_lossy()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("gust: [2, 1] is not a range"));
    let _ = std::fs::remove_dir_all(&dir);
}
