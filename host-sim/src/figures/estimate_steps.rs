//! The estimation per lift of `estimate --output` (the paper's Fig. 6, flattened to 2-D views):
//! for one trial, at the start and after each lift, the posterior's marginal over (COM x, COM y)
//! as a heat map and over mass as bars, with the truth and the estimate marked, and each
//! lifting group's mutual information for the next lift as bars, the chosen group highlighted.

use anyhow::Result;
use plotters::prelude::*;

use super::canvas::{
    self, Area, Figure, LEGEND_WIDTH, Swatch, centred, colour, draw_error, legend, titled,
    with_legend_column,
};
use crate::trial_trace::{EstimationStep, TrialTrace};
use shared::estimation::{Measurement, Status};

/// The posterior's colour (its darkest cell).
const POSTERIOR: RGBColor = RGBColor(31, 80, 160);
/// The truth's colour.
const TRUTH: RGBColor = RGBColor(214, 39, 40);
/// The chosen group's colour.
const CHOSEN: RGBColor = RGBColor(255, 127, 14);

/// One step's page: heat map, mass bars, information bars, and the legend.
pub struct StepFigure<'a> {
    /// The scenario's name.
    pub name: &'a str,
    /// Which trial (from 1, as people count).
    pub trial: usize,
    /// The whole trial.
    pub trace: &'a TrialTrace,
    /// Which step (0: the start).
    pub index: usize,
}

impl StepFigure<'_> {
    fn step(&self) -> &EstimationStep {
        &self.trace.steps[self.index]
    }

    fn title(&self) -> String {
        let step = self.step();
        let what = match (step.lift, step.model) {
            (None, _) => "before the first lift (uniform prior on the footprint)".to_string(),
            (Some((g, Measurement::Lifted { thrust })), model) => format!(
                "after lift {}: pair {g} read {thrust:.2} N per robot{}",
                self.index,
                model.map_or(String::new(), |m| format!(
                    " (model for the truth {m:.2} N)"
                ))
            ),
            (Some((g, Measurement::CouldNotLift)), model) => format!(
                "after lift {}: pair {g} could not lift{}",
                self.index,
                model.map_or(String::new(), |m| format!(
                    " (model for the truth {m:.2} N)"
                ))
            ),
        };
        format!("{}, trial {}: {what}", self.name, self.trial)
    }
}

impl Figure for StepFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (1500 + LEGEND_WIDTH, 520)
    }

    fn draw<DB: DrawingBackend>(&self, root: &Area<DB>) -> Result<()> {
        let body = titled(root, &self.title())?;
        let (plots, key) = with_legend_column(&body);
        let width = plots.dim_in_pixel().0;
        let (com, rest) = plots.split_horizontally(width * 2 / 5);
        let (mass, info) = rest.split_horizontally(width * 3 / 10);
        let peak = self.com_panel(&com)?;
        self.mass_panel(&mass)?;
        self.information_panel(&info)?;
        let entries = [
            ("truth".to_string(), Swatch::Triangle(TRUTH)),
            ("estimate (after a lift)".to_string(), Swatch::Cross(BLACK)),
            ("posterior".to_string(), Swatch::Bar(POSTERIOR)),
            ("pair lifted next".to_string(), Swatch::Bar(CHOSEN)),
            ("other pairs".to_string(), Swatch::Bar(colour(0))),
            ("pair out of reach".to_string(), Swatch::Cross(canvas::GREY)),
        ];
        legend(&key, 40, &entries)?;
        colour_bar(&key, 60 + 22 * entries.len() as i32, peak)?;
        let e = &self.step().estimate;
        let status = match e.status {
            Status::Measuring => "measuring".to_string(),
            Status::Converged => "converged".to_string(),
            Status::NotConverged => "stopped, not converged".to_string(),
            Status::Settled => "settled: out of lifts, spread within bounds".to_string(),
            Status::OutsideGrid(_) => "outside the grid".to_string(),
        };
        let font = ("sans-serif", 14).into_font();
        let y = 60 + 22 * entries.len() as i32 + 200;
        for (k, line) in [
            format!("estimate: {status}"),
            format!("mass near the MAP {:.2}", e.confidence),
            format!(
                "truth ({:.3}, {:.3}) m, {:.2} kg",
                self.trace.truth[0], self.trace.truth[1], self.trace.truth[2]
            ),
        ]
        .into_iter()
        .enumerate()
        {
            key.draw(&Text::new(line, (8, y + 18 * k as i32), font.clone()))
                .map_err(draw_error)?;
        }
        Ok(())
    }
}

impl StepFigure<'_> {
    /// The COM marginal as a heat map over the grid's cells; returns its largest cell.
    fn com_panel<DB: DrawingBackend>(&self, area: &Area<DB>) -> Result<f32> {
        let grid = &self.trace.grid;
        let [nx, ny, _] = grid.shape();
        let res = grid.resolution();
        let step = self.step();
        let truth = self.trace.truth;
        let est = step.estimate.theta;
        let x_edges = (
            grid.axis_value(0, 0) - res[0] / 2.0,
            grid.axis_value(0, nx - 1) + res[0] / 2.0,
        );
        let y_edges = (
            grid.axis_value(1, 0) - res[1] / 2.0,
            grid.axis_value(1, ny - 1) + res[1] / 2.0,
        );
        let x = canvas::span([x_edges.0, x_edges.1, truth[0], est[0]], x_edges);
        let y = canvas::span([y_edges.0, y_edges.1, truth[1], est[1]], y_edges);
        let mut chart = ChartBuilder::on(area)
            .caption("COM marginal", ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x.0..x.1, y.0..y.1)
            .map_err(draw_error)?;
        chart
            .configure_mesh()
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .disable_mesh()
            .x_desc("COM x (m)")
            .y_desc("COM y (m)")
            .draw()
            .map_err(draw_error)?;
        let peak = step.com_marginal.iter().copied().fold(0.0f32, f32::max);
        chart
            .draw_series((0..nx * ny).map(|c| {
                let (ix, iy) = (c / ny, c % ny);
                let (cx, cy) = (grid.axis_value(0, ix), grid.axis_value(1, iy));
                let p = step.com_marginal[c];
                Rectangle::new(
                    [
                        (cx - res[0] / 2.0, cy - res[1] / 2.0),
                        (cx + res[0] / 2.0, cy + res[1] / 2.0),
                    ],
                    shade(p / peak.max(f32::MIN_POSITIVE)).filled(),
                )
            }))
            .map_err(draw_error)?;
        // Cell borders, thin, so that the grid reads.
        chart
            .draw_series((0..nx * ny).map(|c| {
                let (cx, cy) = (grid.axis_value(0, c / ny), grid.axis_value(1, c % ny));
                Rectangle::new(
                    [
                        (cx - res[0] / 2.0, cy - res[1] / 2.0),
                        (cx + res[0] / 2.0, cy + res[1] / 2.0),
                    ],
                    RGBColor(220, 220, 220).stroke_width(1),
                )
            }))
            .map_err(draw_error)?;
        chart
            .draw_series([TriangleMarker::new((truth[0], truth[1]), 9, TRUTH.filled())])
            .map_err(draw_error)?;
        if self.index > 0 {
            chart
                .draw_series([Cross::new((est[0], est[1]), 8, BLACK.stroke_width(3))])
                .map_err(draw_error)?;
        }
        Ok(peak)
    }

    /// The mass marginal as bars, with the truth and the estimate as vertical lines.
    fn mass_panel<DB: DrawingBackend>(&self, area: &Area<DB>) -> Result<()> {
        let grid = &self.trace.grid;
        let nm = grid.shape()[2];
        let res = grid.resolution()[2];
        let step = self.step();
        let truth = self.trace.truth[2];
        let est = step.estimate.theta[2];
        let edges = (grid.mass(0) - res / 2.0, grid.mass(nm - 1) + res / 2.0);
        let x = canvas::span([edges.0, edges.1, truth, est], edges);
        let top = step.mass_marginal.iter().copied().fold(0.0f32, f32::max);
        let top = (top * 1.1).max(0.05);
        let mut chart = ChartBuilder::on(area)
            .caption("mass marginal", ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(55)
            .build_cartesian_2d(x.0..x.1, 0f32..top)
            .map_err(draw_error)?;
        chart
            .configure_mesh()
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .disable_x_mesh()
            .x_desc("mass (kg)")
            .y_desc("probability")
            .draw()
            .map_err(draw_error)?;
        chart
            .draw_series(step.mass_marginal.iter().enumerate().map(|(im, &p)| {
                let m = grid.mass(im);
                Rectangle::new(
                    [(m - 0.4 * res, 0.0), (m + 0.4 * res, p)],
                    POSTERIOR.filled(),
                )
            }))
            .map_err(draw_error)?;
        chart
            .draw_series([PathElement::new(
                vec![(truth, 0.0), (truth, top)],
                TRUTH.stroke_width(3),
            )])
            .map_err(draw_error)?;
        chart
            .draw_series([TriangleMarker::new((truth, top * 0.96), 9, TRUTH.filled())])
            .map_err(draw_error)?;
        if self.index > 0 {
            chart
                .draw_series([Cross::new((est, top * 0.9), 8, BLACK.stroke_width(3))])
                .map_err(draw_error)?;
        }
        Ok(())
    }

    /// Each group's mutual information for the next lift; the chosen one highlighted.
    fn information_panel<DB: DrawingBackend>(&self, area: &Area<DB>) -> Result<()> {
        let step = self.step();
        let groups = self.trace.steps[0].information.len().max(1);
        let top = step
            .information
            .iter()
            .flatten()
            .copied()
            .fold(0.0f32, f32::max);
        let top = (top * 1.15).max(0.1);
        let mut chart = ChartBuilder::on(area)
            .caption("information of the next lift", ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(55)
            .build_cartesian_2d(-0.6f32..(groups as f32 - 0.4), 0f32..top)
            .map_err(draw_error)?;
        chart
            .configure_mesh()
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .disable_x_mesh()
            .x_labels(groups.min(16))
            .x_label_formatter(&|v| {
                let i = v.round();
                if (v - i).abs() < 1e-3 && i >= 0.0 {
                    format!("{}", i as usize)
                } else {
                    String::new()
                }
            })
            .x_desc("pair (its first candidate)")
            .y_desc("mutual information (nats)")
            .draw()
            .map_err(draw_error)?;
        if step.information.is_empty() {
            let (w, h) = area.dim_in_pixel();
            area.draw(&Text::new(
                "no next lift: the estimation is over",
                (w as i32 / 2 + 20, h as i32 / 2),
                centred(16),
            ))
            .map_err(draw_error)?;
            return Ok(());
        }
        chart
            .draw_series(step.information.iter().enumerate().filter_map(|(g, i)| {
                let value = (*i)?;
                let c = if Some(g) == step.next {
                    CHOSEN
                } else {
                    colour(0)
                };
                let x = g as f32;
                Some(Rectangle::new(
                    [(x - 0.35, 0.0), (x + 0.35, value)],
                    c.filled(),
                ))
            }))
            .map_err(draw_error)?;
        // Groups the robots cannot stand at: a grey cross on the axis.
        chart
            .draw_series(
                step.information
                    .iter()
                    .enumerate()
                    .filter(|(_, i)| i.is_none())
                    .map(|(g, _)| Cross::new((g as f32, top * 0.03), 5, canvas::GREY)),
            )
            .map_err(draw_error)?;
        Ok(())
    }
}

/// White (nothing) to the posterior's colour (the largest cell).
fn shade(fraction: f32) -> RGBColor {
    let f = fraction.clamp(0.0, 1.0);
    let mix = |c: u8| (255.0 - f * (255.0 - f32::from(c))).round() as u8;
    RGBColor(mix(POSTERIOR.0), mix(POSTERIOR.1), mix(POSTERIOR.2))
}

/// The heat map's scale: a vertical bar from 0 to `peak`, at `top` pixels down.
fn colour_bar<DB: DrawingBackend>(area: &Area<DB>, top: i32, peak: f32) -> Result<()> {
    let font = ("sans-serif", 14).into_font();
    area.draw(&Text::new("COM cell probability", (8, top), font.clone()))
        .map_err(draw_error)?;
    let (x0, x1, y0, height) = (12, 32, top + 24, 140);
    const STEPS: i32 = 40;
    for k in 0..STEPS {
        let f = 1.0 - k as f32 / (STEPS - 1) as f32;
        let y = y0 + height * k / STEPS;
        area.draw(&Rectangle::new(
            [(x0, y), (x1, y + height / STEPS + 1)],
            shade(f).filled(),
        ))
        .map_err(draw_error)?;
    }
    area.draw(&Rectangle::new([(x0, y0), (x1, y0 + height)], BLACK))
        .map_err(draw_error)?;
    area.draw(&Text::new(
        format!("{peak:.3}"),
        (x1 + 8, y0 - 6),
        font.clone(),
    ))
    .map_err(draw_error)?;
    area.draw(&Text::new("0", (x1 + 8, y0 + height - 8), font))
        .map_err(draw_error)?;
    Ok(())
}
