use super::*;
use crate::figures::canvas::{LEGEND_WIDTH, legend_height};
use crate::figures::mission_summary::{MissionSummary, SummarySample};
use plotters::style::IntoFont;

/// What plotters takes for an 18-pixel caption: an em of 18 / 1.24 pixels and 5 above and
/// below.
const CAPTION_ROOM: u32 = 24;

/// The plotting area of the page's row `row` for `robots` rotors, pixels.
fn plot_of(row: usize, robots: usize) -> (u32, u32) {
    let (width, _) = page_size(robots);
    let height = row_heights(robots)[row];
    plot_size((
        width - LEGEND_WIDTH - 2 * MARGIN,
        height - 2 * MARGIN - CAPTION_ROOM,
    ))
}

/// A flight of `robots` rotors, two samples long.
fn summary_with(robots: usize) -> MissionSummary {
    let sample = |t: f32| SummarySample {
        t,
        height: 0.5,
        roll_pitch_deg: [0.0, 0.0],
        thrust: (0..robots).map(|j| 4.0 + j as f32 * 0.1).collect(),
    };
    MissionSummary {
        series: vec![sample(50.0), sample(60.0)],
        thrust_in_newtons: true,
        ..MissionSummary::default()
    }
}

#[test]
fn every_robot_has_its_own_legend_entry_and_the_rotor_panel_holds_them_all() {
    for robots in [4, 8, 12, 16] {
        let summary = summary_with(robots);
        let curves = summary.thrust_curves();
        let labels: Vec<&str> = curves.iter().map(|(l, _, _)| l.as_str()).collect();
        let expected: Vec<String> = (1..=robots).map(|j| format!("robot {j}")).collect();
        assert_eq!(labels, expected, "{robots} robots");
        for (i, a) in curves.iter().enumerate() {
            for b in &curves[i + 1..] {
                assert_ne!(
                    a.1, b.1,
                    "{robots} robots: {} and {} share a colour",
                    a.0, b.0
                );
            }
        }
        // Each robot's entry and the phases' line, below the panel's top.
        let bottom = legend_height(CURVE_LEGEND_TOP, robots + 1);
        let row = row_heights(robots)[4] as i32;
        assert!(
            bottom <= row,
            "{robots} robots: the legend reaches {bottom} px, the panel {row} px"
        );
    }
    // The page the paper's eight robots had is unchanged.
    assert_eq!(page_size(8), (1300, 1500));
}

/// `count` lifts as a 16-robot mission's might read: pairs up to 17, readings beside models
/// a few hundredths apart, every fifth out of reach.
fn lifts(count: usize) -> Vec<LiftBar> {
    let values = [6.55, 11.67, 8.75, 14.19, 9.93, 12.08];
    (0..count)
        .map(|k| {
            let v = values[k % values.len()];
            LiftBar {
                pair: (k * 7 + 2) % 18,
                reading: (k % 5 != 4).then_some(v),
                model: Some(v + 0.03),
            }
        })
        .collect()
}

#[test]
fn lift_labels_never_overlap_and_every_value_is_written_up_to_twenty_lifts() {
    let plot = plot_of(1, 16);
    let ceiling = 14.2;
    for count in 1..=50 {
        let bars = lifts(count);
        let placed = lift_layout(&bars, ceiling, ceiling * 1.12, plot);
        let boxes: Vec<TextBox> = placed.values.iter().map(|l| l.bounds).collect();
        assert!(!any_overlap(&boxes), "{count} lifts: value labels overlap");
        for b in &boxes {
            assert!(
                b.inside(plot.0, plot.1),
                "{count} lifts: {b:?} leaves the plot"
            );
        }
        assert!(
            !any_overlap(&placed.name_bounds),
            "{count} lifts: lift names overlap: {:?}",
            placed.names
        );
        assert_eq!(placed.names.len(), count);
        assert!(!placed.name_bounds.is_empty(), "{count} lifts: none named");
        // The bars keep at least half the panel.
        assert!(placed.top <= 2.0 * ceiling * 1.12 + 1e-3);
        if count <= 20 {
            let written = bars.len() + bars.iter().filter(|l| l.model.is_some()).count();
            assert_ne!(placed.value_text, ValueText::Left, "{count} lifts");
            assert_eq!(placed.values.len(), written, "{count} lifts");
            assert_eq!(
                placed.name_bounds.len(),
                count,
                "{count} lifts: a lift unnamed"
            );
        }
    }
    // A few lifts are written as before: level, each named in full.
    let few = lift_layout(&lifts(3), ceiling, ceiling * 1.12, plot);
    assert_eq!(few.value_text, ValueText::Level);
    assert_eq!(few.names[0], "lift 1: pair 2");
    assert_eq!(few.x_desc, None);
    // Thirteen (as a 16-robot mission has flown) no longer fit level.
    let many = lift_layout(&lifts(13), ceiling, ceiling * 1.12, plot);
    assert_eq!(many.value_text, ValueText::Upright);
}

#[test]
fn phase_names_keep_apart_and_inside_the_plot() {
    let (width, height) = plot_of(4, 16);
    let named = |v: &[(&str, f32)]| -> Vec<(String, f32)> {
        v.iter().map(|&(n, t)| (n.to_string(), t)).collect()
    };
    // rect-16's flight, and one that ends in a hurry (phases a few tenths apart).
    let cases = [
        (
            named(&[
                ("takeoff", 50.42),
                ("trajectory", 53.55),
                ("hover", 61.06),
                ("landing", 64.06),
                ("disarmed", 67.56),
            ]),
            (50.42, 67.56),
        ),
        (
            named(&[
                ("takeoff", 10.0),
                ("trajectory", 12.0),
                ("failsafe-land", 20.0),
                ("landing", 20.2),
                ("disarmed", 20.5),
            ]),
            (10.0, 20.5),
        ),
    ];
    for (phases, t) in &cases {
        let placed = phase_labels(phases, *t, width);
        assert_eq!(placed.len(), phases.len());
        let boxes: Vec<TextBox> = placed.iter().map(|p| p.bounds).collect();
        assert!(!any_overlap(&boxes), "{placed:?}");
        for b in &boxes {
            assert!(b.inside(width, height), "{b:?} leaves the plot");
        }
        let last = placed.last().expect("a phase");
        assert!(
            !last.right_of_line,
            "the last phase's name runs off the plot"
        );
        assert!(phase_room(&placed) < height as i32 / 2);
    }
}

#[test]
fn the_text_estimate_bounds_what_the_font_draws() {
    let texts = [
        "11.67",
        "could not lift",
        "lift 13: pair 16",
        "pair 17",
        "17",
        "disarmed",
        "preflight-checks",
        "failsafe-land",
        "robot 16",
    ];
    for size in [VALUE_FONT, LABEL_FONT] {
        for text in texts {
            let font = ("sans-serif", size).into_font();
            let Ok((w, h)) = font.box_size(text) else {
                eprintln!("no sans-serif font here: the estimate is not checked");
                return;
            };
            let (ew, eh) = text_size(text, size);
            assert!(ew >= w && eh >= h, "{text} at {size}: {ew}x{eh} < {w}x{h}");
        }
    }
}
