//! One scene of the frontier bench, REPS times (for callgrind: take
//! (REPS=3 - REPS=1) / 2 to remove the set-up).
//! `cargo run --release --example prof -- SCENE RECORD` with SCENE one of
//! n0 n2 n8 n8s percall onecall floor, RECORD shipped | b1 | b2 | c1 | c2 | c3 | a path.
#[path = "../tests/common/mod.rs"]
#[allow(unused_imports)]
mod common;
use stacked_live_load::{ground::record, physics::sdof, Settings, Simulator};
use std::hint::black_box;

fn main() {
    common::engine_copy_from_env();
    let args: Vec<String> = std::env::args().collect();
    let scene = args.get(1).map_or("n8", |s| s.as_str());
    let rec = args.get(2).map_or("shipped", |s| s.as_str());
    let reps: usize = std::env::var("REPS").ok().map_or(1, |s| s.parse().unwrap());
    let gm = match rec {
        "shipped" => {
            let gm = stacked_live_load::GroundMotion::read(
                &common::shared_record("RSN787_LOMAP_SLC270.AT2"),
                9.81,
            )
            .unwrap();
            common::truncate(&gm, 20.0)
        }
        "b1" => common::broadband_record(&mut common::Rng(0xb0ad1e), 20.0, 0.005),
        "b2" => common::broadband_record(&mut common::Rng(0xf1e1d5e), 20.0, 0.005),
        // Coarse broadband records: c1 at 0.01 s, c2 and c3 at 0.02 s.
        "c1" | "c2" | "c3" => common::coarse_record(rec),
        // Any other record: a path, its first 20 s.
        path => common::truncate(
            &stacked_live_load::GroundMotion::read(path.as_ref(), 9.81).unwrap(),
            20.0,
        ),
    };
    let p = match scene {
        "n0" => common::graded_stack(0),
        "n2" | "percall" | "onecall" => common::graded_stack(2),
        "n8s" => common::graded_stack_static_above_kinetic(),
        _ => common::graded_stack(8),
    };
    let pieces = common::record_pieces(&gm);
    let mut events = 0;
    for _ in 0..reps {
        match scene {
            "floor" => {
                let omega = 2.0 * std::f64::consts::PI / p.tp;
                black_box(sdof::response(
                    omega,
                    p.zeta,
                    gm.time[1] - gm.time[0],
                    black_box(&gm.accel),
                ));
            }
            "percall" => {
                let mut sim = Simulator::new(&p, &Settings::default()).unwrap();
                for (t1, exc) in &pieces {
                    sim.advance(*t1, exc).unwrap();
                }
                events = sim.stats().events;
                if std::env::var("OUT").is_ok() {
                    println!("{:?}", sim.outputs());
                }
                black_box(sim.outputs());
            }
            "onecall" => {
                let mut sim = Simulator::new(&p, &Settings::default()).unwrap();
                sim.advance_pieces(pieces.iter().copied()).unwrap();
                events = sim.stats().events;
                black_box(sim.outputs());
            }
            _ => {
                let mut sim = Simulator::new(&p, &Settings::default()).unwrap();
                record::run(&mut sim, &gm, 1.0).unwrap();
                events = sim.stats().events;
                let st = sim.stats();
                eprintln!(
                    "steps {} events {} tries {}",
                    st.steps,
                    st.events,
                    (sim.work() - st.steps - 64 * st.events) / 2
                );
                if std::env::var("OUT").is_ok() {
                    println!("{:?}", sim.outputs());
                }
                black_box(sim.outputs());
            }
        }
    }
    println!("{scene} {rec}: {events} events");
}
