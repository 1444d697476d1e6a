//! The job task: the autonomy's long computations, in thread mode, below both interrupt
//! executors (issue 11, section 1). The control step keeps its period while a job runs: it
//! preempts this task at every sample.
//!
//! It owns the mission's job side, the [`MissionPlanner`] with the estimator's grid-sized
//! buffers, built in place in a static. A payload description that passed the link's checks
//! comes here first: the planner is loaded with it (a grid-sized reset, never in a tick),
//! and only then does the description go to the control task and the ground hear that it was
//! accepted (or, should the estimator refuse it, why not).

use embassy_futures::select::{Either, select};
use shared::mission::MissionPlanner;
use static_cell::ConstStaticCell;

use super::autonomy::{CONFIG, Report, Severity, run_job};
use super::comms::Outbound;
use super::{JOB_REQUESTS, JOB_RESULTS, OUTBOX, PAYLOAD, TO_LOAD};

static PLANNER: ConstStaticCell<MissionPlanner> = ConstStaticCell::new(MissionPlanner::UNLOADED);

/// Runs each job asked for by the control task and hands its result back, numbered as asked;
/// loads each payload description received.
#[embassy_executor::task]
pub async fn jobs() {
    let planner = PLANNER.take();
    loop {
        match select(TO_LOAD.receive(), JOB_REQUESTS.receive()).await {
            Either::First(received) => {
                let mut report = Report::default();
                match planner.load(&received.scenario, CONFIG) {
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
                        PAYLOAD.signal(received.scenario);
                    }
                    Err(why) => {
                        report.text(Severity::Error, format_args!("payload refused: {why}"));
                    }
                }
                OUTBOX.send(Outbound::Report(report)).await;
            }
            Either::Second((id, request)) => {
                let result = run_job(planner, &request.work);
                JOB_RESULTS.send((id, result)).await;
            }
        }
    }
}
