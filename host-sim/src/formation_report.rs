//! What `formation --output DIR` writes: each robot's place in the even and the optimised
//! formation as CSV, and the figure of [`crate::figures::formation`]. Files are named from the
//! scenario's name through [`file_stem`]; a figure that cannot be drawn is skipped with a
//! warning, the CSV is written regardless.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use shared::scenario::Scenario;

use crate::figures::canvas;
use crate::figures::formation::FormationFigure;
use crate::report::file_stem;

/// Writes `<stem>-formation.csv` and `<stem>-formation.png`/`.svg` into `dir` (`stem`: the
/// scenario's name through [`file_stem`]); returns the files written.
pub fn write(dir: &Path, name: &str, figure: &FormationFigure<'_>) -> Result<Vec<PathBuf>> {
    fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let stem = format!("{}-formation", file_stem(name));
    let csv = dir.join(format!("{stem}.csv"));
    write_csv(&csv, figure.scenario, figure.even.0, figure.optimised.0)?;
    let mut written = vec![csv];
    written.extend(canvas::write(dir, &stem, figure));
    Ok(written)
}

fn write_csv(path: &Path, s: &Scenario, even: &[f32], optimised: &[f32]) -> Result<()> {
    let mut f =
        fs::File::create(path).with_context(|| format!("cannot write {}", path.display()))?;
    writeln!(
        f,
        "robot,spin,even_arc_m,even_x_m,even_y_m,optimised_arc_m,optimised_x_m,optimised_y_m"
    )?;
    let rail = &s.payload.rail;
    for (j, (&e, &o)) in even.iter().zip(optimised).enumerate() {
        let (pe, po) = (rail.point_at(e), rail.point_at(o));
        writeln!(
            f,
            "{},{},{e:.4},{:.4},{:.4},{o:.4},{:.4},{:.4}",
            j + 1,
            s.robots.spin.get(j).copied().unwrap_or(1),
            pe.x,
            pe.y,
            po.x,
            po.y
        )?;
    }
    Ok(())
}
