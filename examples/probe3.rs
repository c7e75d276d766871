#[path = "../tests/common/mod.rs"]
mod common;
use common::*;
use stacked_live_load::*;
fn main() {
    let p = Params::default();
    let gm = truncate(&read_shared("RSN6_IMPVALL.I_I-ELC180.AT2", p.g), 3.0);
    let mut sim = Simulator::new(&p, &Settings::default()).unwrap();
    let mut last = *sim.mode();
    for i in 1..gm.time.len() {
        record::advance_with_record(&mut sim, gm.time[i], &gm, 1.0, &Excitation::default())
            .unwrap();
        if *sim.mode() != last {
            let o = sim.outputs();
            println!(
                "engine t={:.3} {:?} -> {:?} v {:.4e} {:.4e} {:.4e}",
                o.t,
                &last.contact[1..3],
                &sim.mode().contact[1..3],
                o.vp,
                o.vb[0],
                o.vb[1]
            );
            last = *sim.mode();
        }
    }
    let ex = Exact::new(&p).run(&gm, 16);
    println!("exact events {}", ex.events);
}
