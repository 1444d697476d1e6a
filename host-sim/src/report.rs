//! Flight reports on disk: the time series as CSV and the figures of [`crate::figures`].

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::harness::{FlightOutcome, FlightSetup};

/// Writes `<dir>/<stem>.csv`, `<stem>-height.png` and `<stem>-attitude.png` with
/// `stem = <name>-<formation>-<mixer>`, and returns the files written. A figure that cannot be
/// drawn (no font) is reported on stderr; the CSV always is written.
pub fn write_flight(
    dir: &Path,
    name: &str,
    setup: &FlightSetup,
    outcome: &FlightOutcome,
) -> Result<Vec<PathBuf>> {
    fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let stem = format!("{name}-{:?}-{:?}", setup.formation, setup.mixer).to_lowercase();
    let csv = dir.join(format!("{stem}.csv"));
    let mut f =
        fs::File::create(&csv).with_context(|| format!("cannot write {}", csv.display()))?;
    writeln!(
        f,
        "t_s,x_m,y_m,z_m,ref_x_m,ref_y_m,ref_z_m,roll_deg,pitch_deg,yaw_deg,max_thrust_fraction,collective_n,saturated"
    )?;
    for s in &outcome.samples {
        writeln!(
            f,
            "{:.4},{:.5},{:.5},{:.5},{:.5},{:.5},{:.5},{:.3},{:.3},{:.3},{:.4},{:.3},{}",
            s.t,
            s.position.x,
            s.position.y,
            s.position.z,
            s.reference.x,
            s.reference.y,
            s.reference.z,
            s.attitude_deg.x,
            s.attitude_deg.y,
            s.attitude_deg.z,
            s.max_thrust_fraction,
            s.collective,
            u8::from(s.saturated)
        )?;
    }
    let mut written = vec![csv];
    let label = format!("{:?} formation, {:?} mixer", setup.formation, setup.mixer);
    let height = crate::figures::height(
        &dir.join(format!("{stem}-height.png")),
        &format!("{name}: height, {label}"),
        &[(label.as_str(), outcome)],
    );
    let attitude = crate::figures::attitude(
        &dir.join(format!("{stem}-attitude.png")),
        &format!("{name}: roll and pitch, {label}"),
        outcome,
    );
    for figure in [height, attitude] {
        match figure {
            Ok(path) => written.push(path),
            Err(e) => eprintln!("warning: figure skipped: {e:#}"),
        }
    }
    Ok(written)
}

/// Writes the paper's comparison figure, height over time for several flights, to
/// `<dir>/<name>-height-comparison.png`.
pub fn write_comparison(
    dir: &Path,
    name: &str,
    flights: &[(&str, &FlightOutcome)],
) -> Result<PathBuf> {
    fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    crate::figures::height(
        &dir.join(format!("{name}-height-comparison.png")),
        &format!("{name}: height, even vs optimised formation"),
        flights,
    )
}
