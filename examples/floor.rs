//! The physical floor for a record, for `scripts/accuracy_speed.py`: median
//! seconds of the exact Nigam–Jennings recurrence of a bare SDOF over the
//! record's samples (a 2x2 affine map per sample), 31 rounds.
//!
//! `cargo run --release --example floor -- RECORD [Tp] [zeta]`
use stacked_live_load::{physics::sdof, GroundMotion};
use std::hint::black_box;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let gm = GroundMotion::read(std::path::Path::new(&args[1]), 9.81).expect("a readable record");
    let tp: f64 = args.get(2).map_or(0.5, |s| s.parse().unwrap());
    let zeta: f64 = args.get(3).map_or(0.05, |s| s.parse().unwrap());
    let (omega, dt) = (2.0 * std::f64::consts::PI / tp, gm.time[1] - gm.time[0]);
    let reps = (400_000 / gm.accel.len()).max(1);
    let mut rounds: Vec<f64> = (0..31)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..reps {
                black_box(sdof::response(omega, zeta, dt, black_box(&gm.accel)));
            }
            t.elapsed().as_secs_f64() / reps as f64
        })
        .collect();
    rounds.sort_by(|a, b| a.total_cmp(b));
    println!("{:.9e}", rounds[15]);
}
