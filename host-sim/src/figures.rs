//! Figures like the paper's, drawn with plotters. This file draws `fly`'s (docs/system.md#paper-cases;
//! the paper's Fig. 8): height over time for several flights against their
//! reference, and roll and pitch over time, as PNG files. The submodules draw the others, as PNG
//! and SVG through [`canvas`]: [`estimate_summary`] (Fig. 7) and [`estimate_steps`] (Fig. 6)
//! for `estimate`, [`formation`] for `formation`, [`mission_summary`] for `mission`, and
//! [`campaign_outcomes`] for `campaign`; [`summary_layout`] places the mission summary's text.
//!
//! Text is drawn with the system's sans-serif font (plotters' `ttf` feature, through
//! fontconfig). Where no font can be found the figure is skipped with a message; the CSV files
//! carry the same data.

pub mod campaign_outcomes;
pub mod canvas;
pub mod estimate_steps;
pub mod estimate_summary;
pub mod formation;
pub mod mission_summary;
pub mod summary_layout;

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use plotters::prelude::*;

use crate::harness::FlightOutcome;

const COLOURS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];

/// Picks one angle out of a sample.
type AngleOf = fn(&crate::harness::Sample) -> f32;

use canvas::draw_error;

/// Room kept free above the curves for the legend, which sits in the top right corner, as a
/// fraction of the curves' largest value: no curve passes under it.
const LEGEND_HEADROOM: f32 = 0.5;

/// Height above ground over time for each `(label, flight)`, with the first flight's
/// reference dashed (drawn down to the ground: after the plan the controller's setpoint sits
/// below the ground, which the CSV keeps); written to `path`.
pub fn height(path: &Path, title: &str, flights: &[(&str, &FlightOutcome)]) -> Result<PathBuf> {
    let Some(&(_, first)) = flights.first() else {
        bail!("no flight to draw");
    };
    let t_end = flights
        .iter()
        .filter_map(|(_, f)| f.samples.last().map(|s| s.t))
        .fold(1.0f32, f32::max);
    let top = flights
        .iter()
        .flat_map(|(_, f)| f.samples.iter().map(|s| -s.position.z.min(s.reference.z)))
        .fold(0.6f32, f32::max);
    let root = BitMapBackend::new(path, (900, 500)).into_drawing_area();
    root.fill(&WHITE).map_err(draw_error)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(0f32..t_end, -0.05f32..top * (1.1 + LEGEND_HEADROOM))
        .map_err(draw_error)?;
    chart
        .configure_mesh()
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .x_desc("time (s)")
        .y_desc("height (m)")
        .draw()
        .map_err(draw_error)?;
    chart
        .draw_series(DashedLineSeries::new(
            first
                .samples
                .iter()
                .map(|s| (s.t, (-s.reference.z).max(0.0))),
            6,
            4,
            BLACK.stroke_width(1),
        ))
        .map_err(draw_error)?
        .label("reference (plan)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    for (i, (label, flight)) in flights.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        chart
            .draw_series(LineSeries::new(
                flight.samples.iter().map(|s| (s.t, -s.position.z)),
                colour.stroke_width(2),
            ))
            .map_err(draw_error)?
            .label(*label)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(draw_error)?;
    root.present().map_err(draw_error)?;
    Ok(path.to_path_buf())
}

/// Roll and pitch over time of one flight; written to `path`.
pub fn attitude(path: &Path, title: &str, flight: &FlightOutcome) -> Result<PathBuf> {
    let t_end = flight.samples.last().map_or(1.0, |s| s.t.max(1.0));
    let peak = flight
        .samples
        .iter()
        .map(|s| s.attitude_deg.x.abs().max(s.attitude_deg.y.abs()))
        .fold(5.0f32, f32::max);
    let root = BitMapBackend::new(path, (900, 500)).into_drawing_area();
    root.fill(&WHITE).map_err(draw_error)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(
            0f32..t_end,
            -peak * 1.1..peak * (1.1 + 2.0 * LEGEND_HEADROOM),
        )
        .map_err(draw_error)?;
    chart
        .configure_mesh()
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .x_desc("time (s)")
        .y_desc("angle (deg)")
        .draw()
        .map_err(draw_error)?;
    let series: [(&str, AngleOf); 2] = [
        ("roll", |s| s.attitude_deg.x),
        ("pitch", |s| s.attitude_deg.y),
    ];
    for (i, (label, value)) in series.into_iter().enumerate() {
        let colour = COLOURS[i];
        chart
            .draw_series(LineSeries::new(
                flight.samples.iter().map(|s| (s.t, value(s))),
                colour.stroke_width(2),
            ))
            .map_err(draw_error)?
            .label(label)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(draw_error)?;
    root.present().map_err(draw_error)?;
    Ok(path.to_path_buf())
}
