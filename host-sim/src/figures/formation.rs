//! The formation figure of `formation --output` (the layout of the paper's Fig. 5 with its
//! formation decision added): the payload's footprint, the rail, the candidate attachment points
//! (numbered as the lifting pairs are), the even formation and the optimised one with each
//! robot's spin sign, the COM the formation was solved for and the truth, on equal axes.

use anyhow::Result;
use plotters::prelude::*;
use shared::formation::FormationFigures;
use shared::geometry::{Vec2, signed_area};
use shared::scenario::Scenario;

use super::canvas::{
    self, Area, Figure, LEGEND_WIDTH, Swatch, centred, draw_error, legend, titled,
    with_legend_column,
};

/// The footprint's fill.
const FOOTPRINT: RGBColor = RGBColor(198, 219, 239);
/// The even formation's colour.
const EVEN: RGBColor = RGBColor(255, 127, 14);
/// The optimised formation's colour.
const OPTIMISED: RGBColor = RGBColor(31, 119, 180);
/// The truth's colour.
const TRUTH: RGBColor = RGBColor(214, 39, 40);

/// Width of the plot area, pixels.
const PLOT_WIDTH: u32 = 900;
/// Smallest and largest height of the plot area, pixels.
const PLOT_HEIGHT: (u32, u32) = (260, 900);
/// Margin around the chart and its label areas, pixels.
const MARGIN: u32 = 15;
const X_LABELS: u32 = 45;
const Y_LABELS: u32 = 65;
const TITLE: u32 = 40;

/// The figure.
pub struct FormationFigure<'a> {
    /// Title.
    pub title: String,
    /// The scenario (footprint, rail, candidates, spins).
    pub scenario: &'a Scenario,
    /// The even formation, arc lengths, m, and its figures (det(B B^T), balance).
    pub even: (&'a [f32], FormationFigures),
    /// The optimised formation, arc lengths, m, and its figures.
    pub optimised: (&'a [f32], FormationFigures),
    /// The COM the formation was solved for, and whether it was given (`--com`) or is the
    /// scenario's truth.
    pub com: (Vec2, bool),
    /// The scenario's truth, if it has one.
    pub truth: Option<Vec2>,
}

impl FormationFigure<'_> {
    /// The plot's ranges, equal metres per pixel on both axes, its height in pixels and its
    /// pixels per metre.
    fn layout(&self) -> ((f32, f32), (f32, f32), u32, f32) {
        let p = &self.scenario.payload;
        let points = || p.footprint.iter().chain(p.rail.vertices());
        let x = canvas::span(points().map(|v| v.x), (-1.0, 1.0));
        let y = canvas::span(points().map(|v| v.y), (-1.0, 1.0));
        // Room for the candidates' numbers outside the rail.
        let pad = 0.12 * (x.1 - x.0).max(y.1 - y.0);
        let (dx, dy) = (x.1 - x.0 + 2.0 * pad, y.1 - y.0 + 2.0 * pad);
        let scale = PLOT_WIDTH as f32 / dx;
        let height = ((dy * scale).round() as u32).clamp(PLOT_HEIGHT.0, PLOT_HEIGHT.1);
        // The same metres per pixel on both axes: the ranges follow the plot's size.
        let scale = scale.min(height as f32 / dy);
        let (half_w, half_h) = (PLOT_WIDTH as f32 / scale / 2.0, height as f32 / scale / 2.0);
        let (cx, cy) = ((x.0 + x.1) / 2.0, (y.0 + y.1) / 2.0);
        (
            (cx - half_w, cx + half_w),
            (cy - half_h, cy + half_h),
            height,
            scale,
        )
    }
}

impl Figure for FormationFigure<'_> {
    fn size(&self) -> (u32, u32) {
        let (_, _, height, _) = self.layout();
        (
            PLOT_WIDTH + Y_LABELS + 2 * MARGIN + LEGEND_WIDTH,
            height + X_LABELS + 2 * MARGIN + TITLE,
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &Area<DB>) -> Result<()> {
        let (x, y, _, scale) = self.layout();
        let body = titled(root, &self.title)?;
        let (plot, key) = with_legend_column(&body);
        let mut chart = ChartBuilder::on(&plot)
            .margin(MARGIN)
            .x_label_area_size(X_LABELS)
            .y_label_area_size(Y_LABELS)
            .build_cartesian_2d(x.0..x.1, y.0..y.1)
            .map_err(draw_error)?;
        chart
            .configure_mesh()
            .light_line_style(WHITE)
            .x_label_formatter(&canvas::tick)
            .y_label_formatter(&canvas::tick)
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .x_desc("x, payload frame (m)")
            .y_desc("y (m)")
            .draw()
            .map_err(draw_error)?;
        let s = self.scenario;
        let p = &s.payload;
        let xy = |v: Vec2| (v.x, v.y);
        chart
            .draw_series([Polygon::new(
                p.footprint.iter().copied().map(xy).collect::<Vec<_>>(),
                FOOTPRINT.filled(),
            )])
            .map_err(draw_error)?;
        let mut rail: Vec<_> = p.rail.vertices().iter().copied().map(xy).collect();
        rail.extend(rail.first().copied());
        chart
            .draw_series([PathElement::new(rail, canvas::GREY.stroke_width(2))])
            .map_err(draw_error)?;
        // Candidates, numbered just outside the rail (the segment's outward normal).
        let outward = if signed_area(p.rail.vertices()) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        for (i, &arc) in p.candidates.iter().enumerate() {
            let q = p.rail.point_at(arc);
            let d = p.rail.segment_direction(p.rail.segment_at(arc));
            let normal = Vec2::new(d.y, -d.x) * outward;
            let label_at = q + normal * (22.0 / scale);
            chart
                .draw_series([Circle::new(xy(q), 3, BLACK.filled())])
                .map_err(draw_error)?;
            chart
                .draw_series([Text::new(format!("{i}"), xy(label_at), centred(14))])
                .map_err(draw_error)?;
        }
        let (even, optimised) = (self.even.0, self.optimised.0);
        // The even formation under the optimised one, a little larger: where a robot stays
        // put, its orange ring shows round the blue dot.
        for (positions, filled) in [(even, false), (optimised, true)] {
            for (j, &arc) in positions.iter().enumerate() {
                let q = xy(p.rail.point_at(arc));
                let sign = if s.robots.spin.get(j).copied().unwrap_or(1) >= 0 {
                    "+"
                } else {
                    "−"
                };
                let (fill, ring, text, radius) = if filled {
                    (OPTIMISED, OPTIMISED, WHITE, 10)
                } else {
                    (WHITE, EVEN, BLACK, 12)
                };
                chart
                    .draw_series([EmptyElement::at(q)
                        + Circle::new((0, 0), radius, fill.filled())
                        + Circle::new((0, 0), radius, ring.stroke_width(3))
                        + Text::new(sign, (0, 0), centred(17).color(&text))])
                    .map_err(draw_error)?;
            }
        }
        let (com, given) = self.com;
        // Without --com the formation was solved for the truth: one mark says both.
        if let Some(t) = self.truth.filter(|_| given) {
            chart
                .draw_series([TriangleMarker::new(xy(t), 9, TRUTH.filled())])
                .map_err(draw_error)?;
        }
        chart
            .draw_series([Cross::new(xy(com), 8, BLACK.stroke_width(3))])
            .map_err(draw_error)?;
        let mut entries = vec![
            ("footprint".to_string(), Swatch::Bar(FOOTPRINT)),
            ("rail".to_string(), Swatch::Line(canvas::GREY)),
            ("candidate points".to_string(), Swatch::Dot(BLACK)),
            (
                format!("even, det {:.2e}", self.even.1.det),
                Swatch::Ring(EVEN),
            ),
            (
                format!("optimised, det {:.2e}", self.optimised.1.det),
                Swatch::Dot(OPTIMISED),
            ),
            ("robot spin +1".to_string(), Swatch::Sign("+")),
            ("robot spin −1".to_string(), Swatch::Sign("−")),
            (
                if given {
                    "COM estimate (--com)".to_string()
                } else {
                    "COM used (the truth)".to_string()
                },
                Swatch::Cross(BLACK),
            ),
        ];
        if given && self.truth.is_some() {
            entries.push(("truth".to_string(), Swatch::Triangle(TRUTH)));
        }
        legend(&key, 30, &entries)?;
        let font = ("sans-serif", 14).into_font();
        let notes = [
            "det: det(B B^T), m^6".to_string(),
            "offsets from the COM, summed:".to_string(),
            format!(
                "  even ({}, {}) m",
                millimetres(self.even.1.balance[0]),
                millimetres(self.even.1.balance[1])
            ),
            format!(
                "  optimised ({}, {}) m",
                millimetres(self.optimised.1.balance[0]),
                millimetres(self.optimised.1.balance[1])
            ),
            "candidates numbered as the".to_string(),
            "lifting pairs that start there".to_string(),
        ];
        let top = 40 + 22 * entries.len() as i32;
        for (k, line) in notes.into_iter().enumerate() {
            key.draw(&Text::new(line, (8, top + 18 * k as i32), font.clone()))
                .map_err(draw_error)?;
        }
        Ok(())
    }
}

/// `v` metres to the millimetre, never a negative zero.
fn millimetres(v: f32) -> String {
    let rounded = (v * 1000.0).round() / 1000.0 + 0.0;
    format!("{rounded:.3}")
}
