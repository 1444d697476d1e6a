//! The Monte Carlo summary of `estimate --output` (the paper's Fig. 7): per axis (COM x, COM y,
//! mass) the mean error over the trials as a bar and its standard deviation as an error bar,
//! both in units of the grid's resolution, for one scenario or several side by side.

use anyhow::Result;
use plotters::prelude::*;

use super::canvas::{
    self, Area, Figure, LEGEND_WIDTH, Swatch, colour, draw_error, legend, titled,
    with_legend_column,
};
use crate::monte_carlo::Summary;

/// The axes' names, as the x axis shows them.
const AXES: [&str; 3] = ["COM x", "COM y", "mass"];

/// The figure: one group of bars per axis, one bar per scenario.
pub struct ErrorSummary<'a> {
    /// Title.
    pub title: String,
    /// Each scenario's name and summary.
    pub scenarios: &'a [(String, Summary)],
}

impl Figure for ErrorSummary<'_> {
    fn size(&self) -> (u32, u32) {
        (760 + LEGEND_WIDTH, 520)
    }

    fn draw<DB: DrawingBackend>(&self, root: &Area<DB>) -> Result<()> {
        let body = titled(root, &self.title)?;
        let (plot, key) = with_legend_column(&body);
        let n = self.scenarios.len().max(1);
        let (lo, hi) = canvas::span(
            self.scenarios.iter().flat_map(|(_, s)| {
                (0..3).flat_map(move |a| {
                    let (m, d) = (
                        s.mean_error_over_resolution[a] as f32,
                        s.std_error_over_resolution[a] as f32,
                    );
                    [m - d, m + d]
                })
            }),
            (-1.0, 1.0),
        );
        // One resolution either way always shows, for scale.
        let (lo, hi) = (lo.min(-1.2), hi.max(1.2));
        let pad = 0.08 * (hi - lo);
        let mut chart = ChartBuilder::on(&plot)
            .margin(14)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(-0.5f32..2.5f32, (lo - pad)..(hi + pad))
            .map_err(draw_error)?;
        chart
            .configure_mesh()
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .disable_x_mesh()
            .x_labels(7)
            .x_label_formatter(&|v| {
                let i = v.round();
                if (v - i).abs() < 1e-3 && (0.0..=2.0).contains(&i) {
                    AXES[i as usize].to_string()
                } else {
                    String::new()
                }
            })
            .x_label_style(("sans-serif", 17))
            .y_desc("error / resolution")
            .draw()
            .map_err(draw_error)?;
        for level in [-1.0f32, 1.0] {
            chart
                .draw_series(DashedLineSeries::new(
                    [(-0.5, level), (2.5, level)],
                    6,
                    4,
                    canvas::GREY.stroke_width(1),
                ))
                .map_err(draw_error)?;
        }
        chart
            .draw_series(LineSeries::new([(-0.5, 0.0), (2.5, 0.0)], BLACK))
            .map_err(draw_error)?;
        let width = 0.7 / n as f32;
        for (i, (_, s)) in self.scenarios.iter().enumerate() {
            let c = colour(i);
            for a in 0..3 {
                let x = a as f32 - 0.35 + width * (i as f32 + 0.5);
                let mean = s.mean_error_over_resolution[a] as f32;
                let std = s.std_error_over_resolution[a] as f32;
                chart
                    .draw_series([Rectangle::new(
                        [(x - 0.4 * width, 0.0), (x + 0.4 * width, mean)],
                        c.mix(0.85).filled(),
                    )])
                    .map_err(draw_error)?;
                // The error bar: one standard deviation either way, with caps.
                let (low, high) = (mean - std, mean + std);
                let cap = 0.15 * width;
                chart
                    .draw_series([
                        PathElement::new(vec![(x, low), (x, high)], BLACK.stroke_width(2)),
                        PathElement::new(
                            vec![(x - cap, low), (x + cap, low)],
                            BLACK.stroke_width(2),
                        ),
                        PathElement::new(
                            vec![(x - cap, high), (x + cap, high)],
                            BLACK.stroke_width(2),
                        ),
                    ])
                    .map_err(draw_error)?;
            }
        }
        let mut entries: Vec<(String, Swatch)> = self
            .scenarios
            .iter()
            .enumerate()
            .map(|(i, (name, _))| (format!("{name}: mean"), Swatch::Bar(colour(i))))
            .collect();
        entries.push(("± one std. deviation".to_string(), Swatch::Line(BLACK)));
        entries.push(("± one resolution".to_string(), Swatch::Dashed(canvas::GREY)));
        legend(&key, 40, &entries)?;
        // The numbers themselves, under the legend.
        let font = ("sans-serif", 14).into_font();
        let mut y = 60 + 22 * entries.len() as i32;
        for (name, s) in self.scenarios {
            key.draw(&Text::new(name.clone(), (8, y), font.clone()))
                .map_err(draw_error)?;
            y += 18;
            for (a, axis) in AXES.iter().enumerate() {
                key.draw(&Text::new(
                    format!(
                        "{axis}: {:+.2} ± {:.2}",
                        s.mean_error_over_resolution[a], s.std_error_over_resolution[a]
                    ),
                    (16, y),
                    font.clone(),
                ))
                .map_err(draw_error)?;
                y += 18;
            }
            key.draw(&Text::new(
                format!("within 1 res.: {:.0} %", 100.0 * s.within_one_resolution),
                (16, y),
                font.clone(),
            ))
            .map_err(draw_error)?;
            y += 26;
        }
        Ok(())
    }
}
