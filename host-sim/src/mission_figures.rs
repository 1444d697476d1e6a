//! What `mission --output DIR` writes about the flight: the robots' rail positions, each
//! rotor's thrust and the payload's roll and pitch over time, as one PNG of three panels
//! (plotters) with the injected load shift and each in-flight re-formation marked, and the
//! same samples as CSV (a load that shifts in flight, docs/system.md#in-flight-adaptation); beside them the
//! whole mission on one page ([`crate::figures::mission_summary`], PNG and SVG).

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::figures::canvas;
use crate::figures::mission_summary::{LiftBar, MissionSummary, Span, SummarySample};
use crate::mission_run::{FlightSample, MissionOutcome};
use crate::report::file_stem;

use crate::figures::canvas::{colour, draw_error};

/// Writes `<name>-mission-flight.csv` and `.png`, and `<name>-mission-summary.png` and `.svg`,
/// into `dir` (`name` through [`file_stem`]); returns the paths written. `max_thrust` is the
/// robots' maximum thrust, N (the summary's lifts). A figure is skipped with a warning (the CSV
/// stays) where it cannot be drawn (no font; the flight figure of a mission that never flew).
pub fn write(
    dir: &Path,
    name: &str,
    outcome: &MissionOutcome,
    max_thrust: f32,
) -> Result<Vec<PathBuf>> {
    fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let stem = format!("{}-mission-flight", file_stem(name));
    let csv = dir.join(format!("{stem}.csv"));
    write_csv(&csv, &outcome.series)?;
    let mut written = vec![csv];
    let png = dir.join(format!("{stem}.png"));
    match draw(&png, name, outcome) {
        Ok(()) => written.push(png),
        Err(e) => crate::report::warn(&format!("figure skipped: {e:#}")),
    }
    written.extend(canvas::write(
        dir,
        &format!("{}-mission-summary", file_stem(name)),
        &summary(name, outcome, max_thrust),
    ));
    Ok(written)
}

/// The one-page summary's data of a simulated mission: the scenario's `name`, what the
/// mission did, the robots' maximum thrust, N.
pub fn summary(name: &str, outcome: &MissionOutcome, max_thrust: f32) -> MissionSummary {
    let o = outcome;
    let verdict = if o.dropped {
        "dropped"
    } else if o.aborted.is_some() {
        "aborted"
    } else if o.delivered {
        "delivered"
    } else {
        "not delivered"
    };
    MissionSummary {
        title: format!(
            "{name}: the mission, {verdict} ({:.1} s simulated)",
            o.simulated_s
        ),
        end_s: o.simulated_s,
        phases: Span::from_durations(&o.phases, o.simulated_s),
        lifts: o
            .lifts
            .iter()
            .map(|&(pair, reading, model)| LiftBar {
                pair,
                reading,
                model: model.is_finite().then_some(model),
            })
            .collect(),
        max_thrust: Some(max_thrust),
        series: o
            .series
            .iter()
            .map(|s| SummarySample {
                t: s.t,
                height: s.height,
                roll_pitch_deg: s.roll_pitch_deg,
                thrust: s.thrust.clone(),
            })
            .collect(),
        thrust_in_newtons: true,
        no_flight: "no flight: the mission never took off".to_string(),
    }
}

fn write_csv(path: &Path, series: &[FlightSample]) -> Result<()> {
    let mut f =
        fs::File::create(path).with_context(|| format!("cannot write {}", path.display()))?;
    let n = series.first().map_or(0, |s| s.rail.len());
    let mut header = String::from("t_s,height_m,roll_deg,pitch_deg");
    for j in 0..n {
        header.push_str(&format!(",rail_{j}_m"));
    }
    for j in 0..n {
        header.push_str(&format!(",thrust_{j}_n"));
    }
    writeln!(f, "{header}")?;
    for s in series {
        let mut line = format!(
            "{:.3},{:.4},{:.3},{:.3}",
            s.t, s.height, s.roll_pitch_deg[0], s.roll_pitch_deg[1]
        );
        for v in s.rail.iter().chain(&s.thrust) {
            line.push_str(&format!(",{v:.4}"));
        }
        writeln!(f, "{line}")?;
    }
    Ok(())
}

/// One curve: its label, colour and (time, value) points.
type Curve = (String, RGBColor, Vec<(f32, f32)>);

/// Vertical dashed marks: (time, label, colour).
type Mark = (f32, String, RGBColor);

fn marks(outcome: &MissionOutcome) -> Vec<Mark> {
    let mut marks = Vec::new();
    if let Some(t) = outcome.shift_at {
        marks.push((t, "load shift".to_string(), RED));
    }
    for a in &outcome.adaptations {
        marks.push((a.t, "shift measured".to_string(), RGBColor(255, 127, 14)));
        if let Some(r) = a.rebalanced_at {
            marks.push((r, "rebalanced".to_string(), RGBColor(44, 160, 44)));
        }
    }
    marks
}

/// Where a panel's legend begins, pixels from its top.
const LEGEND_TOP: i32 = 40;
/// Distance between two legend entries, pixels.
const LEGEND_PITCH: i32 = 20;
/// Width and least height of the page, pixels (three panels of 386 under the title's 40).
const PAGE: (u32, u32) = (1100, 1200);
/// Room for the page's title, pixels.
const TITLE: u32 = 40;

/// The legend of a panel of `series` with `marks`: each series, then each kind of mark once
/// (a mission that adapts twice marks "shift measured" twice, with one colour).
fn legend_entries<'a>(series: &'a [Curve], marks: &'a [Mark]) -> Vec<(&'a str, RGBColor, bool)> {
    let mut entries: Vec<(&str, RGBColor, bool)> = series
        .iter()
        .map(|(label, c, _)| (label.as_str(), *c, false))
        .collect();
    for (_, label, c) in marks {
        if !entries
            .iter()
            .any(|(l, _, dashed)| *dashed && *l == label.as_str())
        {
            entries.push((label.as_str(), *c, true));
        }
    }
    entries
}

/// The page's size for panels whose longest legend has `entries`: tall enough that each
/// panel holds it.
fn page_size(entries: usize) -> (u32, u32) {
    let legend = LEGEND_TOP + LEGEND_PITCH * entries.saturating_sub(1) as i32 + 12;
    let panel = ((PAGE.1 - TITLE) / 3).max(legend.max(0) as u32);
    (PAGE.0, PAGE.1.max(TITLE + 3 * panel))
}

/// One panel: each series `(label, points)` against time, with the marks; the legend in a
/// column of its own right of the plot, so it covers no curve.
fn panel(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    title: &str,
    y_desc: &str,
    t: (f32, f32),
    series: &[Curve],
    marks: &[Mark],
) -> Result<()> {
    const LEGEND_WIDTH: u32 = 150;
    let width = area.dim_in_pixel().0;
    let (plot, legend) = area.split_horizontally(width.saturating_sub(LEGEND_WIDTH));
    let (lo, hi) = series
        .iter()
        .flat_map(|(_, _, p)| p.iter().map(|&(_, v)| v))
        .fold((f32::MAX, f32::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (0.0, 1.0) };
    let pad = ((hi - lo) * 0.08).max(0.05);
    let mut chart = ChartBuilder::on(&plot)
        .caption(title, ("sans-serif", 20))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(t.0..t.1, (lo - pad)..(hi + pad))
        .map_err(draw_error)?;
    chart
        .configure_mesh()
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .x_desc("time (s)")
        .y_desc(y_desc)
        .draw()
        .map_err(draw_error)?;
    for (time, _, c) in marks {
        chart
            .draw_series(DashedLineSeries::new(
                [(*time, lo - pad), (*time, hi + pad)],
                5,
                4,
                c.stroke_width(2),
            ))
            .map_err(draw_error)?;
    }
    for (_, c, points) in series {
        chart
            .draw_series(LineSeries::new(points.iter().copied(), c.stroke_width(2)))
            .map_err(draw_error)?;
    }
    for (k, (label, c, dashed)) in legend_entries(series, marks).into_iter().enumerate() {
        let y = LEGEND_TOP + LEGEND_PITCH * k as i32;
        let line = if dashed {
            PathElement::new(vec![(4, y), (10, y), (14, y), (20, y)], c.stroke_width(2))
        } else {
            PathElement::new(vec![(4, y), (24, y)], c.stroke_width(3))
        };
        legend.draw(&line).map_err(draw_error)?;
        if dashed {
            // A gap in the middle marks the dashed ones.
            legend
                .draw(&PathElement::new(
                    vec![(11, y), (13, y)],
                    WHITE.stroke_width(3),
                ))
                .map_err(draw_error)?;
        }
        legend
            .draw(&Text::new(
                label.to_string(),
                (30, y - 7),
                ("sans-serif", 14).into_font(),
            ))
            .map_err(draw_error)?;
    }
    Ok(())
}

/// Mean of each value over a centred window of `half` samples each side: the rotors'
/// commands carry the rate loop's answer to sensor noise, which hides their level.
fn smoothed(points: &[(f32, f32)], half: usize) -> Vec<(f32, f32)> {
    (0..points.len())
        .map(|i| {
            let lo = i.saturating_sub(half);
            let hi = (i + half + 1).min(points.len());
            let mean = points[lo..hi].iter().map(|p| p.1).sum::<f32>() / (hi - lo) as f32;
            (points[i].0, mean)
        })
        .collect()
}

fn draw(path: &Path, name: &str, outcome: &MissionOutcome) -> Result<()> {
    let s = &outcome.series;
    let (Some(first), Some(last)) = (s.first(), s.last()) else {
        return Err(anyhow!("the mission never flew: no flight to draw"));
    };
    let t = (first.t, last.t.max(first.t + 1.0));
    let n = first.rail.len();
    let marks = marks(outcome);
    let size = page_size(n + legend_entries(&[], &marks).len());
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(draw_error)?;
    let (title, body) = root.split_vertically(TITLE);
    let what = if marks.is_empty() {
        "the flight"
    } else {
        "the flight, load shift and re-formation"
    };
    title
        .titled(&format!("{name}: {what}"), ("sans-serif", 24))
        .map_err(draw_error)?;
    let panels = body.split_evenly((3, 1));
    let per_robot = |value: fn(&FlightSample, usize) -> f32, unit: &str| {
        (0..n)
            .map(|j| {
                (
                    // Robots counted from 1, as on the command line.
                    format!("robot {}{unit}", j + 1),
                    colour(j),
                    s.iter().map(|p| (p.t, value(p, j))).collect::<Vec<_>>(),
                )
            })
            .collect::<Vec<_>>()
    };
    panel(
        &panels[0],
        "robots' rail positions",
        "arc length (m)",
        t,
        &per_robot(|p, j| p.rail.get(j).copied().unwrap_or(0.0), ""),
        &marks,
    )?;
    // 100 Hz samples: 12 each side is a quarter-second mean.
    let thrusts: Vec<_> = per_robot(|p, j| p.thrust.get(j).copied().unwrap_or(0.0), "")
        .into_iter()
        .map(|(label, c, points)| (label, c, smoothed(&points, 12)))
        .collect();
    panel(
        &panels[1],
        "rotor thrusts (quarter-second means)",
        "thrust (N)",
        t,
        &thrusts,
        &marks,
    )?;
    let attitude = vec![
        (
            "roll".to_string(),
            colour(0),
            s.iter().map(|p| (p.t, p.roll_pitch_deg[0])).collect(),
        ),
        (
            "pitch".to_string(),
            colour(3),
            s.iter().map(|p| (p.t, p.roll_pitch_deg[1])).collect(),
        ),
    ];
    panel(
        &panels[2],
        "payload attitude",
        "angle (deg)",
        t,
        &attitude,
        &marks,
    )?;
    root.present().map_err(draw_error)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_robot_and_each_kind_of_mark_fits_in_a_flight_panel() {
        let marks: Vec<Mark> = vec![
            (60.0, "load shift".to_string(), RED),
            (61.0, "shift measured".to_string(), colour(1)),
            (62.0, "rebalanced".to_string(), colour(2)),
            (70.0, "shift measured".to_string(), colour(1)),
            (71.0, "rebalanced".to_string(), colour(2)),
        ];
        for robots in [4, 8, 12, 16] {
            let series: Vec<Curve> = (0..robots)
                .map(|j| (format!("robot {}", j + 1), colour(j), Vec::new()))
                .collect();
            let entries = legend_entries(&series, &marks);
            let labels: Vec<&str> = entries.iter().map(|e| e.0).collect();
            for j in 1..=robots {
                let name = format!("robot {j}");
                assert_eq!(labels.iter().filter(|l| **l == name).count(), 1, "{name}");
            }
            assert_eq!(entries.len(), robots + 3, "{labels:?}");
            let (_, height) = page_size(entries.len());
            let panel = (height - TITLE) / 3;
            let bottom = LEGEND_TOP + LEGEND_PITCH * (entries.len() as i32 - 1) + 12;
            assert!(
                bottom <= panel as i32,
                "{robots} robots: {bottom} px in {panel}"
            );
        }
        // Eight robots and no marks: the page as it was.
        assert_eq!(page_size(8), PAGE);
    }
}
