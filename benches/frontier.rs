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

fn simulate(p: &Params, gm: &GroundMotion) -> Simulator {
    let mut sim = Simulator::new(p, &Settings::default()).unwrap();
    record::run(&mut sim, gm, 1.0).unwrap();
    sim
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
    (common::median(engine), common::median(floor))
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

/// Median seconds per simulation of the two-block scene driven with the
/// record's samples as inputs with slopes — one `advance` per sample, as a
/// co-simulation master drives the FMU, and all of them as pieces in one
/// `advance_pieces` call (the engine's own work on such inputs) — and
/// through the record path, timed alternately: `[per call, in one call,
/// record]`.
fn timed_inputs(p: &Params, gm: &GroundMotion, rounds: usize, reps: usize) -> [f64; 3] {
    let pieces = common::record_pieces(gm);
    let per_call = || {
        let mut sim = Simulator::new(p, &Settings::default()).unwrap();
        for (t1, exc) in &pieces {
            sim.advance(*t1, exc).unwrap();
        }
        sim.outputs().peak_up
    };
    let one_call = || {
        let mut sim = Simulator::new(p, &Settings::default()).unwrap();
        sim.advance_pieces(pieces.iter().copied()).unwrap();
        sim.outputs().peak_up
    };
    let record = || simulate(black_box(p), gm).outputs().peak_up;
    let mut times = [Vec::new(), Vec::new(), Vec::new()];
    for _ in 0..rounds {
        for (way, run) in [&per_call as &dyn Fn() -> f64, &one_call, &record]
            .into_iter()
            .enumerate()
        {
            let t = Instant::now();
            for _ in 0..reps {
                black_box(run());
            }
            times[way].push(t.elapsed().as_secs_f64() / reps as f64);
        }
    }
    times.map(common::median)
}

fn main() {
    // `cargo test --benches` runs benches with `--test`: a smoke run only.
    let smoke = std::env::args().any(|a| a == "--test");
    let rounds: usize = std::env::var("ROUNDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(if smoke { 1 } else { 11 });
    let reps = if smoke { 1 } else { 20 };
    // The shipped record (or RECORD=path) and two broadband records
    // generated from seeds the engine was never tuned on.
    let mut records = vec![("shipped".to_string(), record_20s())];
    for seed in [0xb0ad1e_u64, 0xf1e1d5e] {
        let mut rng = common::Rng(seed);
        let gm = common::broadband_record(&mut rng, 20.0, 0.005);
        records.push((format!("broadband {seed:#x}"), gm));
    }
    let mut scenes: Vec<(String, Params)> = vec![
        ("bare structure (N = 0)".into(), common::graded_stack(0)),
        ("N = 1".into(), common::graded_stack(1)),
        ("two-block scene (paper)".into(), common::graded_stack(2)),
        ("N = 4".into(), common::graded_stack(4)),
        ("N = 8".into(), common::graded_stack(8)),
        (
            "N = 8, mus > muk".into(),
            common::graded_stack_static_above_kinetic(),
        ),
    ];
    // One block that never slides, to price a switch against (same record).
    let mut rigid = common::graded_stack(1);
    rigid.mus[0] = 10.0;
    rigid.muk[0] = 10.0;
    scenes.push(("N = 1, never slides".into(), rigid));
    let copy = common::engine_copy_from_env();
    println!("{rounds} rounds of {reps} simulations, medians; floor: the exact recurrence of the bare structure; the engine's {copy} copy");
    for (r, (label, gm)) in records.iter().enumerate() {
        println!(
            "\n{label}: {} samples at {} s",
            gm.time.len(),
            gm.time[1] - gm.time[0]
        );
        println!(
            "{:<28} {:>9} {:>9} {:>7} {:>7} {:>8} {:>9} {:>9}",
            "scene", "median", "floor", "ratio", "events", "steps", "peaks", "energy"
        );
        // Warm-up, untimed (the first scene measured otherwise ran up to
        // 1.5x slower in some runs while the machine came out of idle).
        if !smoke {
            timed(&scenes[0].1, gm, 5, reps);
        }
        let mut per_step = Vec::new();
        for (name, p) in &scenes {
            let (t, floor) = timed(p, gm, rounds, reps);
            let sim = simulate(p, gm);
            let st = sim.stats();
            // Errors against the exact reference on the first record only
            // (the reference is slow; the tests cover the others).
            let (peak, energy) = if smoke || r > 0 {
                (f64::NAN, f64::NAN)
            } else {
                errors(p, gm)
            };
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
        let ((t_slide, events), (t_rigid, _)) = (per_step[1], per_step[6]);
        if events > 0 {
            println!(
                "one stick/slip switch (N = 1 minus N = 1 never sliding, per switch): {:.2} us",
                (t_slide - t_rigid) / events as f64 * 1e6
            );
        }
        let [per_call, one_call, by_record] = timed_inputs(&scenes[2].1, gm, rounds, reps);
        println!(
            "two-block scene, the samples as inputs with slopes / the record path: one call per sample {:.2}x, all in one call {:.2}x ({:.1} us, {:.1} us / {:.1} us)",
            per_call / by_record,
            one_call / by_record,
            per_call * 1e6,
            one_call * 1e6,
            by_record * 1e6
        );
    }
    println!("\ntargets: bare <= 3x the floor, two blocks <= 6x, eight blocks <= 12x; inputs per step no dearer than the record; peaks and energy <= 1e-9");
}
