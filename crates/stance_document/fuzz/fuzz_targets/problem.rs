//! The problem-file reader (`Problem::from_json`, what `stance solve`, `stance bench
//! --problem` and `stance comfort` read) on arbitrary text. Must never panic; every error
//! must say something. A problem that loads gets its closed-form limb starts, a few solver
//! iterations and the solution's JSON (joints, posture, report with the comfort).
//!
//! Seeds: `fuzz/seeds/problem/` (written by `cargo test -p stance_document --test all fuzz_seeds::
//! -- --ignored`).
#![no_main]

#[path = "../common/solve_briefly.rs"]
mod solve_briefly;

use libfuzzer_sys::fuzz_target;
use stance_document::Problem;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let problem = match Problem::from_json(&text) {
        Ok(problem) => problem,
        Err(e) => {
            assert!(!e.to_string().trim().is_empty(), "empty error: {e:?}");
            return;
        }
    };
    solve_briefly::solve_briefly(&problem);
});
