//! `host-sim campaign`: many missions on the paper's cases, each plant drawn from a
//! dispersion of the `[plant]` departures, in parallel; `campaign merge` joins the shards'
//! JSON (docs/commands.md#campaign).

use std::path::PathBuf;

use anyhow::{Context, Result, anyhow};
use clap::{Args, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};

use crate::campaign::{self, CampaignOutput, CampaignSetup, Dispersion};
use crate::cli::Outcome;
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
            "{} trials (seed {}, shard {}/{}): {} delivered within {} m, {} not delivered, {} dropped, {} aborted ({} false alarms)",
            r.trials,
            out.seed,
            out.shard[0],
            out.shard[1],
            r.delivered,
            campaign::DELIVERED_WITHIN,
            r.not_delivered,
            r.dropped,
            r.aborted.values().sum::<usize>(),
            r.false_alarms
        )?;
        for (why, n) in &r.aborted {
            say!("  aborted {n}x: {why}")?;
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
    let out = CampaignOutput {
        campaign_trials: setup.trials,
        seed: setup.seed,
        dispersion,
        shard: [k, n],
        report: campaign::report(&results),
        results,
    };
    show(&out, args.json)
}
