//! What every figure of `estimate`, `formation` and `mission` shares: one drawing written as
//! PNG and SVG (the same code on plotters' bitmap and SVG backends), the palette, and a legend
//! drawn in a column of its own beside the plot, so that it covers no data.
//!
//! Text is drawn with the system's sans-serif font (plotters' `ttf` feature, through
//! fontconfig). A figure that cannot be drawn (no font) is skipped with a warning; the CSV or
//! JSON beside it carries the data.

use std::path::{Path, PathBuf};

use anyhow::{Result, anyhow};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::report::warn;

/// A drawing area of any backend (bitmap for PNG, SVG).
pub type Area<DB> = DrawingArea<DB, Shift>;

/// A figure that can draw itself on any plotters backend.
pub trait Figure {
    /// Size in pixels (PNG) or user units (SVG).
    fn size(&self) -> (u32, u32);
    /// Draws the whole figure on `root` (already white).
    fn draw<DB: DrawingBackend>(&self, root: &Area<DB>) -> Result<()>;
}

/// Turns a plotters error into one readable line.
pub fn draw_error<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("drawing failed: {e}")
}

/// Writes `figure` to `<dir>/<stem>.png` and `<dir>/<stem>.svg`; returns the files written.
/// A file that cannot be drawn is skipped with a warning on stderr (and not left behind
/// half-drawn).
pub fn write(dir: &Path, stem: &str, figure: &impl Figure) -> Vec<PathBuf> {
    let png = dir.join(format!("{stem}.png"));
    let svg = dir.join(format!("{stem}.svg"));
    let drawn = [
        (png.clone(), render_png(&png, figure)),
        (svg.clone(), render_svg(&svg, figure)),
    ];
    let mut written = Vec::new();
    for (path, result) in drawn {
        match result {
            Ok(()) => written.push(path),
            Err(e) => {
                let _ = std::fs::remove_file(&path);
                warn(&format!("figure {} skipped: {e:#}", path.display()));
            }
        }
    }
    written
}

fn render_png(path: &Path, figure: &impl Figure) -> Result<()> {
    let root = BitMapBackend::new(path, figure.size()).into_drawing_area();
    root.fill(&WHITE).map_err(draw_error)?;
    figure.draw(&root)?;
    root.present().map_err(draw_error)
}

fn render_svg(path: &Path, figure: &impl Figure) -> Result<()> {
    let root = SVGBackend::new(path, figure.size()).into_drawing_area();
    root.fill(&WHITE).map_err(draw_error)?;
    figure.draw(&root)?;
    root.present().map_err(draw_error)
}

/// The palette: colour `i`, repeating after [`PALETTE_SIZE`]. The first ten are matplotlib's
/// "tab10"; the next ten are darker or paler hues unlike them, so that each of 16 robots has
/// its own.
pub fn colour(i: usize) -> RGBColor {
    const C: [RGBColor; PALETTE_SIZE] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
        RGBColor(0, 0, 0),
        RGBColor(0, 0, 128),
        RGBColor(230, 171, 2),
        RGBColor(231, 41, 138),
        RGBColor(0, 110, 110),
        RGBColor(128, 0, 0),
        RGBColor(85, 107, 47),
        RGBColor(174, 199, 232),
        RGBColor(255, 152, 150),
        RGBColor(152, 223, 138),
    ];
    C[i % C.len()]
}

/// How many colours [`colour`] has before it repeats.
pub const PALETTE_SIZE: usize = 20;

/// Grey for things drawn for orientation (outlines, rails).
pub const GREY: RGBColor = RGBColor(150, 150, 150);

/// A figure's title across the top of `root`; returns the rest.
pub fn titled<DB: DrawingBackend>(root: &Area<DB>, title: &str) -> Result<Area<DB>> {
    root.titled(title, ("sans-serif", 24)).map_err(draw_error)
}

/// How a legend entry shows its series.
#[derive(Clone, Copy, Debug)]
pub enum Swatch {
    /// A solid line.
    Line(RGBColor),
    /// A dashed line.
    Dashed(RGBColor),
    /// A filled box (bars, areas).
    Bar(RGBColor),
    /// A filled circle.
    Dot(RGBColor),
    /// An open circle.
    Ring(RGBColor),
    /// A cross.
    Cross(RGBColor),
    /// An upward triangle.
    Triangle(RGBColor),
    /// A sign drawn in a circle (the robots' spin).
    Sign(&'static str),
}

/// Width of the legend column right of a plot, pixels.
pub const LEGEND_WIDTH: u32 = 190;

/// Splits `area` into the plot (left) and a legend column of [`LEGEND_WIDTH`] (right).
pub fn with_legend_column<DB: DrawingBackend>(area: &Area<DB>) -> (Area<DB>, Area<DB>) {
    let width = area.dim_in_pixel().0;
    area.split_horizontally(width.saturating_sub(LEGEND_WIDTH))
}

/// Distance between two legend entries, pixels.
pub const LEGEND_PITCH: i32 = 22;

/// How far down a legend of `entries` starting `top` pixels down reaches, pixels (the last
/// entry's text and swatch, and a few pixels' margin).
pub fn legend_height(top: i32, entries: usize) -> i32 {
    top + LEGEND_PITCH * entries.saturating_sub(1) as i32 + 12
}

/// Draws `entries` (label, swatch) one under the other in `area`, starting `top` pixels down
/// ([`LEGEND_PITCH`] apart; [`legend_height`] says how far they reach).
pub fn legend<DB: DrawingBackend>(
    area: &Area<DB>,
    top: i32,
    entries: &[(String, Swatch)],
) -> Result<()> {
    let font = ("sans-serif", 15).into_font();
    for (k, (label, swatch)) in entries.iter().enumerate() {
        let y = top + LEGEND_PITCH * k as i32;
        let x = 16;
        match *swatch {
            Swatch::Line(c) => area
                .draw(&PathElement::new(vec![(4, y), (28, y)], c.stroke_width(3)))
                .map_err(draw_error)?,
            Swatch::Dashed(c) => {
                for x0 in [4, 13, 22] {
                    area.draw(&PathElement::new(
                        vec![(x0, y), (x0 + 6, y)],
                        c.stroke_width(2),
                    ))
                    .map_err(draw_error)?;
                }
            }
            Swatch::Bar(c) => area
                .draw(&Rectangle::new([(6, y - 7), (26, y + 7)], c.filled()))
                .map_err(draw_error)?,
            Swatch::Dot(c) => area
                .draw(&Circle::new((x, y), 6, c.filled()))
                .map_err(draw_error)?,
            Swatch::Ring(c) => area
                .draw(&Circle::new((x, y), 6, c.stroke_width(2)))
                .map_err(draw_error)?,
            Swatch::Cross(c) => area
                .draw(&Cross::new((x, y), 6, c.stroke_width(3)))
                .map_err(draw_error)?,
            Swatch::Triangle(c) => area
                .draw(&TriangleMarker::new((x, y), 7, c.filled()))
                .map_err(draw_error)?,
            Swatch::Sign(sign) => {
                area.draw(&Circle::new((x, y), 8, BLACK.stroke_width(1)))
                    .map_err(draw_error)?;
                area.draw(&Text::new(sign, (x, y), centred(14)))
                    .map_err(draw_error)?;
            }
        }
        area.draw(&Text::new(label.clone(), (36, y - 8), font.clone()))
            .map_err(draw_error)?;
    }
    Ok(())
}

/// A sans-serif font of `size` pixels, anchored at its centre.
pub fn centred(size: u32) -> TextStyle<'static> {
    TextStyle::from(("sans-serif", size).into_font()).pos(Pos::new(HPos::Center, VPos::Center))
}

/// The smallest and largest of `values` (finite ones), or `fallback` when there is none;
/// never an empty range.
pub fn span(values: impl IntoIterator<Item = f32>, fallback: (f32, f32)) -> (f32, f32) {
    let (lo, hi) = values
        .into_iter()
        .filter(|v| v.is_finite())
        .fold((f32::MAX, f32::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo > hi {
        fallback
    } else if hi - lo < 1e-6 {
        (lo - 0.5, hi + 0.5)
    } else {
        (lo, hi)
    }
}

/// A tick label: the value without float noise or a negative zero (`0.3`, `0`, not
/// `0.30000001` or `-0.0`).
pub fn tick(v: &f32) -> String {
    let rounded = (f64::from(*v) * 1e6).round() / 1e6 + 0.0;
    format!("{rounded}")
}
