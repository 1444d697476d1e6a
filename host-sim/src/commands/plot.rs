//! `host-sim plot FILE.ulg --output DIR`: the one-page mission summary of `mission --output`
//! drawn from a flight log, the firmware's, the simulator's or a real flight's
//! (docs/formats.md#plotting-a-flight-log). It says what the log lacks (a topic, the lifts,
//! its end) and how much of a log cut short or corrupt it read; a file it cannot read at all
//! is an error naming what is wrong.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Args;
use flight_log::reader::{self, Stop, Ulog};
use serde_json::json;

use crate::cli::Outcome;
use crate::figures::canvas;
use crate::log_summary::{LogSummary, summarise};
use crate::report::{file_stem, print_json};
use crate::say;
use crate::scenario_file;

/// Arguments of `plot`.
#[derive(Debug, Args)]
pub struct PlotArgs {
    /// The flight log (ULog, as `mission --log` or the firmware writes it).
    #[arg(value_name = "FILE.ulg")]
    log: PathBuf,
    /// Write `<log's name>-mission-summary.png` and `.svg` into this folder.
    #[arg(long, value_name = "DIR")]
    output: PathBuf,
    /// The scenario flown (its robots' maximum thrust and its truth): the thrusts in newtons
    /// and each lift beside the model's lift-off thrust.
    #[arg(long, value_name = "FILE")]
    scenario: Option<PathBuf>,
    /// Print one JSON object on stdout and nothing else.
    #[arg(long)]
    json: bool,
}

/// Runs the command.
pub fn run(args: &PlotArgs) -> Result<Outcome> {
    let log = reader::read_file(&args.log)?;
    if log.data_messages() == 0 {
        let why = match &log.stop {
            Some(Stop::Truncated { at }) => format!(", ending at byte {at} inside a message"),
            Some(Stop::Corrupt { at, why }) => format!(", corrupt from byte {at} ({why})"),
            None => String::new(),
        };
        bail!(
            "{} holds no data to plot (read {} of its {} bytes{why})",
            args.log.display(),
            log.read,
            log.len()
        );
    }
    let loaded = args
        .scenario
        .as_deref()
        .map(scenario_file::load)
        .transpose()?;
    let name = args
        .log
        .file_stem()
        .map_or_else(|| "log".to_string(), |s| s.to_string_lossy().into_owned());
    let summary = summarise(&log, &name, loaded.as_ref().map(|l| &l.scenario));
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("cannot create {}", args.output.display()))?;
    let files = canvas::write(
        &args.output,
        &format!("{}-mission-summary", file_stem(&name)),
        &summary.summary,
    );
    if args.json {
        print_json(report(args, &log, &summary, &files))?;
    } else {
        // Notes go to stderr: stdout stays what the log holds.
        let mut err = std::io::stderr().lock();
        for note in &summary.notes {
            let _ = writeln!(err, "note: {note}");
        }
        tell(args, &log, &summary, &files)?;
    }
    Ok(Outcome::Done)
}

/// What the log says, for people.
fn tell(args: &PlotArgs, log: &Ulog, s: &LogSummary, files: &[PathBuf]) -> Result<()> {
    let what = |key: &str| log.info(key).unwrap_or("unknown").to_string();
    say!(
        "{}: {} on {} (software {}), {:.1} s, {} of {} bytes read",
        args.log.display(),
        what("sys_name"),
        what("ver_hw"),
        what("ver_sw"),
        s.summary.end_s,
        log.read,
        log.len()
    )?;
    for p in &s.summary.phases {
        say!("  {:7.2} s  {}", p.start, p.name)?;
    }
    for l in &s.summary.lifts {
        let model = l
            .model
            .map_or(String::new(), |m| format!(", the model says {m:.3} N"));
        match l.reading {
            Some(r) => say!("lift with pair {}: read {r:.3} N{model}", l.pair)?,
            None => say!("lift with pair {}: could not lift{model}", l.pair)?,
        }
    }
    say!("{} flight samples from take-off", s.summary.series.len())?;
    for path in files {
        say!("wrote {}", path.display())?;
    }
    Ok(())
}

/// The JSON report: the log, what it holds, what it lacks (`notes`) and the files written.
fn report(args: &PlotArgs, log: &Ulog, s: &LogSummary, files: &[PathBuf]) -> serde_json::Value {
    json!({
        "log": args.log.display().to_string(),
        "bytes": log.len(),
        "bytes_read": log.read,
        "complete": log.stop.is_none(),
        "mission_ended": !s.cut_short,
        "sys_name": log.info("sys_name"),
        "ver_sw": log.info("ver_sw"),
        "ver_hw": log.info("ver_hw"),
        "duration_s": s.summary.end_s,
        "phases": s.summary.phases.iter().map(|p| json!({
            "name": p.name,
            "start_s": p.start,
            "duration_s": p.end - p.start,
        })).collect::<Vec<_>>(),
        "lifts": s.summary.lifts.iter().map(|l| json!({
            "pair": l.pair,
            "reading": l.reading,
            "model": l.model,
        })).collect::<Vec<_>>(),
        "flight_samples": s.summary.series.len(),
        "notes": s.notes,
        "files": files.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
    })
}
