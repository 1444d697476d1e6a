//! The one-page summary of a mission (`mission --output`, and `plot` from a flight log): the
//! phases on a time line (one row per phase, a bar for each time it was entered), each lift's
//! reading against the model's lift-off thrust for the truth (where it is known), and from
//! take-off on the height, roll and pitch, and each rotor's thrust, with the flight's phases
//! marked. Where its text goes, so that none overlaps at up to 16 robots and any lift count, is
//! [`super::summary_layout`]'s. Beside [`crate::mission_figures`]' flight figure; the paper has
//! no such page (its Figs. 6 and 8 show parts of it). What it draws is [`MissionSummary`]'s
//! data, filled from a simulated mission ([`crate::mission_figures`]) or from a log
//! ([`crate::log_summary`]).

use anyhow::Result;
use plotters::coord::ranged1d::SegmentValue;
use plotters::prelude::*;

use plotters::style::FontTransform;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::canvas::{
    self, Area, Figure, Swatch, colour, draw_error, legend, titled, with_legend_column,
};
use super::summary_layout::{
    self as layout, LABEL_FONT, MARGIN, VALUE_FONT, ValueText, X_LABELS, Y_LABELS,
};

/// A panel's caption font size, pixels.
const CAPTION_FONT: u32 = 18;

/// The summary page's data.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MissionSummary {
    /// The page's title.
    pub title: String,
    /// When the run ends, s (the time line's end).
    pub end_s: f32,
    /// Each phase as it was entered, in order.
    pub phases: Vec<Span>,
    /// Each lift, in order.
    pub lifts: Vec<LiftBar>,
    /// The robots' maximum thrust, N (a reading at it could not lift), if known.
    pub max_thrust: Option<f32>,
    /// The flight from take-off, about 100 Hz (the thrusts are smoothed over a quarter
    /// second, 12 samples each side).
    pub series: Vec<SummarySample>,
    /// The thrusts are in newtons; otherwise percent of the rotors' maximum.
    pub thrust_in_newtons: bool,
    /// What the flight panels say when there is no flight.
    pub no_flight: String,
}

/// A phase as drawn: name, start and end, s.
#[derive(Clone, Debug, PartialEq)]
pub struct Span {
    /// The phase's short name (`takeoff`).
    pub name: String,
    /// When it was entered, s.
    pub start: f32,
    /// When it was left, s.
    pub end: f32,
}

/// One lift: its pair, its reading and the model's lift-off thrust for the truth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiftBar {
    /// The lifting pair's group.
    pub pair: usize,
    /// The reading, N per robot (`None`: could not lift).
    pub reading: Option<f32>,
    /// The model's lift-off thrust for the truth, N (`None` where the truth is not known).
    pub model: Option<f32>,
}

/// One sample of the flight.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SummarySample {
    /// Time, s.
    pub t: f32,
    /// Height above the start, m.
    pub height: f32,
    /// Roll and pitch, degrees.
    pub roll_pitch_deg: [f32; 2],
    /// Each rotor's thrust (N, or percent of its maximum).
    pub thrust: Vec<f32>,
}

impl Span {
    /// Phases as a run lists them, `(name, duration)` in order, the last ending at `end`.
    pub fn from_durations(phases: &[(String, f32)], end: f32) -> Vec<Span> {
        let total: f32 = phases.iter().map(|(_, d)| d).sum();
        let mut t = (end - total).max(0.0);
        phases
            .iter()
            .map(|(name, d)| {
                let span = Span {
                    name: name.clone(),
                    start: t,
                    end: t + d,
                };
                t += d;
                span
            })
            .collect()
    }
}

impl Figure for MissionSummary {
    fn size(&self) -> (u32, u32) {
        layout::page_size(self.robots())
    }

    fn draw<DB: DrawingBackend>(&self, root: &Area<DB>) -> Result<()> {
        let body = titled(root, &self.title)?;
        let spans = &self.phases;
        let heights = layout::row_heights(self.robots());
        let mut breaks = [0u32; 4];
        let mut y = 0;
        for (b, h) in breaks.iter_mut().zip(heights) {
            y += h;
            *b = y;
        }
        let rows = body.split_by_breakpoints([] as [u32; 0], breaks);
        self.timeline(&rows[0], spans)?;
        self.lifts(&rows[1])?;
        let flight: Vec<&Span> = spans.iter().skip_while(|s| s.name != "takeoff").collect();
        let series = &self.series;
        let Some(first) = series.first() else {
            for row in &rows[2..] {
                note(row, &self.no_flight)?;
            }
            return Ok(());
        };
        let t = (first.t, series.last().map_or(first.t + 1.0, |s| s.t));
        let t = (t.0, t.1.max(t.0 + 1.0));
        let height = vec![(
            "height".to_string(),
            colour(0),
            series.iter().map(|s| (s.t, s.height)).collect(),
        )];
        curves(
            &rows[2],
            "height above the start",
            "height (m)",
            t,
            &height,
            &flight,
        )?;
        let attitude = vec![
            (
                "roll".to_string(),
                colour(0),
                series.iter().map(|s| (s.t, s.roll_pitch_deg[0])).collect(),
            ),
            (
                "pitch".to_string(),
                colour(3),
                series.iter().map(|s| (s.t, s.roll_pitch_deg[1])).collect(),
            ),
        ];
        curves(
            &rows[3],
            "payload attitude",
            "angle (deg)",
            t,
            &attitude,
            &flight,
        )?;
        let thrusts = self.thrust_curves();
        let (title, unit) = if self.thrust_in_newtons {
            ("rotor thrusts (quarter-second means)", "thrust (N)")
        } else {
            (
                "rotor commands (quarter-second means)",
                "command (% of maximum)",
            )
        };
        curves(&rows[4], title, unit, t, &thrusts, &flight)
    }
}

/// `text` in the middle of `area` (a panel with nothing to draw).
fn note<DB: DrawingBackend>(area: &Area<DB>, text: &str) -> Result<()> {
    let (w, h) = area.dim_in_pixel();
    area.draw(&Text::new(
        text.to_string(),
        (w as i32 / 2, h as i32 / 2),
        canvas::centred(18),
    ))
    .map_err(draw_error)?;
    Ok(())
}

impl MissionSummary {
    /// The rotors the flight has (none without a flight).
    pub fn robots(&self) -> usize {
        self.series.first().map_or(0, |s| s.thrust.len())
    }

    /// Each rotor's thrust over the flight, a quarter-second mean, as the rotor panel draws
    /// it: one curve per robot, named from 1.
    pub(crate) fn thrust_curves(&self) -> Vec<Curve> {
        (0..self.robots())
            .map(|j| {
                let points: Vec<(f32, f32)> = self
                    .series
                    .iter()
                    .map(|s| (s.t, s.thrust.get(j).copied().unwrap_or(0.0)))
                    .collect();
                // 100 Hz samples: 12 each side is a quarter-second mean (the rate loop's
                // answer to sensor noise hides the level otherwise).
                (format!("robot {}", j + 1), colour(j), smoothed(&points, 12))
            })
            .collect()
    }

    /// One row per phase (in the order first entered), a bar for each time it ran.
    fn timeline<DB: DrawingBackend>(&self, area: &Area<DB>, spans: &[Span]) -> Result<()> {
        let (plot, _) = with_legend_column(area);
        let mut names: Vec<&str> = Vec::new();
        for s in spans {
            if !names.contains(&s.name.as_str()) {
                names.push(&s.name);
            }
        }
        if names.is_empty() {
            return note(area, "no phase recorded");
        }
        let end = self.end_s.max(1.0);
        let rows = names.len() as i32;
        let mut chart = ChartBuilder::on(&plot)
            .caption("phases", ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(130)
            .build_cartesian_2d(0f32..end, (0..rows).into_segmented())
            .map_err(draw_error)?;
        // Top to bottom in the order entered.
        let row_of =
            |name: &str| rows - 1 - names.iter().position(|n| *n == name).unwrap_or(0) as i32;
        let labels: Vec<String> = names.iter().map(|n| n.to_string()).collect();
        chart
            .configure_mesh()
            .disable_y_mesh()
            .y_labels(names.len())
            .y_label_formatter(&|v| match v {
                SegmentValue::CenterOf(i) => labels
                    .get((rows - 1 - i) as usize)
                    .cloned()
                    .unwrap_or_default(),
                _ => String::new(),
            })
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .x_desc("time (s)")
            .draw()
            .map_err(draw_error)?;
        // Short phases still show: at least a 400th of the run.
        let least = end / 400.0;
        chart
            .draw_series(spans.iter().map(|s| {
                let r = row_of(&s.name);
                let k = names.iter().position(|n| *n == s.name).unwrap_or(0);
                Rectangle::new(
                    [
                        (s.start, SegmentValue::Exact(r)),
                        ((s.end).max(s.start + least), SegmentValue::Exact(r + 1)),
                    ],
                    colour(k).filled(),
                )
            }))
            .map_err(draw_error)?;
        Ok(())
    }

    /// Each lift's reading beside the model's lift-off thrust for the truth (where known),
    /// each bar's value written where [`layout::lift_layout`] says.
    fn lifts<DB: DrawingBackend>(&self, area: &Area<DB>) -> Result<()> {
        let lifts = &self.lifts;
        if lifts.is_empty() {
            return note(area, "no lifts");
        }
        let (plot, key) = with_legend_column(area);
        let count = lifts.len();
        // A lift that could not lift is drawn up to the maximum thrust, or without it to the
        // largest value drawn.
        let largest = lifts
            .iter()
            .flat_map(|l| [l.reading, l.model])
            .flatten()
            .chain(self.max_thrust)
            .filter(|v| v.is_finite())
            .fold(0.0f32, f32::max);
        let ceiling = self.max_thrust.unwrap_or(largest.max(1.0));
        let with_model = lifts.iter().any(|l| l.model.is_some());
        let caption = if with_model {
            "lifts: reading against the model for the truth"
        } else {
            "lifts: reading (no truth to compare with)"
        };
        let inner = captioned(&plot, caption)?;
        let placed = layout::lift_layout(
            lifts,
            ceiling,
            largest.max(ceiling) * 1.12,
            layout::plot_size(inner.dim_in_pixel()),
        );
        let names = &placed.names;
        let mut chart = ChartBuilder::on(&inner)
            .x_label_area_size(X_LABELS)
            .y_label_area_size(Y_LABELS)
            .build_cartesian_2d(-0.5f32..(count as f32 - 0.5), 0f32..placed.top)
            .map_err(draw_error)?;
        let name_of = |v: &f32| {
            let i = v.round();
            if (v - i).abs() < 1e-3 && i >= 0.0 {
                names.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        };
        let mut mesh = chart.configure_mesh();
        mesh.disable_x_mesh()
            .x_labels(count * 2 + 1)
            .x_label_formatter(&name_of)
            .label_style(("sans-serif", LABEL_FONT))
            .axis_desc_style(("sans-serif", 16))
            .y_desc("thrust per robot (N)");
        if let Some(desc) = placed.x_desc {
            mesh.x_desc(desc);
        }
        mesh.draw().map_err(draw_error)?;
        if let Some(max) = self.max_thrust {
            chart
                .draw_series(DashedLineSeries::new(
                    [(-0.5, max), (count as f32 - 0.5, max)],
                    6,
                    4,
                    colour(3).stroke_width(2),
                ))
                .map_err(draw_error)?;
        }
        let half = 2.0 * layout::BAR_HALF;
        for (k, lift) in lifts.iter().enumerate() {
            let x = k as f32;
            match lift.reading {
                Some(r) => chart
                    .draw_series([Rectangle::new(
                        [(x - half, 0.0), (x, r)],
                        colour(0).filled(),
                    )])
                    .map_err(draw_error)?,
                None => chart
                    .draw_series([Rectangle::new(
                        [(x - half, 0.0), (x, ceiling)],
                        colour(0).stroke_width(2),
                    )])
                    .map_err(draw_error)?,
            };
            if let Some(model) = lift.model {
                chart
                    .draw_series([Rectangle::new(
                        [(x, 0.0), (x + half, model)],
                        canvas::GREY.filled(),
                    )])
                    .map_err(draw_error)?;
            }
        }
        let level = canvas::centred(VALUE_FONT);
        let upright = TextStyle::from(
            ("sans-serif", VALUE_FONT)
                .into_font()
                .transform(FontTransform::Rotate270),
        )
        .pos(Pos::new(HPos::Left, VPos::Center));
        let style = match placed.value_text {
            ValueText::Upright => &upright,
            _ => &level,
        };
        chart
            .draw_series(placed.values.iter().map(|l| {
                EmptyElement::at(l.at)
                    + Rectangle::new(l.backdrop, WHITE.mix(0.85).filled())
                    + Text::new(l.text.clone(), l.offset, style.clone())
            }))
            .map_err(draw_error)?;
        let mut entries = vec![
            ("reading".to_string(), Swatch::Bar(colour(0))),
            ("could not lift".to_string(), Swatch::Ring(colour(0))),
        ];
        if with_model {
            entries.push(("model, truth".to_string(), Swatch::Bar(canvas::GREY)));
        }
        if self.max_thrust.is_some() {
            entries.push(("max. thrust".to_string(), Swatch::Dashed(colour(3))));
        }
        legend(&key, 50, &entries)?;
        if placed.value_text == ValueText::Left {
            let below = canvas::legend_height(50, entries.len()) + 10;
            for (k, line) in ["too many lifts to", "write their values"]
                .iter()
                .enumerate()
            {
                key.draw(&Text::new(
                    line.to_string(),
                    (8, below + 18 * k as i32),
                    ("sans-serif", LABEL_FONT).into_font(),
                ))
                .map_err(draw_error)?;
            }
        }
        Ok(())
    }
}

/// `area` less the chart margin, with `caption` across its top: where a chart's label areas
/// and plot go.
fn captioned<DB: DrawingBackend>(area: &Area<DB>, caption: &str) -> Result<Area<DB>> {
    let m = MARGIN as i32;
    area.margin(m, m, m, m)
        .titled(caption, ("sans-serif", CAPTION_FONT))
        .map_err(draw_error)
}

/// One curve: its label, colour and (time, value) points.
pub(crate) type Curve = (String, RGBColor, Vec<(f32, f32)>);

/// Curves against time over `t`, the flight's phases as dashed lines named at the top (where
/// [`layout::phase_labels`] says), and the legend in its own column.
fn curves<DB: DrawingBackend>(
    area: &Area<DB>,
    title: &str,
    y_desc: &str,
    t: (f32, f32),
    series: &[Curve],
    phases: &[&Span],
) -> Result<()> {
    let (plot, key) = with_legend_column(area);
    let inner = captioned(&plot, title)?;
    let (width, height) = layout::plot_size(inner.dim_in_pixel());
    // The phase the series starts in (take-off) is named at the left edge.
    let starts: Vec<(String, f32)> = phases
        .iter()
        .filter(|s| s.start >= t.0 - 0.1 && s.start <= t.1)
        .map(|s| (s.name.clone(), s.start.max(t.0)))
        .collect();
    let names = layout::phase_labels(&starts, t, width);
    let (lo, hi) = canvas::span(
        series
            .iter()
            .flat_map(|(_, _, p)| p.iter().map(|&(_, v)| v)),
        (0.0, 1.0),
    );
    // Room at the top for the phases' names: a quarter of the range, or the pixels their
    // rows take.
    let pad = (hi - lo) * 0.08;
    let lo = lo - pad;
    let room = (layout::phase_room(&names) as f32 / height.max(1) as f32).min(0.9);
    let hi = (hi + 3.0 * pad).max((hi - room * lo) / (1.0 - room));
    let mut chart = ChartBuilder::on(&inner)
        .x_label_area_size(X_LABELS)
        .y_label_area_size(Y_LABELS)
        .build_cartesian_2d(t.0..t.1, lo..hi)
        .map_err(draw_error)?;
    chart
        .configure_mesh()
        .label_style(("sans-serif", LABEL_FONT))
        .axis_desc_style(("sans-serif", 16))
        .x_desc("time (s)")
        .y_desc(y_desc)
        .draw()
        .map_err(draw_error)?;
    for name in &names {
        chart
            .draw_series(DashedLineSeries::new(
                [(name.start, lo), (name.start, hi)],
                5,
                4,
                canvas::GREY.stroke_width(1),
            ))
            .map_err(draw_error)?;
        let font = ("sans-serif", LABEL_FONT).into_font();
        let y = layout::PHASE_TOP + name.row as i32 * layout::PHASE_ROW;
        let (dx, anchor) = if name.right_of_line {
            (layout::PHASE_INSET, HPos::Left)
        } else {
            (-layout::PHASE_INSET, HPos::Right)
        };
        let style = TextStyle::from(font).pos(Pos::new(anchor, VPos::Top));
        chart
            .draw_series([
                EmptyElement::at((name.start, hi)) + Text::new(name.text.clone(), (dx, y), style)
            ])
            .map_err(draw_error)?;
    }
    for (_, c, points) in series {
        chart
            .draw_series(LineSeries::new(points.iter().copied(), c.stroke_width(2)))
            .map_err(draw_error)?;
    }
    let entries: Vec<(String, Swatch)> = series
        .iter()
        .map(|(label, c, _)| (label.clone(), Swatch::Line(*c)))
        .chain([("phase begins".to_string(), Swatch::Dashed(canvas::GREY))])
        .collect();
    legend(&key, layout::CURVE_LEGEND_TOP, &entries)
}

/// Mean of each value over a centred window of `half` samples each side.
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
