#[path = "../tests/common/mod.rs"]
mod common;
use common::*;
use stacked_live_load::*;
fn run(p: &Params, gm: &GroundMotion, label: &str) {
    let ex = Exact::new(p).run(gm, 16);
    let mut sim = Simulator::new(p, &Settings::default()).unwrap();
    record::run(&mut sim, gm, 1.0).unwrap();
    let o = sim.outputs();
    println!("{label}: exact u0 {:.6e} ev {} | engine {:.6e} ev {} rel {:.2e} slip {:?} vs {:?} stats {:?}", ex.peak_u0, ex.events, o.peak_up, o.n_events, rel(o.peak_up, ex.peak_u0), &o.peak_slip[..p.n_blocks], ex.peak_slip, sim.stats());
}
fn main() {
    let base = Params::default();
    let gm = truncate(&read_shared("RSN6_IMPVALL.I_I-ELC180.AT2", base.g), 10.0);
    // NJ for bare
    let w = 2.0 * std::f64::consts::PI / base.tp;
    let nj = sdof::response(w, base.zeta, 0.01, &gm.accel);
    println!(
        "NJ bare peak {:.6e}",
        nj.iter().fold(0.0f64, |m, x| m.max(x.abs()))
    );
    let mut p = base.clone();
    p.n_blocks = 0;
    run(&p, &gm, "N=0");
    let mut p = base.clone();
    p.n_blocks = 1;
    p.mus[0] = 100.0;
    p.muk[0] = 100.0;
    run(&p, &gm, "N=1 mu=100");
    let mut p = base.clone();
    p.n_blocks = 1;
    p.mus[0] = 0.0;
    p.muk[0] = 0.0;
    run(&p, &gm, "N=1 mu=0");
    let mut p = base.clone();
    p.n_blocks = 1;
    run(&p, &gm, "N=1 mu=0.1");
    let mut p = base.clone();
    p.n_blocks = 2;
    p.mus[1] = 100.0;
    p.muk[1] = 100.0;
    run(&p, &gm, "N=2 mu2=100");
    let mut p = base.clone();
    run(&p, &gm, "N=2 default");
    p.mus[1] = 0.3;
    p.muk[1] = 0.3;
    run(&p, &gm, "N=2 mu2=.3");
}
