//! Prints the time of one full prioritized iteration (the textbook iteration: every level
//! every iteration, as `stance bench` times it) and of one solve on S2..S5, natively and in
//! the browser: the same code, so that one `npm test` log gives the wasm/native ratio. A
//! measurement, not a check: no time is asserted (the figures vary with the machine).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use stance_hanim::scenarios;
use stance_ik::{Iteration, Solver, SolverSettings};

#[cfg(not(target_arch = "wasm32"))]
fn now_ms() -> f64 {
    use std::sync::OnceLock;
    use std::time::Instant;
    static START: OnceLock<Instant> = OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64() * 1e3
}

#[cfg(target_arch = "wasm32")]
fn now_ms() -> f64 {
    let performance = js_sys::Reflect::get(&js_sys::global(), &"performance".into()).unwrap();
    let now = js_sys::Reflect::get(&performance, &"now".into()).unwrap();
    js_sys::Function::from(now)
        .call0(&performance)
        .unwrap()
        .as_f64()
        .unwrap()
}

fn report(line: &str) {
    #[cfg(target_arch = "wasm32")]
    wasm_bindgen_test::console_log!("{line}");
    #[cfg(not(target_arch = "wasm32"))]
    println!("{line}");
}

/// Median of `runs` timings of `f` (ms each), each run repeated until it lasts 20 ms, after
/// `warm_ms` of warm-up (the browser compiles WebAssembly with a baseline compiler first and
/// optimises the hot functions later).
fn median_ms(runs: usize, warm_ms: f64, mut f: impl FnMut()) -> f64 {
    let start = now_ms();
    while now_ms() - start < warm_ms {
        f();
    }
    let mut samples: Vec<f64> = (0..runs)
        .map(|_| {
            let start = now_ms();
            let mut count = 0u32;
            while now_ms() - start < 20.0 {
                f();
                count += 1;
            }
            (now_ms() - start) / f64::from(count)
        })
        .collect();
    samples.sort_by(f64::total_cmp);
    samples[samples.len() / 2]
}

#[test]
fn scenario_timings() {
    let platform = if cfg!(target_arch = "wasm32") {
        "wasm"
    } else {
        "native"
    };
    let textbook = SolverSettings {
        iteration: Iteration::Textbook,
        restarts: false,
        ..SolverSettings::default()
    };
    let chosen: Vec<_> = scenarios::all()
        .unwrap()
        .into_iter()
        .filter(|s| ["S2", "S3", "S4", "S5"].contains(&s.name))
        .collect();
    // Every scenario's code paths warmed up before any is timed.
    for s in &chosen {
        let mut solver = Solver::default();
        median_ms(1, 400.0, || {
            let mut p = s.start.clone();
            solver.solve(&s.skeleton, &s.tasks, &mut p).unwrap();
        });
    }
    let mut timed = 0;
    for s in &chosen {
        let mut solver = Solver::new(textbook).unwrap();
        let per_iteration = median_ms(5, 100.0, || {
            let mut p = s.start.clone();
            solver.iterate(&s.skeleton, &s.tasks, &mut p).unwrap();
        });
        let mut solver = Solver::default();
        let per_solve = median_ms(3, 100.0, || {
            let mut p = s.start.clone();
            solver.solve(&s.skeleton, &s.tasks, &mut p).unwrap();
        });
        report(&format!(
            "timing {platform} {}: {:.1} us/iteration, {:.0} us/solve",
            s.name,
            per_iteration * 1e3,
            per_solve * 1e3
        ));
        timed += 1;
    }
    assert_eq!(timed, 4, "S2..S5 timed");
}
