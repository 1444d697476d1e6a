//! `campaign --output`'s figure (docs/commands.md#campaign): each trial's final error over
//! each parameter drawn for it (the robots' count, the payload's mass and vertices, every
//! `[plant]` departure of docs/formats.md#the-plant-section), one small plot a parameter,
//! every trial a mark coloured by what came of it.

use anyhow::Result;
use plotters::prelude::*;

use super::canvas::{Area, Figure, GREY, Swatch, colour, draw_error, legend, span, tick, titled};
use crate::campaign::{DELIVERED_WITHIN, TrialResult};

/// What came of a trial, as the figure colours it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Delivered within the campaign's distance.
    Delivered,
    /// Ended elsewhere, neither dropped nor aborted.
    NotDelivered,
    /// Dropped.
    Dropped,
    /// Refused before take-off for want of margin.
    Refused,
    /// A healthy vehicle aborted.
    FalseAlarm,
    /// A fault was injected and the vehicle stopped or landed for it.
    FaultFound,
    /// A fault was injected and the vehicle did not answer it (not dropped).
    FaultMissed,
}

impl Outcome {
    /// Every outcome, in the legend's order.
    pub const ALL: [Self; 7] = [
        Self::Delivered,
        Self::NotDelivered,
        Self::Refused,
        Self::FalseAlarm,
        Self::FaultFound,
        Self::FaultMissed,
        Self::Dropped,
    ];

    /// What came of `r`.
    pub fn of(r: &TrialResult) -> Self {
        if r.outcome == "dropped" {
            Self::Dropped
        } else if r.fault.is_some() {
            if r.fault_found == Some(true) {
                Self::FaultFound
            } else {
                Self::FaultMissed
            }
        } else if r.outcome == "refused" {
            Self::Refused
        } else if r.outcome == "aborted" {
            Self::FalseAlarm
        } else if r.outcome == "delivered" {
            Self::Delivered
        } else {
            Self::NotDelivered
        }
    }

    fn label(self) -> &'static str {
        match self {
            Self::Delivered => "delivered",
            Self::NotDelivered => "not delivered",
            Self::Dropped => "dropped (at the top)",
            Self::Refused => "refused before take-off",
            Self::FalseAlarm => "aborted, no fault",
            Self::FaultFound => "fault found",
            Self::FaultMissed => "fault missed",
        }
    }

    fn swatch(self) -> Swatch {
        match self {
            Self::Delivered => Swatch::Dot(colour(2)),
            Self::NotDelivered => Swatch::Dot(colour(1)),
            Self::Dropped => Swatch::Cross(colour(3)),
            Self::Refused => Swatch::Ring(colour(6)),
            Self::FalseAlarm => Swatch::Triangle(colour(4)),
            Self::FaultFound => Swatch::Ring(colour(0)),
            Self::FaultMissed => Swatch::Triangle(colour(5)),
        }
    }
}

/// One drawn parameter: its axis label and its value in a trial.
struct Parameter {
    label: &'static str,
    value: fn(&TrialResult) -> f32,
}

fn plant(r: &TrialResult, key: &str) -> f32 {
    r.plant.get(key).copied().unwrap_or(f32::NAN)
}

const PARAMETERS: [Parameter; 15] = [
    Parameter {
        label: "robots on the rail",
        value: |r| r.robots as f32,
    },
    Parameter {
        label: "payload mass, kg",
        value: |r| r.payload_mass_kg,
    },
    Parameter {
        label: "footprint vertices",
        value: |r| r.vertices as f32,
    },
    Parameter {
        label: "rotor efficiency spread, +-fraction",
        value: |r| plant(r, "rotor_efficiency_spread"),
    },
    Parameter {
        label: "motor time constant, s",
        value: |r| plant(r, "motor_time_constant"),
    },
    Parameter {
        label: "inertia scale, x model",
        value: |r| plant(r, "inertia_scale"),
    },
    Parameter {
        label: "robot mass scale, x model",
        value: |r| plant(r, "robot_mass_scale"),
    },
    Parameter {
        label: "motion-capture latency, s",
        value: |r| plant(r, "mocap_latency"),
    },
    Parameter {
        label: "motion-capture dropout, fraction",
        value: |r| plant(r, "mocap_dropout"),
    },
    Parameter {
        label: "wind speed, m/s",
        value: |r| plant(r, "wind"),
    },
    Parameter {
        label: "gust, m/s RMS",
        value: |r| plant(r, "gust"),
    },
    Parameter {
        label: "accelerometer vibration, m/s^2 RMS",
        value: |r| plant(r, "imu_vibration"),
    },
    Parameter {
        label: "gyro vibration, rad/s RMS",
        value: |r| plant(r, "gyro_vibration"),
    },
    Parameter {
        label: "battery sag, Ohm",
        value: |r| plant(r, "battery_sag"),
    },
    Parameter {
        label: "ground effect, off 0 / on 1",
        value: |r| plant(r, "ground_effect"),
    },
];

/// Plots a row.
const COLUMNS: usize = 4;

/// The figure: the trials and a title.
pub struct CampaignOutcomes<'a> {
    /// The trials.
    pub results: &'a [TrialResult],
    /// Its title.
    pub title: String,
}

impl Figure for CampaignOutcomes<'_> {
    fn size(&self) -> (u32, u32) {
        (1400, 900)
    }

    fn draw<DB: DrawingBackend>(&self, root: &Area<DB>) -> Result<()> {
        let body = titled(root, &self.title)?;
        let rows =
            PARAMETERS.len().div_ceil(COLUMNS) + usize::from(PARAMETERS.len() % COLUMNS == 0);
        let cells = body.split_evenly((rows, COLUMNS));
        // The error axis, shared: logarithmic, from the smallest error to the largest.
        let errors = self
            .results
            .iter()
            .filter_map(|r| r.final_error_m)
            .filter(|e| e.is_finite() && *e > 0.0);
        let (lo, hi) = span(errors, (0.01, 1.0));
        let (lo, hi) = ((lo / 1.5).max(1e-4), (hi * 1.5).max(lo * 10.0));
        for (parameter, cell) in PARAMETERS.iter().zip(&cells) {
            let values = self.results.iter().map(parameter.value);
            let (x0, x1) = span(values, (0.0, 1.0));
            let pad = 0.05 * (x1 - x0);
            let mut chart = ChartBuilder::on(cell)
                .margin(8)
                .x_label_area_size(38)
                .y_label_area_size(52)
                .build_cartesian_2d((x0 - pad)..(x1 + pad), (lo..hi).log_scale())
                .map_err(draw_error)?;
            chart
                .configure_mesh()
                .label_style(("sans-serif", 12))
                .axis_desc_style(("sans-serif", 14))
                .x_labels(5)
                .y_labels(5)
                .x_label_formatter(&tick)
                .y_label_formatter(&|v| format!("{v:.3}"))
                .x_desc(parameter.label)
                .y_desc("final error, m")
                .draw()
                .map_err(draw_error)?;
            // The delivery distance, dashed.
            let within = DELIVERED_WITHIN.clamp(lo, hi);
            chart
                .draw_series(DashedLineSeries::new(
                    [(x0 - pad, within), (x1 + pad, within)],
                    6,
                    4,
                    GREY.stroke_width(1),
                ))
                .map_err(draw_error)?;
            for r in self.results {
                let x = (parameter.value)(r);
                if !x.is_finite() {
                    continue;
                }
                let y = r.final_error_m.filter(|e| e.is_finite()).unwrap_or(hi);
                let y = y.clamp(lo, hi);
                let outcome = Outcome::of(r);
                let at = (x, y);
                match outcome.swatch() {
                    Swatch::Cross(c) => chart.draw_series([Cross::new(at, 4, c.stroke_width(2))]),
                    Swatch::Ring(c) => chart.draw_series([Circle::new(at, 4, c.stroke_width(2))]),
                    Swatch::Triangle(c) => {
                        chart.draw_series([TriangleMarker::new(at, 5, c.filled())])
                    }
                    Swatch::Dot(c) | Swatch::Bar(c) | Swatch::Line(c) | Swatch::Dashed(c) => {
                        chart.draw_series([Circle::new(at, 3, c.mix(0.8).filled())])
                    }
                    Swatch::Sign(_) => continue,
                }
                .map_err(draw_error)?;
            }
        }
        // The legend in the last cell, with the counts.
        if let Some(cell) = cells.last() {
            let mut entries: Vec<(String, Swatch)> = Outcome::ALL
                .iter()
                .map(|&o| {
                    let n = self.results.iter().filter(|r| Outcome::of(r) == o).count();
                    (format!("{} ({n})", o.label()), o.swatch())
                })
                .collect();
            entries.push((
                format!("delivered within {DELIVERED_WITHIN} m"),
                Swatch::Dashed(GREY),
            ));
            legend(cell, 30, &entries)?;
        }
        Ok(())
    }
}
