//! The job task's side of a payload description (docs/firmware.md#control-step-and-jobs): a checked
//! description from the link is loaded into the [`MissionPlanner`] first (a grid-sized reset,
//! never in a tick) and only then offered to the control task, with the configuration the
//! parameters make at that moment; when a parameter changes while the mission is not
//! running, the last description is loaded again with the new configuration, so what the
//! ground set is what the next mission flies.

use core::fmt;

use shared::mission::{AbortReason, MissionConfig, MissionPlanner};
use shared::scenario::Scenario;

use crate::autonomy::{Report, Severity};
use crate::link_service::Received;

/// A description loaded into the planner, for the control task, with its configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedPayload {
    /// The description.
    pub scenario: Scenario,
    /// The configuration.
    pub config: MissionConfig,
}

/// Why a received description was not loaded into the planner.
enum LoadRefusal {
    /// A running mission's jobs need the planner it started with.
    Running,
    /// The planner refused it.
    Checks(AbortReason),
}

impl fmt::Display for LoadRefusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Running => f.write_str("the mission is running"),
            Self::Checks(why) => why.fmt(f),
        }
    }
}

/// The last description accepted, kept to load again when the parameters change.
#[derive(Default)]
pub struct PayloadLoader {
    last: Option<Received>,
}

impl PayloadLoader {
    /// Nothing accepted yet.
    pub const fn new() -> Self {
        Self { last: None }
    }

    /// Loads `received` into `planner` with `config` unless the mission runs; says which, or
    /// why not. What the control task is to take comes back with the report.
    pub fn load(
        &mut self,
        planner: &mut MissionPlanner,
        received: Received,
        config: MissionConfig,
        running: bool,
    ) -> (Report, Option<LoadedPayload>) {
        let mut report = Report::default();
        // A running mission's jobs need the planner it started with: a description that
        // comes now is not loaded (the mission would ignore it anyway).
        let loaded = if running {
            Err(LoadRefusal::Running)
        } else {
            planner
                .load(&received.scenario, config)
                .map_err(LoadRefusal::Checks)
        };
        match loaded {
            Ok(()) => {
                let grid = &received.scenario.estimation;
                report.text(
                    Severity::Info,
                    format_args!(
                        "payload {} accepted: {} robots, {} candidates, grid {}x{}x{}",
                        received.name,
                        received.scenario.robots.count(),
                        received.scenario.payload.candidates.len(),
                        grid.axis_len(0),
                        grid.axis_len(1),
                        grid.axis_len(2)
                    ),
                );
                let payload = LoadedPayload {
                    scenario: received.scenario.clone(),
                    config,
                };
                self.last = Some(received);
                (report, Some(payload))
            }
            Err(why) => {
                report.text(Severity::Error, format_args!("payload refused: {why}"));
                (report, None)
            }
        }
    }

    /// New parameters: the last description loaded again with `config`, unless the mission
    /// runs (the link refuses changes then; this guards the moment of a start); says so, or
    /// nothing when there is nothing to load.
    pub fn reload(
        &mut self,
        planner: &mut MissionPlanner,
        config: MissionConfig,
        running: bool,
    ) -> Option<(Report, Option<LoadedPayload>)> {
        let received = self.last.as_ref().filter(|_| !running)?;
        let mut report = Report::default();
        match planner.load(&received.scenario, config) {
            Ok(()) => {
                report.text(
                    Severity::Info,
                    format_args!("params applied to payload {}", received.name),
                );
                let payload = LoadedPayload {
                    scenario: received.scenario.clone(),
                    config,
                };
                Some((report, Some(payload)))
            }
            Err(why) => {
                report.text(Severity::Error, format_args!("params not applied: {why}"));
                Some((report, None))
            }
        }
    }

    /// The last description accepted.
    pub fn last(&self) -> Option<&Received> {
        self.last.as_ref()
    }
}
