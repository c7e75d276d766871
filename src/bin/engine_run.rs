//! Runs the engine (no FMU) on a record and prints peaks as JSON: the
//! reference the fmpy tests compare the FMU with.
//!
//! engine_run RECORD [--hold] [--scale S] [--g G]
//!   --hold: the record is held constant over each sample interval (what an
//!           importer without input derivatives gives); default: linear.
use stacked_live_load::{ground::record, Excitation, GroundMotion, Params, Settings, Simulator};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .map(|i| args[i + 1].parse::<f64>().expect("a number"))
    };
    let path = args
        .first()
        .expect("usage: engine_run RECORD [--hold] [--scale S] [--g G]");
    let g = value("--g").unwrap_or(9.81);
    let scale = value("--scale").unwrap_or(1.0);
    let gm = GroundMotion::read(std::path::Path::new(path), g).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(1)
    });
    let mut sim = Simulator::new(&Params::default(), &Settings::default()).unwrap();
    if args.iter().any(|a| a == "--hold") {
        for (w, &a) in gm.time.windows(2).zip(&gm.accel) {
            let exc = Excitation {
                ag: scale * a,
                ..Default::default()
            };
            sim.advance(w[1], &exc).unwrap();
        }
    } else {
        record::run(&mut sim, &gm, scale).unwrap();
    }
    let o = sim.outputs();
    println!(
        "{{\"t\": {:?}, \"up\": {:?}, \"peakUp\": {:?}, \"peakSlip\": [{:?}, {:?}], \"nEvents\": {}}}",
        o.t, o.up, o.peak_up, o.peak_slip[0], o.peak_slip[1], o.n_events
    );
}
