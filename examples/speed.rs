//! Times one 20 s simulation (for profiling; the figures are `cargo bench`'s).
//! `cargo run --release --example speed -- N`; `RIGID=1` keeps block 1 stuck.
use stacked_live_load::ground::{record, synthetic};
use stacked_live_load::physics::sdof;
use stacked_live_load::*;
fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(2);
    let mut p = Params {
        n_blocks: n,
        ..Params::default()
    };
    // RIGID=1: the lowest block never slides (mu 10), to price a switch
    // against the same run with it sliding (as the frontier bench does).
    if std::env::var("RIGID").is_ok_and(|v| v == "1") {
        p.mus[0] = 10.0;
        p.muk[0] = 10.0;
    }
    // RECORD=path: a record file instead of the embedded default (first 20 s).
    let gm = match std::env::var("RECORD") {
        Ok(path) => {
            let gm = GroundMotion::read(std::path::Path::new(&path), 9.81).unwrap();
            let n = gm.time.iter().take_while(|&&t| t <= 20.0 + 1e-9).count();
            GroundMotion {
                time: gm.time[..n].to_vec(),
                accel: gm.accel[..n].to_vec(),
            }
        }
        Err(_) => synthetic::default_record(),
    };
    let reps: usize = std::env::var("REPS")
        .ok()
        .map(|s| s.parse().unwrap())
        .unwrap_or(300);
    let t = std::time::Instant::now();
    let mut st = Stats::default();
    for _ in 0..reps {
        let mut sim = Simulator::new(&p, &Settings::default()).unwrap();
        record::run(&mut sim, &gm, 1.0).unwrap();
        st = sim.stats();
        std::hint::black_box(sim.outputs());
    }
    let el = t.elapsed().as_secs_f64() / reps as f64;
    // The physical floor in the same run: the exact Nigam–Jennings
    // recurrence of the bare structure over the same samples.
    let dt = gm.time[1] - gm.time[0];
    let t = std::time::Instant::now();
    for _ in 0..reps {
        std::hint::black_box(sdof::response(
            2.0 * std::f64::consts::PI / p.tp,
            p.zeta,
            dt,
            std::hint::black_box(&gm.accel),
        ));
    }
    let floor = t.elapsed().as_secs_f64() / reps as f64;
    println!(
        "N={n}: {:.3} ms per sim ({:.1}x the floor, {:.1} us), {} steps, {} events, {:.1} ns/step",
        el * 1e3,
        el / floor,
        floor * 1e6,
        st.steps,
        st.events,
        el * 1e9 / st.steps as f64
    );
}
