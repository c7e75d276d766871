//! Engine benchmarks (issue #2): one simulation of a 20 s record sampled at
//! 0.005 s with default accuracy, for the paper's 2-block scene and for
//! N = 0, 1, 4, 8; the step-end baseline; and, as a machine-independent
//! yardstick measured in the same run, the exact Nigam–Jennings recurrence
//! of the bare structure over the same samples.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use stacked_live_load::{
    ground::record, physics::sdof, GroundMotion, Method, Params, Settings, Simulator,
};
use std::path::PathBuf;

fn record_20s() -> GroundMotion {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/ground_motions/RSN787_LOMAP_SLC270.AT2");
    let gm = GroundMotion::read(&path, 9.81).expect("the benchmark reads ../shared/ground_motions");
    let n = 4001; // 20 s at 0.005 s
    GroundMotion {
        time: gm.time[..n].to_vec(),
        accel: gm.accel[..n].to_vec(),
    }
}

fn scene(n: usize) -> Params {
    let mut p = Params {
        n_blocks: n,
        ..Params::default()
    };
    for j in 2..n {
        p.alpha[j] = 0.25 / j as f64;
        p.mus[j] = 0.05;
        p.muk[j] = 0.05;
    }
    p
}

fn simulate(p: &Params, settings: &Settings, gm: &GroundMotion) -> f64 {
    let mut sim = Simulator::new(p, settings).unwrap();
    record::run(&mut sim, gm, 1.0).unwrap();
    sim.outputs().peak_up
}

fn benches(c: &mut Criterion) {
    let gm = record_20s();
    let mut g = c.benchmark_group("20 s record at 0.005 s");
    g.bench_function("baseline: Nigam-Jennings bare SDOF", |b| {
        let w = 2.0 * std::f64::consts::PI / 0.5;
        b.iter(|| sdof::response(w, 0.05, 0.005, black_box(&gm.accel)))
    });
    let default = Settings::default();
    g.bench_function("2-block scene, default accuracy", |b| {
        b.iter(|| simulate(&scene(2), &default, black_box(&gm)))
    });
    for n in [0, 1, 4, 8] {
        g.bench_function(format!("N = {n}, default accuracy"), |b| {
            b.iter(|| simulate(&scene(n), &default, black_box(&gm)))
        });
    }
    let step_end = Settings {
        method: Method::StepEnd,
        ..Settings::default()
    };
    g.bench_function("2-block scene, step-end switching, same steps", |b| {
        b.iter(|| simulate(&scene(2), &step_end, black_box(&gm)))
    });
    g.finish();
}

criterion_group!(engine, benches);
criterion_main!(engine);
