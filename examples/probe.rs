#[path = "../tests/common/mod.rs"]
mod common;
use common::*;
use stacked_live_load::*;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rec = args
        .get(1)
        .map(|s| s.as_str())
        .unwrap_or("RSN6_IMPVALL.I_I-ELC180.AT2");
    let secs: f64 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(20.0);
    let p = Params::default();
    let gm = truncate(&read_shared(rec, p.g), secs);
    let t = std::time::Instant::now();
    let ex = Exact::new(&p).run(&gm, 16);
    println!(
        "exact: peak u0 {:.12e} slips {:?} events {} ({:?})",
        ex.peak_u0,
        ex.peak_slip,
        ex.events,
        t.elapsed()
    );
    for ms in [0.0, 0.01, 0.005, 0.0025, 0.00125, 0.000625] {
        for method in [Method::EventLocated, Method::StepEnd] {
            let s = Settings {
                method,
                max_step: ms,
            };
            let mut sim = Simulator::new(&p, &s).unwrap();
            let t = std::time::Instant::now();
            record::run(&mut sim, &gm, 1.0).unwrap();
            let el = t.elapsed();
            let o = sim.outputs();
            println!("{:?} h={} : peak_u0 rel {:.2e} slip1 {:.2e} slip2 {:.2e} final u0 diff {:.2e} Eres {:.2e} ev {} stats {:?} {:?}",
                method, sim.max_internal_step(), rel(o.peak_up, ex.peak_u0), rel(o.peak_slip[0], ex.peak_slip[0]), rel(o.peak_slip[1], ex.peak_slip[1]),
                (o.up - ex.u[0]).abs()/ex.peak_u0, o.energy_residual()/o.e_input, o.n_events, sim.stats(), el);
        }
    }
}
