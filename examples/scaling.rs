//! Cost of one simulation at default settings as the problem grows (issue
//! #14, item 4), as CSV on stdout for `scripts/scaling.py`:
//! `sweep,x,engine_us,floor_us,events,steps`. Each point is the median of
//! `ROUNDS` rounds timed alternately with the physical floor (the
//! Nigam–Jennings recurrence of the bare structure over the same samples).
//!
//! Sweeps, on the broadband synthetic record at 0.005 s (0.4 g):
//! - `length`: record length 5–80 s, the paper's two-block scene;
//! - `period`: Tp 0.02–5 s (dt ω from 1.6 down to 0.006), the bare structure;
//! - `events`: the single block's friction from 0.02 to 1 (more switches as
//!   it falls), 20 s;
//! - `height`: 0 to 8 blocks (`common::graded_stack`, the frontier bench's scenes), 20 s.

#[path = "../tests/common/mod.rs"]
mod common;

use stacked_live_load::ground::{record, synthetic};
use stacked_live_load::physics::sdof;
use stacked_live_load::*;
use std::hint::black_box;
use std::time::Instant;

fn point(sweep: &str, x: f64, p: &Params, gm: &GroundMotion, rounds: usize) {
    let reps = (200_000 / gm.time.len()).max(3);
    let dt = gm.time[1] - gm.time[0];
    let omega = 2.0 * std::f64::consts::PI / p.tp;
    let (mut engine, mut floor) = (Vec::new(), Vec::new());
    let mut stats = Stats::default();
    for _ in 0..rounds {
        let t = Instant::now();
        for _ in 0..reps {
            let mut sim = Simulator::new(black_box(p), &Settings::default()).unwrap();
            record::run(&mut sim, gm, 1.0).unwrap();
            stats = sim.stats();
            black_box(sim.outputs().peak_up);
        }
        engine.push(t.elapsed().as_secs_f64() / reps as f64);
        let t = Instant::now();
        for _ in 0..reps {
            black_box(sdof::response(omega, p.zeta, dt, black_box(&gm.accel)));
        }
        floor.push(t.elapsed().as_secs_f64() / reps as f64);
    }
    println!(
        "{sweep},{x},{:.3},{:.3},{},{}",
        common::median(engine) * 1e6,
        common::median(floor) * 1e6,
        stats.events,
        stats.steps
    );
}

fn main() {
    let rounds: usize = std::env::var("ROUNDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(7);
    println!("sweep,x,engine_us,floor_us,events,steps");
    for seconds in [5.0, 10.0, 20.0, 40.0, 80.0] {
        let gm = synthetic::broadband(seconds, 0.005, 0.4 * 9.81);
        point("length", seconds, &common::graded_stack(2), &gm, rounds);
    }
    let gm = synthetic::broadband(20.0, 0.005, 0.4 * 9.81);
    for tp in [0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0] {
        let mut p = common::graded_stack(0);
        p.tp = tp;
        point("period", tp, &p, &gm, rounds);
    }
    for mu in [0.02, 0.05, 0.1, 0.2, 0.4, 1.0] {
        let mut p = common::graded_stack(1);
        p.mus[0] = mu;
        p.muk[0] = mu;
        point("events", mu, &p, &gm, rounds);
    }
    for n in 0..=8 {
        point("height", n as f64, &common::graded_stack(n), &gm, rounds);
    }
}
