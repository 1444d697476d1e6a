//! Formation decision through the command line (docs/formats.md#formation): the JSON keys,
//! the constraints on every paper case, the comparison with the even formation, and errors.

use crate::common;
use common::{host_sim, scenario_path};

fn formation_json(name: &str, extra: &[&str]) -> serde_json::Value {
    let path = scenario_path(name);
    let mut args = vec!["formation", "--scenario", path.to_str().unwrap(), "--json"];
    args.extend(extra);
    let out = host_sim(&args);
    assert!(
        out.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

#[test]
fn every_paper_case_gets_a_balanced_spaced_formation() {
    for (name, eps, perimeter) in [
        ("rect-sim1", 1e-5, 4.88),
        ("rect-sim2", 1e-5, 4.88),
        ("rect-ex1", 1e-5, 4.88),
        ("rect-ex2", 1e-5, 4.88),
        ("L-sim1", 1e-4, 3.44),
        ("L-sim2", 1e-4, 3.44),
    ] {
        let v = formation_json(name, &[]);
        for key in [
            "positions",
            "points",
            "det",
            "balance",
            "min_gap",
            "solve_ms",
        ] {
            assert!(!v[key].is_null(), "{name}: {key} missing");
        }
        let positions = floats(&v["positions"]);
        assert_eq!(positions.len(), 8, "{name}");
        assert!(
            positions.iter().all(|&s| (0.0..perimeter).contains(&s)),
            "{name}"
        );
        // Cyclic order: forward gaps add up to exactly one lap, each at least min_spacing.
        let gaps: Vec<f64> = (0..8)
            .map(|j| (positions[(j + 1) % 8] - positions[j]).rem_euclid(perimeter))
            .collect();
        assert!(
            (gaps.iter().sum::<f64>() - perimeter).abs() < 1e-3,
            "{name}: {gaps:?}"
        );
        assert!(gaps.iter().all(|&g| g >= 0.25 - 1e-6), "{name}: {gaps:?}");
        assert!(v["min_gap"].as_f64().unwrap() >= 0.25 - 1e-6);
        let balance = floats(&v["balance"]);
        assert!(
            balance.iter().all(|b| b.abs() <= eps),
            "{name}: {balance:?}"
        );
        // The even formation is what the paper compared against: it is not balanced.
        let even = floats(&v["even"]["balance"]);
        assert!(
            even.iter().any(|b| b.abs() > 100.0 * eps),
            "{name}: {even:?}"
        );
        assert!(v["det"].as_f64().unwrap() > 0.0);
    }
}

#[test]
fn given_com_is_used_and_bad_input_is_a_clear_error() {
    let v = formation_json("rect-sim1", &["--com=-0.2,0.03", "--mass", "3"]);
    assert_eq!(
        floats(&v["com"])
            .iter()
            .map(|c| *c as f32)
            .collect::<Vec<_>>(),
        [-0.2, 0.03]
    );

    let path = scenario_path("L-sim1");
    for (args, names) in [
        (vec!["--com=0.05,0.02"], "out of the robots' reach"),
        // The refusal says how close to balance the rail can get.
        (
            vec!["--com=0.05,0.02"],
            "the closest the rail allows leaves balance sums",
        ),
        (vec!["--com", "0.6,0.6"], "convex hull"),
        (vec!["--mass", "0"], "--mass"),
    ] {
        let mut all = vec!["formation", "--scenario", path.to_str().unwrap()];
        all.extend(args);
        let out = host_sim(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert!(err.contains(names), "must say {names}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    }
}
