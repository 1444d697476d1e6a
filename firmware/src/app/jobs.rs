//! The job task: the autonomy's long computations, in thread mode, below both interrupt
//! executors. The control step keeps its period while a job runs: it
//! preempts this task at every sample.
//!
//! It owns the mission's job side, the [`MissionPlanner`] with the estimator's grid-sized
//! buffers, built in place in a static. A payload description that passed the link's checks
//! comes here first: the planner is loaded with it (a grid-sized reset, never in a tick),
//! and only then does the description go to the control task and the ground hear that it was
//! accepted (or, should the estimator refuse it, why not). Both are loaded with the
//! configuration the parameters make at that moment (`super::MISSION_CONFIG`); when a
//! parameter changes while the mission is not running, the last description is loaded again
//! with the new configuration, so what the ground set is what the next mission flies.

use core::sync::atomic::Ordering;

use embassy_futures::select::{Either3, select3};
use link::status::MissionState;
use shared::mission::MissionPlanner;
use static_cell::{ConstStaticCell, StaticCell};

use super::autonomy::{Report, Severity, run_job};
use super::comms::{Outbound, Received};
use super::{
    JOB_REQUESTS, JOB_RESULTS, LOADING, LoadedPayload, MISSION_CONFIG, MISSION_STATE, OUTBOX,
    PAYLOAD_ROBOTS, RELOAD, TO_LOAD, offer_payload,
};

/// Why a received description was not loaded into the planner.
enum LoadRefusal {
    /// A running mission's jobs need the planner it started with.
    Running,
    /// The planner refused it.
    Checks(shared::mission::AbortReason),
}

impl core::fmt::Display for LoadRefusal {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Running => f.write_str("the mission is running"),
            Self::Checks(why) => why.fmt(f),
        }
    }
}

static PLANNER: ConstStaticCell<MissionPlanner> = ConstStaticCell::new(MissionPlanner::UNLOADED);
/// The last payload description accepted, for loading again when the parameters change.
static LAST: StaticCell<Option<Received>> = StaticCell::new();

/// Runs each job asked for by the control task and hands its result back, numbered as asked;
/// loads each payload description received.
///
/// The task's future is a static: what it keeps across a wait costs RAM for good. So a
/// description (1.4 KB) never crosses one: it stays in `TO_LOAD` until the task is ready to
/// load it, and the loading, in [`load`] and [`reload`], is synchronous; only the report
/// crosses the wait for the link's queue.
#[embassy_executor::task]
pub async fn jobs() {
    let planner = PLANNER.take();
    let last = LAST.init(None);
    loop {
        match select3(
            TO_LOAD.ready_to_receive(),
            JOB_REQUESTS.receive(),
            RELOAD.wait(),
        )
        .await
        {
            Either3::First(()) => {
                let Some(report) = load(planner, last) else {
                    continue;
                };
                OUTBOX.send(Outbound::Report(report)).await;
            }
            Either3::Third(()) => {
                let Some(report) = reload(planner, last) else {
                    continue;
                };
                OUTBOX.send(Outbound::Report(report)).await;
            }
            Either3::Second((id, request)) => {
                let result = run_job(planner, &request.work);
                JOB_RESULTS.send((id, result)).await;
            }
        }
    }
}

/// Loads the planner with the description waiting in `TO_LOAD` and offers it to the control
/// task, keeping it in `last`; says which, or why not (nothing if none waits: the task is
/// `TO_LOAD`'s only receiver, so one does).
fn load(planner: &mut MissionPlanner, last: &mut Option<Received>) -> Option<Report> {
    let received = TO_LOAD.try_receive().ok()?;
    let mut report = Report::default();
    LOADING.store(true, Ordering::SeqCst);
    // The parameters in force now; the mission gets the same with the description.
    let config = MISSION_CONFIG.lock(|c| c.get());
    // A running mission's jobs need the planner it started with: a description
    // that comes now is not loaded (the mission would ignore it anyway).
    let running = MISSION_STATE.load(Ordering::SeqCst) == MissionState::Running as u8;
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
            PAYLOAD_ROBOTS.store(received.scenario.robots.count() as u8, Ordering::Relaxed);
            offer_payload(LoadedPayload {
                scenario: received.scenario.clone(),
                config,
            });
            *last = Some(received);
        }
        Err(why) => {
            report.text(Severity::Error, format_args!("payload refused: {why}"));
        }
    }
    LOADING.store(false, Ordering::SeqCst);
    Some(report)
}

/// New parameters: the last description loaded again with them, unless the mission runs (the
/// link refuses changes then; this guards the moment of a start); says so, or nothing when
/// there is nothing to load.
fn reload(planner: &mut MissionPlanner, last: &Option<Received>) -> Option<Report> {
    LOADING.store(true, Ordering::SeqCst);
    let running = MISSION_STATE.load(Ordering::SeqCst) == MissionState::Running as u8;
    let mut answer = None;
    if let (Some(received), false) = (last.as_ref(), running) {
        let config = MISSION_CONFIG.lock(|c| c.get());
        let mut report = Report::default();
        match planner.load(&received.scenario, config) {
            Ok(()) => {
                report.text(
                    Severity::Info,
                    format_args!("params applied to payload {}", received.name),
                );
                offer_payload(LoadedPayload {
                    scenario: received.scenario.clone(),
                    config,
                });
            }
            Err(why) => {
                report.text(Severity::Error, format_args!("params not applied: {why}"));
            }
        }
        answer = Some(report);
    }
    LOADING.store(false, Ordering::SeqCst);
    answer
}
