//! `paperbot::model::estimator` and `paperbot::model::measurement` on the
//! lx106 against the same calls on the core built for the host: the scripted
//! runs of `crate::scripts` (predict with every motion and irregular time
//! steps, lidar corrections accepted, gated as outliers and refused as
//! unusable, compass corrections, `expected_lidar` / `expected_heading`
//! before each correction) must give the host's bits after every call
//! (`crate::host_bits`, written by lx106/vectors).

use super::{check, Mismatches, Test, TestResult};
use crate::host_bits::ESTIMATOR;
use crate::println;
use crate::scripts::{run_estimator, EstRec, EST_RUNS};

pub const TESTS: &[Test] = &[("scripted_runs_bit_exact_vs_host", scripted_runs)];

fn scripted_runs() -> TestResult {
    check(EST_RUNS.len() == ESTIMATOR.len(), "host_bits.rs has another number of runs (stale?)")?;
    let mut m = Mismatches::new();
    for (run, want) in EST_RUNS.iter().zip(ESTIMATOR) {
        let mut i = 0usize;
        let mut kinds = [[0u32; 4]; 4]; // [kind][update code]
        run_estimator(run, |got: EstRec| {
            match want.get(i) {
                Some(w) if *w == got => {}
                Some(w) => m.fail(format_args!("{} call #{i}: got {:?}, host {:?}", run.name, got, w)),
                None => m.fail(format_args!("{} call #{i}: more calls than the host made", run.name)),
            }
            if let Some(k) = kinds.get_mut(usize::from(got.0)).and_then(|k| k.get_mut(usize::from(got.1))) {
                *k += 1;
            }
            i += 1;
        });
        if i != want.len() {
            m.fail(format_args!("{}: {} calls, the host made {}", run.name, i, want.len()));
        }
        println!(
            "      {}: {} calls bit-exact: {} predicts; lidar accepted/outlier/unusable {}/{}/{}; compass accepted/outlier {}/{}",
            run.name,
            i,
            kinds[0][0],
            kinds[1][1] + kinds[2][1],
            kinds[1][2] + kinds[2][2],
            kinds[1][3] + kinds[2][3],
            kinds[3][1],
            kinds[3][2]
        );
    }
    m.result("the lx106 estimator differs from the host build")
}
