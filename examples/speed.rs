use stacked_live_load::*;
fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(2);
    let mut p = Params::default();
    p.n_blocks = n;
    for j in 2..n {
        p.alpha[j] = 0.25 / j as f64;
        p.mus[j] = 0.05;
        p.muk[j] = 0.05;
    }
    let path = std::path::Path::new("../shared/ground_motions/RSN787_LOMAP_SLC270.AT2");
    let gm = GroundMotion::read(path, 9.81).unwrap();
    let gm = GroundMotion {
        time: gm.time[..4001].to_vec(),
        accel: gm.accel[..4001].to_vec(),
    };
    let reps = 300;
    let t = std::time::Instant::now();
    let mut st = Stats::default();
    for _ in 0..reps {
        let mut sim = Simulator::new(&p, &Settings::default()).unwrap();
        record::run(&mut sim, &gm, 1.0).unwrap();
        st = sim.stats();
        std::hint::black_box(sim.outputs());
    }
    let el = t.elapsed().as_secs_f64() / reps as f64;
    println!(
        "N={n}: {:.3} ms per sim, {:?}, {:.1} ns/step",
        el * 1e3,
        st,
        el * 1e9 / st.steps as f64
    );
}
