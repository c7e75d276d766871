use stacked_live_load::*;
fn main() {
    let p = Params::default();
    let dt = 0.005;
    let n = 4001;
    let acc: Vec<f64> = (0..n)
        .map(|i| {
            let t = i as f64 * dt;
            3.0 * (2.0 * t).sin() * (7.3 * t).sin() + 1.5 * (13.1 * t).cos() * (t / 4.0).min(1.0)
        })
        .collect();
    let gm = GroundMotion::uniform(dt, acc);
    let reps = 200;
    let t = std::time::Instant::now();
    let mut steps = 0;
    for _ in 0..reps {
        let mut sim = Simulator::new(&p, &Settings::default()).unwrap();
        record::run(&mut sim, &gm, 1.0).unwrap();
        steps = sim.stats().steps;
        std::hint::black_box(sim.outputs());
    }
    let el = t.elapsed().as_secs_f64() / reps as f64;
    println!(
        "{:.3} ms per sim, {} steps, {:.1} ns/step",
        el * 1e3,
        steps,
        el * 1e9 / steps as f64
    );
}
