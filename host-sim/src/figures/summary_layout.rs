//! Where the text of the mission's one-page summary ([`super::mission_summary`]) goes, worked
//! out in pixels before anything is drawn, so that no two labels overlap for any robot count
//! the software takes (up to 16) and any lift count: the rows' heights (the rotor panel tall
//! enough for a legend entry per robot), the lifts panel's value labels (level above each bar,
//! upright where they would run into each other, left out where even that does not fit) and
//! its lift names under the bars (shortened, then thinned, as the lifts crowd), and the flight
//! panels' phase names (moved left of their line at the right edge, and down a row where they
//! would meet the one before).
//!
//! Text is measured with [`text_size`], an upper bound on what the sans-serif fonts plotters
//! finds draw (a test checks it against the font this machine has).

use super::canvas::legend_height;
use super::mission_summary::LiftBar;

/// Room for the page's title, pixels.
pub const TITLE_ROOM: u32 = 40;
/// Heights of the page's rows (phases, lifts, height, attitude) above the rotor panel, pixels.
const UPPER_ROWS: [u32; 4] = [300, 260, 300, 300];
/// Least height of the rotor panel, pixels.
const ROTOR_ROW: u32 = 300;
/// Where a flight panel's legend begins, pixels from the row's top.
pub const CURVE_LEGEND_TOP: i32 = 40;

/// Margin round each panel's chart, pixels.
pub const MARGIN: u32 = 10;
/// Height of the area under a chart for the x-axis labels, pixels.
pub const X_LABELS: u32 = 35;
/// Width of the area left of a chart for the y-axis labels, pixels.
pub const Y_LABELS: u32 = 70;

/// Font size of the lifts' value labels, pixels (as plotters counts them).
pub const VALUE_FONT: u32 = 13;
/// Font size of the tick labels, the lift names and the phase names, pixels.
pub const LABEL_FONT: u32 = 14;
/// Least free space kept between two labels, pixels.
const GAP: i32 = 3;
/// A phase name's row height in the flight panels, pixels.
pub const PHASE_ROW: i32 = 16;
/// Where the first row of phase names begins, pixels below the plot's top.
pub const PHASE_TOP: i32 = 2;
/// How far a phase name sits from its line, pixels.
pub const PHASE_INSET: i32 = 4;

/// A label's extent, pixels, x to the right and y down from the plotting area's top left
/// corner (below the plot is `y >` its height).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextBox {
    /// Left edge.
    pub x0: i32,
    /// Top edge.
    pub y0: i32,
    /// Right edge.
    pub x1: i32,
    /// Bottom edge.
    pub y1: i32,
}

impl TextBox {
    /// Whether the two come closer than [`GAP`] pixels (touching counts).
    pub fn overlaps(&self, other: &TextBox) -> bool {
        self.x0 < other.x1 + GAP
            && other.x0 < self.x1 + GAP
            && self.y0 < other.y1 + GAP
            && other.y0 < self.y1 + GAP
    }

    /// Whether it lies within `0..width` across and `0..height` down.
    pub fn inside(&self, width: u32, height: u32) -> bool {
        self.x0 >= 0 && self.y0 >= 0 && self.x1 <= width as i32 && self.y1 <= height as i32
    }
}

/// Whether any two of `boxes` overlap.
pub fn any_overlap(boxes: &[TextBox]) -> bool {
    boxes
        .iter()
        .enumerate()
        .any(|(i, a)| boxes[i + 1..].iter().any(|b| a.overlaps(b)))
}

/// Width and height, pixels, that `text` takes at most in the sans-serif font of `size`
/// (plotters' size: an em is `size / 1.24` pixels). Each character's advance is bounded above
/// by DejaVu Sans' and Liberation Sans'.
pub fn text_size(text: &str, size: u32) -> (u32, u32) {
    let em = size as f32 / 1.24;
    let ems: f32 = text
        .chars()
        .map(|c| match c {
            'm' | 'w' | 'M' | 'W' | '%' => 1.0,
            c if c.is_ascii_uppercase() => 0.8,
            ' ' | '.' | ',' | ':' | ';' | 'i' | 'j' | 'l' | '|' | '!' | '\'' | '(' | ')' => 0.4,
            'f' | 't' | 'r' | '-' => 0.5,
            _ => 0.66,
        })
        .sum();
    ((ems * em).ceil() as u32, em.ceil() as u32 + 1)
}

/// The rows' heights, pixels, for a flight of `robots` rotors: phases, lifts, height,
/// attitude and the rotors, whose legend holds an entry per robot and the phases' line.
pub fn row_heights(robots: usize) -> [u32; 5] {
    let legend = legend_height(CURVE_LEGEND_TOP, robots + 1).max(0) as u32;
    let [a, b, c, d] = UPPER_ROWS;
    [a, b, c, d, ROTOR_ROW.max(legend)]
}

/// The page's size, pixels, for a flight of `robots` rotors.
pub fn page_size(robots: usize) -> (u32, u32) {
    (1300, TITLE_ROOM + row_heights(robots).iter().sum::<u32>())
}

/// The plotting area's size, pixels, of a chart built on `inner` pixels (a panel less its
/// [`MARGIN`] and caption): what [`X_LABELS`] and [`Y_LABELS`] leave.
pub fn plot_size(inner: (u32, u32)) -> (u32, u32) {
    (
        inner.0.saturating_sub(Y_LABELS),
        inner.1.saturating_sub(X_LABELS),
    )
}

/// How the lifts panel writes each bar's value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ValueText {
    /// Level, centred above its bar.
    Level,
    /// Upright (reading upwards) above its bar; a lift that could not lift says so inside its
    /// outline.
    Upright,
    /// Not written: too many lifts for even upright text (the bars and the axis still say).
    Left,
}

/// One value label of the lifts panel.
#[derive(Clone, Debug, PartialEq)]
pub struct ValueLabel {
    /// Where it hangs, in the chart's coordinates (lift, N).
    pub at: (f32, f32),
    /// Its anchor's offset from there, pixels.
    pub offset: (i32, i32),
    /// What it says.
    pub text: String,
    /// Written inside the outline of a lift that could not lift (upright only).
    pub inside_outline: bool,
    /// Where it lands, pixels.
    pub bounds: TextBox,
    /// The same box as offsets from where it hangs, pixels (a pale backdrop, so that the
    /// maximum thrust's line does not run through the text).
    pub backdrop: [(i32, i32); 2],
}

/// Where the lifts panel's text goes.
#[derive(Clone, Debug, PartialEq)]
pub struct LiftLayout {
    /// The value axis' top, N.
    pub top: f32,
    /// How the values are written.
    pub value_text: ValueText,
    /// The value labels (none when [`ValueText::Left`]).
    pub values: Vec<ValueLabel>,
    /// Each lift's name under its bars (empty for a lift left unnamed).
    pub names: Vec<String>,
    /// Where each name lands, pixels (named lifts only).
    pub name_bounds: Vec<TextBox>,
    /// The x axis' description, where the names need one.
    pub x_desc: Option<&'static str>,
}

/// The horizontal offset of a lift's reading bar (`-`) and model bar (`+`) centres from the
/// lift's, in lifts; each bar is twice as wide.
pub const BAR_HALF: f32 = 0.15;

/// Where the lifts panel's text goes for `lifts` on a plotting area of `plot` pixels, the bars
/// reaching `ceiling` N where a lift could not lift; `base_top` is the value axis' top without
/// labels.
pub fn lift_layout(lifts: &[LiftBar], ceiling: f32, base_top: f32, plot: (u32, u32)) -> LiftLayout {
    let (names, name_bounds, x_desc) = lift_names(lifts, plot);
    for mode in [ValueText::Level, ValueText::Upright] {
        if let Some((top, values)) = value_labels(lifts, ceiling, base_top, plot, mode) {
            return LiftLayout {
                top,
                value_text: mode,
                values,
                names,
                name_bounds,
                x_desc,
            };
        }
    }
    LiftLayout {
        top: base_top,
        value_text: ValueText::Left,
        values: Vec::new(),
        names,
        name_bounds,
        x_desc,
    }
}

/// The value labels of `mode` and the axis top they need, or `None` if they would overlap,
/// leave the plot or squash the bars to less than half their height.
fn value_labels(
    lifts: &[LiftBar],
    ceiling: f32,
    base_top: f32,
    plot: (u32, u32),
    mode: ValueText,
) -> Option<(f32, Vec<ValueLabel>)> {
    let (w, h) = (plot.0 as f32, plot.1 as f32);
    let count = lifts.len().max(1) as f32;
    // (x, value, text, inside its outline)
    let mut wanted: Vec<(f32, f32, String, bool)> = Vec::new();
    for (k, lift) in lifts.iter().enumerate() {
        let x = k as f32;
        match lift.reading {
            Some(r) => wanted.push((x - BAR_HALF, r, format!("{r:.2}"), false)),
            None => wanted.push((x - BAR_HALF, ceiling, "could not lift".to_string(), true)),
        }
        if let Some(m) = lift.model {
            wanted.push((x + BAR_HALF, m, format!("{m:.2}"), false));
        }
    }
    // Pixels each label needs above its bar's top.
    let above = |text: &str, inside: bool| -> f32 {
        let (tw, th) = text_size(text, VALUE_FONT);
        match mode {
            ValueText::Level => (LEVEL_RAISE + th as i32 / 2 + 1) as f32,
            _ if inside => 0.0,
            _ => (UPRIGHT_RAISE + tw as i32 + 1) as f32,
        }
    };
    let mut top = base_top;
    for (_, v, text, inside) in &wanted {
        let need = above(text, *inside);
        if need >= h {
            return None;
        }
        top = top.max(v * h / (h - need));
    }
    if top > 2.0 * base_top {
        return None;
    }
    let px = |x: f32| (x + 0.5) / count * w;
    let py = |v: f32| h * (1.0 - v / top);
    let labels: Vec<ValueLabel> = wanted
        .into_iter()
        .map(|(x, v, text, inside)| {
            let (tw, th) = text_size(&text, VALUE_FONT);
            let (tw, th) = (tw as i32, th as i32);
            let cx = px(x).round() as i32;
            let (at, offset, bounds) = match mode {
                ValueText::Level => {
                    let cy = py(v).round() as i32 - LEVEL_RAISE;
                    let b = TextBox {
                        x0: cx - tw / 2 - 1,
                        y0: cy - th / 2 - 1,
                        x1: cx + tw / 2 + 1,
                        y1: cy + th / 2 + 1,
                    };
                    ((x, v), (0, -LEVEL_RAISE), b)
                }
                _ => {
                    let (value, raise) = if inside {
                        (0.0, INSIDE_RAISE)
                    } else {
                        (v, UPRIGHT_RAISE)
                    };
                    let bottom = py(value).round() as i32 - raise;
                    // Upright, the text's height lies across.
                    let b = TextBox {
                        x0: cx - th / 2,
                        y0: bottom - tw,
                        x1: cx - th / 2 + th,
                        y1: bottom,
                    };
                    ((x, value), (0, -raise), b)
                }
            };
            let ay = py(at.1).round() as i32;
            ValueLabel {
                at,
                offset,
                text,
                inside_outline: inside && mode == ValueText::Upright,
                bounds,
                backdrop: [
                    (bounds.x0 - cx, bounds.y0 - ay),
                    (bounds.x1 - cx, bounds.y1 - ay),
                ],
            }
        })
        .collect();
    let boxes: Vec<TextBox> = labels.iter().map(|l| l.bounds).collect();
    // "could not lift" written upright stays inside its outline, which reaches the ceiling.
    let in_outline = labels
        .iter()
        .filter(|l| l.inside_outline)
        .all(|l| l.bounds.y0 as f32 >= py(ceiling));
    let fits = in_outline && boxes.iter().all(|b| b.inside(plot.0, plot.1)) && !any_overlap(&boxes);
    fits.then_some((top, labels))
}

/// How far a level value label's centre sits above its bar, pixels.
pub const LEVEL_RAISE: i32 = 10;
/// How far an upright value label's foot sits above its bar, pixels.
pub const UPRIGHT_RAISE: i32 = 4;
/// How far "could not lift", upright, sits above the axis inside its outline, pixels.
pub const INSIDE_RAISE: i32 = 6;
/// How far below the plot a tick label's top sits, pixels (plotters' tick and its gap).
const NAME_DROP: i32 = 5;

/// Each lift's name, the names' boxes and the axis description they need: `lift 3: pair 5`
/// where every one fits under its lift, else `pair 5`, else the pair alone, on every lift or
/// every second, third, ... lift as room allows.
fn lift_names(
    lifts: &[LiftBar],
    plot: (u32, u32),
) -> (Vec<String>, Vec<TextBox>, Option<&'static str>) {
    let count = lifts.len().max(1);
    let slot = plot.0 as f32 / count as f32;
    type Namer = fn(usize, usize) -> String;
    let forms: [(Namer, Option<&'static str>); 3] = [
        (|k, p| format!("lift {k}: pair {p}"), None),
        (|_, p| format!("pair {p}"), Some("lifts in order")),
        (
            |_, p| format!("{p}"),
            Some("the pair of each lift, in order"),
        ),
    ];
    let fits = |names: &[String], step: usize| {
        names
            .iter()
            .all(|n| text_size(n, LABEL_FONT).0 as f32 + GAP as f32 + 2.0 <= slot * step as f32)
    };
    let named = |form: Namer| -> Vec<String> {
        lifts
            .iter()
            .enumerate()
            .map(|(k, l)| form(k + 1, l.pair))
            .collect()
    };
    let (names, desc, step) = forms
        .iter()
        .find_map(|&(form, desc)| {
            let names = named(form);
            fits(&names, 1).then_some((names, desc, 1))
        })
        .unwrap_or_else(|| {
            let (form, desc) = forms[2];
            let names = named(form);
            let step = (1..=count).find(|&s| fits(&names, s)).unwrap_or(count);
            (names, desc, step)
        });
    let names: Vec<String> = names
        .into_iter()
        .enumerate()
        .map(|(k, n)| if k % step == 0 { n } else { String::new() })
        .collect();
    let bounds = names
        .iter()
        .enumerate()
        .filter(|(_, n)| !n.is_empty())
        .map(|(k, n)| {
            let (tw, th) = text_size(n, LABEL_FONT);
            let cx = ((k as f32 + 0.5) * slot).round() as i32;
            let y0 = plot.1 as i32 + NAME_DROP;
            TextBox {
                x0: cx - tw as i32 / 2 - 1,
                y0,
                x1: cx + tw as i32 / 2 + 1,
                y1: y0 + th as i32,
            }
        })
        .collect();
    (names, bounds, desc)
}

/// One phase's name in a flight panel.
#[derive(Clone, Debug, PartialEq)]
pub struct PhaseLabel {
    /// The phase's start, s (its line).
    pub start: f32,
    /// Its name.
    pub text: String,
    /// Written right of its line (else left of it: it would leave the plot on the right).
    pub right_of_line: bool,
    /// Its row, from the top.
    pub row: usize,
    /// Where it lands, pixels.
    pub bounds: TextBox,
}

/// Where the names of phases `(name, start s)` go on a plot of `width` pixels spanning `t`:
/// right of their line, or left of it where they would leave the plot, in the first row from
/// the top where they meet no name already placed.
pub fn phase_labels(phases: &[(String, f32)], t: (f32, f32), width: u32) -> Vec<PhaseLabel> {
    let span = (t.1 - t.0).max(1e-6);
    let mut placed: Vec<PhaseLabel> = Vec::new();
    for (name, start) in phases {
        let (tw, th) = text_size(name, LABEL_FONT);
        let (tw, th) = (tw as i32, th as i32);
        let x = ((start - t.0) / span * width as f32).round() as i32;
        let right_of_line = x + PHASE_INSET + tw <= width as i32;
        let x0 = if right_of_line {
            x + PHASE_INSET
        } else {
            (x - PHASE_INSET - tw).max(0)
        };
        let at_row = |row: usize| TextBox {
            x0,
            y0: PHASE_TOP + row as i32 * PHASE_ROW,
            x1: x0 + tw,
            y1: PHASE_TOP + row as i32 * PHASE_ROW + th,
        };
        let row = (0..)
            .find(|&r| {
                let b = at_row(r);
                placed.iter().all(|p| !p.bounds.overlaps(&b))
            })
            .unwrap_or(0);
        placed.push(PhaseLabel {
            start: *start,
            text: name.clone(),
            right_of_line,
            row,
            bounds: at_row(row),
        });
    }
    placed
}

/// Pixels the phase names take at the top of a flight panel.
pub fn phase_room(labels: &[PhaseLabel]) -> i32 {
    labels.iter().map(|l| l.bounds.y1).max().unwrap_or(0) + GAP
}

#[cfg(test)]
mod tests;
