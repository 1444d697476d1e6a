//! `host-sim campaign` (docs/commands.md#campaign): the JSON keys other tools rely on, two
//! shards merged giving exactly the unsharded run's report, and bad shards and dispersions
//! refused naming what is wrong.

use crate::common::host_sim;

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
    let whole = json(&["campaign", "--trials", "6", "--seed", "5", "--json"]);
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
    let mut files = Vec::new();
    for shard in ["1/2", "2/2"] {
        let part = json(&[
            "campaign", "--trials", "6", "--seed", "5", "--shard", shard, "--json",
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
