//! The job task: the autonomy's long computations, in thread mode, below both interrupt
//! executors (issue 11, section 1). The control step keeps its period while a job runs: it
//! preempts this task at every sample.

use super::autonomy::run_job;
use super::{JOB_REQUESTS, JOB_RESULTS};

/// Runs each job asked for by the control task and hands its result back, numbered as asked.
#[embassy_executor::task]
pub async fn jobs() {
    loop {
        let (id, request) = JOB_REQUESTS.receive().await;
        let result = run_job(&request.work);
        JOB_RESULTS.send((id, result)).await;
    }
}
