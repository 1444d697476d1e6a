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

use super::autonomy::{Report, run_job};
use onboard::payload_loading::PayloadLoader;

use super::comms::Outbound;
use super::{
    JOB_REQUESTS, JOB_RESULTS, LOADING, MISSION_CONFIG, MISSION_STATE, OUTBOX, PAYLOAD_ROBOTS,
    RELOAD, TO_LOAD, offer_payload,
};

static PLANNER: ConstStaticCell<MissionPlanner> = ConstStaticCell::new(MissionPlanner::UNLOADED);
/// The last payload description accepted, for loading again when the parameters change.
static LOADER: StaticCell<PayloadLoader> = StaticCell::new();

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
    let loader = LOADER.init(PayloadLoader::new());
    loop {
        match select3(
            TO_LOAD.ready_to_receive(),
            JOB_REQUESTS.receive(),
            RELOAD.wait(),
        )
        .await
        {
            Either3::First(()) => {
                let Some(report) = load(planner, loader) else {
                    continue;
                };
                OUTBOX.send(Outbound::Report(report)).await;
            }
            Either3::Third(()) => {
                let Some(report) = reload(planner, loader) else {
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
/// task ([`PayloadLoader::load`]); says which, or why not (nothing if none waits: the task is
/// `TO_LOAD`'s only receiver, so one does).
fn load(planner: &mut MissionPlanner, loader: &mut PayloadLoader) -> Option<Report> {
    let received = TO_LOAD.try_receive().ok()?;
    LOADING.store(true, Ordering::SeqCst);
    // The parameters in force now; the mission gets the same with the description.
    let config = MISSION_CONFIG.lock(|c| c.get());
    let running = mission_running();
    let (report, loaded) = loader.load(planner, received, config, running);
    if let Some(payload) = loaded {
        PAYLOAD_ROBOTS.store(payload.scenario.robots.count() as u8, Ordering::Relaxed);
        offer_payload(payload);
    }
    LOADING.store(false, Ordering::SeqCst);
    Some(report)
}

/// New parameters: the last description loaded again with them ([`PayloadLoader::reload`]).
fn reload(planner: &mut MissionPlanner, loader: &mut PayloadLoader) -> Option<Report> {
    LOADING.store(true, Ordering::SeqCst);
    let running = mission_running();
    let config = MISSION_CONFIG.lock(|c| c.get());
    let answer = loader
        .reload(planner, config, running)
        .map(|(report, loaded)| {
            if let Some(payload) = loaded {
                offer_payload(payload);
            }
            report
        });
    LOADING.store(false, Ordering::SeqCst);
    answer
}

/// The mission runs now, as the control task last said.
fn mission_running() -> bool {
    MISSION_STATE.load(Ordering::SeqCst) == MissionState::Running as u8
}
