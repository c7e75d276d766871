#[path = "../tests/common/mod.rs"]
mod common;
use common::*;
use stacked_live_load::*;
fn main() {
    let gm = scaled_to_pga(&read_shared("Rinaldi228.AT2", 9.81), 0.6 * 9.81);
    let mut p = Params::default();
    p.n_blocks = 8;
    for j in 0..8 {
        p.alpha[j] = 0.05 + 0.04 * ((j * 5) % 8) as f64;
        // Friction falls upwards, so that every interface gets to slip.
        p.muk[j] = 0.25 - 0.025 * j as f64;
        p.mus[j] = p.muk[j] * if j % 2 == 0 { 1.0 } else { 1.3 };
    }
    println!("alpha {:?}\nmus {:?}\nmuk {:?}", p.alpha, p.mus, p.muk);
    let ex = Exact::new(&p).run(&gm, 16);
    let mut s = Simulator::new(&p, &Settings::default()).unwrap();
    let mut last = *s.mode();
    run_sampled(&mut s, &gm, |s| {
        if *s.mode() != last && s.time() < 3.5 {
            println!("engine t={:.3} {:?}", s.time(), &s.mode().contact[1..9]);
            last = *s.mode();
        }
    });
    let o = s.outputs();
    println!(
        "engine {:?} ev {}\nexact  {:?} ev {}",
        &o.peak_slip[..8],
        o.n_events,
        ex.peak_slip,
        ex.events
    );
}
