//! `host-sim campaign`: many missions on random payloads (or the paper's cases), each plant
//! drawn from a dispersion of the `[plant]` departures, optionally a fault, in parallel;
//! `--output` draws the outcomes over what was drawn and keeps each trial not delivered as a
//! scenario file; `campaign merge` joins the shards' JSON (docs/commands.md#campaign).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow};
use clap::{Args, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

use crate::campaign::{self, CampaignOutput, CampaignSetup, Dispersion, PayloadSource};
use crate::cli::Outcome;
use crate::figures::campaign_outcomes::CampaignOutcomes;
use crate::figures::canvas;
use crate::report::print_json;
use crate::say;

/// Arguments of `campaign`.
#[derive(Debug, Args)]
pub struct CampaignArgs {
    /// `merge FILE...`: the shards' `--json` outputs joined into the report one run prints.
    #[command(subcommand)]
    merge: Option<CampaignCommand>,
    /// Trials in the campaign (1 to 100,000).
    #[arg(long, default_value_t = 100)]
    trials: usize,
    /// The campaign's seed: the same seed, the same trials.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// A dispersion file (TOML: each `[plant]` key a `[low, high]` range; the defaults for
    /// the others).
    #[arg(long, value_name = "FILE")]
    dispersion: Option<PathBuf>,
    /// What the trials fly: a payload drawn for each (`random`) or the paper's six cases in
    /// turn (`paper`).
    #[arg(long, value_enum, default_value = "random")]
    payloads: PayloadSource,
    /// Give about half the trials one fault each (a rotor, the IMU, motion capture, the
    /// ground link, the battery or a stepper), and report each kind found or missed.
    #[arg(long)]
    faults: bool,
    /// Write the figure of outcomes over the drawn parameters (`campaign-outcomes.png`,
    /// `.svg`) and each trial not delivered as a scenario file (`trial-<i>.toml`) here.
    #[arg(long, value_name = "DIR")]
    output: Option<PathBuf>,
    /// Threads (default: one per core).
    #[arg(long, value_name = "J")]
    jobs: Option<usize>,
    /// Run the K-th of N disjoint slices of the campaign (`--shard 2/4`), for a batch system.
    #[arg(long, value_name = "K/N", value_parser = parse_shard)]
    shard: Option<(usize, usize)>,
    /// Print one JSON object on stdout and nothing else (every trial with the report).
    #[arg(long)]
    json: bool,
}

/// `campaign`'s own subcommand.
#[derive(Debug, Subcommand)]
enum CampaignCommand {
    /// Join the shards' `campaign --json` outputs into the campaign's report.
    Merge {
        /// The shards' JSON files, one a shard.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Print one JSON object on stdout and nothing else.
        #[arg(long)]
        json: bool,
    },
}

/// `K/N` with `1 <= K <= N`.
fn parse_shard(text: &str) -> Result<(usize, usize), String> {
    let (k, n) = text
        .split_once('/')
        .ok_or_else(|| format!("`{text}`: give K/N, the K-th of N shards"))?;
    let k: usize = k
        .trim()
        .parse()
        .map_err(|_| format!("`{k}` is not a whole number"))?;
    let n: usize = n
        .trim()
        .parse()
        .map_err(|_| format!("`{n}` is not a whole number"))?;
    if n == 0 || k == 0 || k > n {
        return Err(format!("{k}/{n}: K runs from 1 to N"));
    }
    Ok((k, n))
}

/// Prints `out` for people (or as JSON).
fn show(out: &CampaignOutput, json: bool) -> Result<Outcome> {
    if json {
        print_json(serde_json::to_value(out)?)?;
    } else {
        let r = &out.report;
        say!(
            "{} trials (seed {}, shard {}/{}): {} delivered within {} m, {} not delivered, {} dropped, {} refused, {} aborted ({} false alarms)",
            r.trials,
            out.seed,
            out.shard[0],
            out.shard[1],
            r.delivered,
            campaign::DELIVERED_WITHIN,
            r.not_delivered,
            r.dropped,
            r.refused,
            r.aborted.values().sum::<usize>(),
            r.false_alarms
        )?;
        for (why, n) in &r.aborted {
            say!("  aborted {n}x: {why}")?;
        }
        if r.refused > 0 {
            let [failed, flown] = r.refused_flown_failed;
            say!(
                "refused before take-off for want of margin: {} (flown anyway with the refusal off: {failed} of {flown} did not deliver)",
                r.refused
            )?;
        }
        if r.faulted > 0 {
            say!(
                "given a fault: {} trials (an abort there is no false alarm)",
                r.faulted
            )?;
            for (kind, t) in &r.faults {
                let unmet = if t.not_reached > 0 {
                    format!(
                        " ({} more never met: the flight had ended, or never began, by its time)",
                        t.not_reached
                    )
                } else {
                    String::new()
                };
                let unholdable = if t.dropped_unholdable > 0 {
                    format!(
                        " ({} where the robots left cannot hold it level at all)",
                        t.dropped_unholdable
                    )
                } else {
                    String::new()
                };
                say!(
                    "  {kind}: {} of {} found, {} dropped{unholdable}, {} missed{unmet}",
                    t.found,
                    t.trials - t.not_reached,
                    t.dropped,
                    t.missed
                )?;
            }
        }
        let redrawn: usize = r.redrawn.values().sum();
        if redrawn > 0 {
            say!("payloads drawn again before those flown: {redrawn}, refused by")?;
            for (why, n) in &r.redrawn {
                say!("  {n}x: {why}")?;
            }
        }
        let e = r.final_error_m;
        let m = |v: Option<f32>| v.map_or("none".to_string(), |v| format!("{v:.3} m"));
        say!(
            "final error: median {}, 95th percentile {}, largest {}",
            m(e.p50),
            m(e.p95),
            m(e.max)
        )?;
    }
    let r = &out.report;
    Ok(if r.dropped > 0 {
        Outcome::Dropped
    } else if r.false_alarms > 0 {
        Outcome::Aborted
    } else if r.not_delivered > 0 {
        Outcome::NotDelivered
    } else {
        Outcome::Done
    })
}

/// Writes the figure of outcomes over the drawn parameters and each trial not delivered as a
/// scenario file into `dir`; says which files (unless `quiet`: the JSON goes alone on stdout).
fn write_output(
    dir: &Path,
    setup: &CampaignSetup,
    results: &[campaign::TrialResult],
    quiet: bool,
) -> Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create the output folder {}", dir.display()))?;
    let figure = CampaignOutcomes {
        results,
        title: format!(
            "campaign seed {}: {} trials, final error over what was drawn",
            setup.seed,
            results.len()
        ),
    };
    let mut written = canvas::write(dir, "campaign-outcomes", &figure);
    // Each trial not delivered, and each fault missed (delivered on a fault never found).
    for r in results
        .iter()
        .filter(|r| r.outcome != "delivered" || r.fault_found == Some(false))
    {
        let path = dir.join(format!("trial-{}.toml", r.trial));
        let text = campaign::trial_file(setup, r.trial)?;
        std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))?;
        written.push(path);
    }
    if !quiet {
        for path in written {
            say!("wrote {}", path.display())?;
        }
    }
    Ok(())
}

/// Runs the command.
pub fn run(args: &CampaignArgs) -> Result<Outcome> {
    if let Some(CampaignCommand::Merge { files, json }) = &args.merge {
        let parts = files
            .iter()
            .map(|f| {
                let text = std::fs::read_to_string(f)
                    .with_context(|| format!("cannot read {}", f.display()))?;
                serde_json::from_str::<CampaignOutput>(&text)
                    .map_err(|e| anyhow!("{}: not a `campaign --json` output: {e}", f.display()))
            })
            .collect::<Result<Vec<_>>>()?;
        return show(&campaign::merge(&parts)?, *json);
    }
    let dispersion = match &args.dispersion {
        Some(path) => Dispersion::load(path)?,
        None => Dispersion::DEFAULT,
    };
    let setup = CampaignSetup {
        trials: args.trials,
        seed: args.seed,
        dispersion,
        payloads: args.payloads,
        faults: args.faults,
        shard: args.shard.unwrap_or((1, 1)),
    };
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(j) = args.jobs {
        if j == 0 {
            return Err(anyhow!("--jobs 0: at least one thread"));
        }
        pool = pool.num_threads(j);
    }
    let pool = pool.build()?;
    let (k, n) = setup.shard;
    let mine = (0..setup.trials).filter(|i| i % n == k - 1).count();
    let bar = if args.json {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(mine as u64).with_style(
            ProgressStyle::with_template("campaign [{bar:40}] {pos}/{len} missions, {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        )
    };
    let results = pool.install(|| campaign::run(&setup, &|| bar.inc(1)))?;
    bar.finish_and_clear();
    if let Some(dir) = &args.output {
        write_output(dir, &setup, &results, args.json)?;
    }
    let out = CampaignOutput {
        campaign_trials: setup.trials,
        seed: setup.seed,
        dispersion,
        payloads: setup.payloads,
        fault_injection: setup.faults,
        shard: [k, n],
        report: campaign::report(&results),
        results,
    };
    show(&out, args.json)
}
