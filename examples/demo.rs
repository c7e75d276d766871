//! The engine alone on the embedded default record: the paper's Fig. 5a
//! scene, and the rigid and single-block configurations for comparison.

use stacked_live_load::{ground::record, ground::synthetic, Params, Settings, Simulator};

fn main() {
    let stack = Params::default();
    let gm = synthetic::default_record();
    let mut single = stack.clone();
    single.n_blocks = 1;
    single.alpha[0] = stack.alpha[0] + stack.alpha[1];
    let mut rigid = stack.clone();
    for j in 0..2 {
        rigid.mus[j] = 1e6;
        rigid.muk[j] = 1e6;
    }
    println!(
        "Embedded record: {:.0} s at {} s, PGA {:.2} m/s2",
        gm.duration(),
        gm.time[1],
        gm.pga()
    );
    let mut peaks = vec![];
    for (name, p) in [("stack", &stack), ("single", &single), ("rigid", &rigid)] {
        let mut sim = Simulator::new(p, &Settings::default()).expect("valid scene");
        record::run(&mut sim, &gm, 1.0).expect("finite record");
        let o = sim.outputs();
        println!(
            "{name:7} peak |up| {:.4} m  peak slips {:?} m  events {:4}  energy residual {:.1e} of input",
            o.peak_up,
            o.peak_slip[..p.n_blocks].iter().map(|s| (s * 1e4).round() / 1e4).collect::<Vec<_>>(),
            o.n_events,
            o.energy_residual() / o.e_input
        );
        peaks.push(o.peak_up);
    }
    println!(
        "DRR1 = stack / rigid = {:.4}   DRR2 = single / rigid = {:.4}",
        peaks[0] / peaks[2],
        peaks[1] / peaks[2]
    );
}
