//! The cost of one stick/slip switch: one block sliding (N = 1) against the
//! same block that never slides (μ = 10), per switch, and the paper's
//! two-block scene, on the frontier bench's record (Loma Prieta SLC270,
//! first 20 s). Rounds alternate the scenes; each scene's figure is the
//! *minimum* over rounds of the mean of `REPS` simulations (interference from
//! other work on a shared machine only adds time), with the median beside
//! it. `cargo bench --bench switch`; `ROUNDS=n`, `RECORD=path`.

#[path = "../tests/common/mod.rs"]
mod common;

use stacked_live_load::{ground::record, physics::sdof, GroundMotion, Params, Settings, Simulator};
use std::hint::black_box;
use std::time::Instant;

fn simulate(p: &Params, gm: &GroundMotion) -> Simulator {
    let mut sim = Simulator::new(p, &Settings::default()).unwrap();
    record::run(&mut sim, gm, 1.0).unwrap();
    sim
}

fn main() {
    let smoke = std::env::args().any(|a| a == "--test");
    let path = std::env::var("RECORD")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|_| common::shared_record("RSN787_LOMAP_SLC270.AT2"));
    let gm = GroundMotion::read(&path, 9.81).expect("the benchmark reads ../shared/ground_motions");
    let gm = common::truncate(&gm, 20.0);
    let rounds: usize = std::env::var("ROUNDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(if smoke { 1 } else { 41 });
    let reps = if smoke { 1 } else { 20 };

    let mut one = Params::default();
    one.n_blocks = 1;
    let mut rigid = one.clone();
    rigid.mus[0] = 10.0;
    rigid.muk[0] = 10.0;
    let two = Params::default();
    let scenes = [
        ("N = 1", one),
        ("N = 1, never slides", rigid),
        ("two-block scene", two),
    ];
    let dt = gm.time[1] - gm.time[0];
    let omega = 2.0 * std::f64::consts::PI / Params::default().tp;

    let mut times = vec![Vec::new(); scenes.len() + 1];
    for _ in 0..rounds {
        for (k, (_, p)) in scenes.iter().enumerate() {
            let t = Instant::now();
            for _ in 0..reps {
                black_box(simulate(black_box(p), &gm).outputs().peak_up);
            }
            times[k].push(t.elapsed().as_secs_f64() / reps as f64);
        }
        let t = Instant::now();
        for _ in 0..reps {
            black_box(sdof::response(omega, 0.05, dt, black_box(&gm.accel)));
        }
        times[scenes.len()].push(t.elapsed().as_secs_f64() / reps as f64);
    }
    let stats = |x: &[f64]| {
        let mut x = x.to_vec();
        x.sort_by(|a, b| a.total_cmp(b));
        (x[0], x[x.len() / 2])
    };
    let (floor_min, floor_median) = stats(&times[scenes.len()]);
    println!(
        "{} samples, {rounds} rounds of {reps} simulations; floor {:.1} us (min), {:.1} us (median)",
        gm.time.len(),
        floor_min * 1e6,
        floor_median * 1e6
    );
    let mut summary = Vec::new();
    for (k, (name, p)) in scenes.iter().enumerate() {
        let (min, median) = stats(&times[k]);
        let events = simulate(p, &gm).stats().events;
        println!(
            "{name:<22} min {:>7.1} us ({:>5.2}x floor)  median {:>7.1} us  {events} switches",
            min * 1e6,
            min / floor_min,
            median * 1e6
        );
        summary.push((min, median, events));
    }
    let ((one_min, one_median, events), (rigid_min, rigid_median, _)) = (summary[0], summary[1]);
    if events > 0 {
        println!(
            "one stick/slip switch (N = 1 minus never sliding, per switch): {:.2} us (min), {:.2} us (median)",
            (one_min - rigid_min) / events as f64 * 1e6,
            (one_median - rigid_median) / events as f64 * 1e6
        );
    }
}
