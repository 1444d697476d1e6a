//! What `estimate --output DIR` writes: every trial as CSV, the first trial step by step as
//! JSON, and the figures of [`crate::figures::estimate_summary`] (the paper's Fig. 7) and
//! [`crate::figures::estimate_steps`] (its Fig. 6, one page per step). Files are named from the
//! scenario's name through [`file_stem`]; a figure that cannot be drawn is skipped with a
//! warning, the CSV and JSON are written regardless.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde_json::json;
use shared::estimation::Measurement;

use crate::figures::canvas;
use crate::figures::estimate_steps::StepFigure;
use crate::figures::estimate_summary::ErrorSummary;
use crate::monte_carlo::{Summary, Trial};
use crate::report::file_stem;
use crate::trial_trace::TrialTrace;

/// Writes into `dir`, with `stem` = `name` through [`file_stem`]:
/// `<stem>-estimate-trials.csv` (one row per trial), `<stem>-estimate-steps.json` (the traced
/// trial: each step's marginals and information), `<stem>-estimate-summary.png`/`.svg` and
/// `<stem>-estimate-step-<k>.png`/`.svg` for `k` = 0 (before the first lift) to the last lift.
/// Returns the files written.
pub fn write(
    dir: &Path,
    name: &str,
    summary: &Summary,
    trials: &[Trial],
    resolution: [f32; 3],
    trace: &TrialTrace,
) -> Result<Vec<PathBuf>> {
    fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let stem = format!("{}-estimate", file_stem(name));
    let csv = dir.join(format!("{stem}-trials.csv"));
    write_trials(&csv, trials, resolution)?;
    let steps = dir.join(format!("{stem}-steps.json"));
    write_steps(&steps, trace)?;
    let mut written = vec![csv, steps];
    let scenarios = [(name.to_string(), *summary)];
    written.extend(canvas::write(
        dir,
        &format!("{stem}-summary"),
        &ErrorSummary {
            title: format!(
                "{name}: estimation error over {} trials (the paper's Fig. 7)",
                trials.len()
            ),
            scenarios: &scenarios,
        },
    ));
    for index in 0..trace.steps.len() {
        written.extend(canvas::write(
            dir,
            &format!("{stem}-step-{index}"),
            &StepFigure {
                name,
                trial: 1,
                trace,
                index,
            },
        ));
    }
    Ok(written)
}

fn write_trials(path: &Path, trials: &[Trial], resolution: [f32; 3]) -> Result<()> {
    let mut f =
        fs::File::create(path).with_context(|| format!("cannot write {}", path.display()))?;
    writeln!(
        f,
        "trial,truth_x_m,truth_y_m,truth_mass_kg,estimate_x_m,estimate_y_m,estimate_mass_kg,error_x_over_res,error_y_over_res,error_mass_over_res,lifts,converged,thrust_scale"
    )?;
    for (i, t) in trials.iter().enumerate() {
        let e = [0, 1, 2].map(|a| (t.estimate[a] - t.truth[a]) / resolution[a]);
        writeln!(
            f,
            "{},{:.4},{:.4},{:.3},{:.4},{:.4},{:.3},{:.3},{:.3},{:.3},{},{},{:.3}",
            i + 1,
            t.truth[0],
            t.truth[1],
            t.truth[2],
            t.estimate[0],
            t.estimate[1],
            t.estimate[2],
            e[0],
            e[1],
            e[2],
            t.measurements,
            u8::from(t.converged),
            t.thrust_scale
        )?;
    }
    Ok(())
}

fn write_steps(path: &Path, trace: &TrialTrace) -> Result<()> {
    let grid = &trace.grid;
    let [nx, ny, nm] = grid.shape();
    let value = json!({
        "truth": trace.truth,
        "com_x_m": (0..nx).map(|i| grid.axis_value(0, i)).collect::<Vec<_>>(),
        "com_y_m": (0..ny).map(|i| grid.axis_value(1, i)).collect::<Vec<_>>(),
        "mass_kg": (0..nm).map(|i| grid.mass(i)).collect::<Vec<_>>(),
        "steps": trace.steps.iter().map(|s| json!({
            "pair": s.lift.map(|(g, _)| g),
            "reading": s.lift.and_then(|(_, m)| match m {
                Measurement::Lifted { thrust } => Some(thrust),
                Measurement::CouldNotLift => None,
            }),
            "could_not_lift": s.lift.is_some_and(|(_, m)| m == Measurement::CouldNotLift),
            "model": s.model,
            "estimate": s.estimate.theta,
            "com_marginal": s.com_marginal.chunks(ny.max(1)).collect::<Vec<_>>(),
            "mass_marginal": s.mass_marginal,
            "information": s.information,
            "next_pair": s.next,
        })).collect::<Vec<_>>(),
    });
    let mut value = value;
    crate::report::shortest_f32_numbers(&mut value);
    fs::write(path, format!("{value}\n"))
        .with_context(|| format!("cannot write {}", path.display()))
}
