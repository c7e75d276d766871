//! Issue #14's benchmark: the default settings against the physical floor,
//! measured in the same run, and against the exact reference.
//!
//! The floor is the exact Nigam–Jennings recurrence of the bare structure
//! over the same record (`sdof::response`, a 2x2 affine map per sample).
//! Each scene and the floor are timed alternately, `ROUNDS` rounds of
//! `REPS` simulations each, and the medians are compared, so that the
//! machine's load moves both alike. The errors are those of the default
//! settings against `tests/common`'s exact event-driven reference (matrix
//! exponential per mode, events by bisection): peak |u0| and slips relative
//! to the peak, and the energy residual relative to the input energy, at
//! the end of the timed run (the whole record in one call) and at every
//! sample of the record taken one sample per call; the worse of the two.
//!
//! `cargo bench --bench frontier` (about a minute); `RECORD=path` another
//! record (its first 20 s), `ROUNDS=n` more rounds.

#[path = "../tests/common/mod.rs"]
mod common;

use stacked_live_load::{ground::record, physics::sdof, GroundMotion, Params, Settings, Simulator};
use std::hint::black_box;
use std::time::Instant;

fn record_20s() -> GroundMotion {
    let path = std::env::var("RECORD")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|_| common::shared_record("RSN787_LOMAP_SLC270.AT2"));
    let gm = GroundMotion::read(&path, 9.81).expect("the benchmark reads ../shared/ground_motions");
    common::truncate(&gm, 20.0)
}

/// The paper's stack, and N blocks with
/// lighter, less rough blocks higher up.
fn scene(n: usize) -> Params {
    let mut p = Params::default();
    p.n_blocks = n;
    for j in 2..n {
        p.alpha[j] = 0.25 / j as f64;
        // Friction falling upwards, never equal to the one below (equal
        // coefficients make a riding block's stick force exactly mus N,
        // where stuck and sliding are both consistent).
        p.mus[j] = 0.05 - 0.004 * (j - 1) as f64;
        p.muk[j] = p.mus[j];
    }
    p
}

fn simulate(p: &Params, gm: &GroundMotion) -> Simulator {
    let mut sim = Simulator::new(p, &Settings::default()).unwrap();
    record::run(&mut sim, gm, 1.0).unwrap();
    sim
}

fn median(mut x: Vec<f64>) -> f64 {
    x.sort_by(|a, b| a.total_cmp(b));
    x[x.len() / 2]
}

/// Median seconds per simulation of `p` and of the floor, timed alternately.
fn timed(p: &Params, gm: &GroundMotion, rounds: usize, reps: usize) -> (f64, f64) {
    let dt = gm.time[1] - gm.time[0];
    let omega = 2.0 * std::f64::consts::PI / p.tp;
    let (mut engine, mut floor) = (Vec::new(), Vec::new());
    for _ in 0..rounds {
        let t = Instant::now();
        for _ in 0..reps {
            black_box(simulate(black_box(p), gm).outputs().peak_up);
        }
        engine.push(t.elapsed().as_secs_f64() / reps as f64);
        let t = Instant::now();
        for _ in 0..reps {
            black_box(sdof::response(omega, p.zeta, dt, black_box(&gm.accel)));
        }
        floor.push(t.elapsed().as_secs_f64() / reps as f64);
    }
    (median(engine), median(floor))
}

/// Errors of the default settings against the exact reference: the timed
/// run (the whole record in one call) and the same record taken one sample
/// per call, whose energy residual is checked at every sample; the worse
/// of the two.
fn errors(p: &Params, gm: &GroundMotion) -> (f64, f64) {
    let exact = common::Exact::new(p).run(gm, 16);
    let peak_error = |s: &Simulator| {
        let o = s.outputs();
        let mut peak = common::rel(o.peak_up, exact.peak_u0);
        for j in 0..p.n_blocks {
            let scale = exact.peak_slip[j].max(exact.peak_u0);
            peak = peak.max((o.peak_slip[j] - exact.peak_slip[j]).abs() / scale);
        }
        peak
    };
    let whole = simulate(p, gm);
    let o = whole.outputs();
    let whole_energy = o.energy_residual().abs() / o.e_input.abs();
    let mut s = Simulator::new(p, &Settings::default()).unwrap();
    let (mut residual, mut input) = (0.0f64, 0.0f64);
    common::run_sampled(&mut s, gm, |s| {
        let o = s.outputs();
        input = input.max(o.e_input.abs());
        residual = residual.max(o.energy_residual().abs());
    });
    (
        peak_error(&whole).max(peak_error(&s)),
        whole_energy.max(residual / input),
    )
}

fn main() {
    // `cargo test --benches` runs benches with `--test`: a smoke run only.
    let smoke = std::env::args().any(|a| a == "--test");
    let gm = record_20s();
    let rounds: usize = std::env::var("ROUNDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(if smoke { 1 } else { 15 });
    let reps = if smoke { 1 } else { 40 };
    println!(
        "{} samples at {} s, {} rounds of {reps} simulations, medians",
        gm.time.len(),
        gm.time[1] - gm.time[0],
        rounds
    );
    println!(
        "{:<28} {:>9} {:>9} {:>7} {:>7} {:>8} {:>9} {:>9}",
        "scene", "median", "floor", "ratio", "events", "steps", "peaks", "energy"
    );
    let mut scenes: Vec<(String, Params)> = vec![
        ("bare structure (N = 0)".into(), scene(0)),
        ("N = 1".into(), scene(1)),
        ("two-block scene (paper)".into(), scene(2)),
        ("N = 4".into(), scene(4)),
        ("N = 8".into(), scene(8)),
    ];
    // One block that never slides, to price a switch against (same record).
    let mut rigid = scene(1);
    rigid.mus[0] = 10.0;
    rigid.muk[0] = 10.0;
    scenes.push(("N = 1, never slides".into(), rigid));
    // Warm-up, untimed (the first scene measured otherwise ran up to 1.5x
    // slower in some runs while the machine came out of idle).
    if !smoke {
        timed(&scenes[0].1, &gm, 5, reps);
    }
    let mut per_step = Vec::new();
    for (name, p) in &scenes {
        let (t, floor) = timed(p, &gm, rounds, reps);
        let sim = simulate(p, &gm);
        let st = sim.stats();
        let (peak, energy) = if smoke { (0.0, 0.0) } else { errors(p, &gm) };
        println!(
            "{name:<28} {:>6.1} us {:>6.1} us {:>6.2}x {:>7} {:>8} {:>9.1e} {:>9.1e}",
            t * 1e6,
            floor * 1e6,
            t / floor,
            st.events,
            st.steps,
            peak,
            energy
        );
        per_step.push((t, st.events));
    }
    // The cost of a switch: the sliding block's run minus the one that
    // never slides, per switch.
    let ((t_slide, events), (t_rigid, _)) = (per_step[1], per_step[5]);
    if events > 0 {
        println!(
            "one stick/slip switch (N = 1 minus N = 1 never sliding, per switch): {:.2} us",
            (t_slide - t_rigid) / events as f64 * 1e6
        );
    }
    println!("targets: bare <= 3x the floor, two-block scene <= 6x; peaks and energy <= 1e-9");
}
