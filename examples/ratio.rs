//! The frontier bench's ratio for a few scenes (quicker than the bench):
//! `cargo run --release --example ratio -- n8 n2 percall onecall` (ROUNDS, REPS;
//! RECORDS=path:path other records, their first 20 s, or c1 c2 c3).
#[path = "../tests/common/mod.rs"]
#[allow(unused_imports)]
mod common;
use stacked_live_load::{ground::record, physics::sdof, Settings, Simulator};
use std::hint::black_box;
use std::time::Instant;

fn main() {
    common::engine_copy_from_env();
    let rounds: usize = std::env::var("ROUNDS")
        .ok()
        .map_or(11, |s| s.parse().unwrap());
    let reps: usize = std::env::var("REPS")
        .ok()
        .map_or(20, |s| s.parse().unwrap());
    let scenes: Vec<String> = std::env::args().skip(1).collect();
    let read = |path: &std::path::Path| {
        let gm = stacked_live_load::GroundMotion::read(path, 9.81).unwrap();
        common::truncate(&gm, 20.0)
    };
    // RECORDS=path:path... other records (their first 20 s) instead.
    let records: Vec<(String, stacked_live_load::GroundMotion)> = match std::env::var("RECORDS") {
        Ok(paths) => paths
            .split(':')
            .map(|p| {
                if matches!(p, "c1" | "c2" | "c3") {
                    return (p.to_string(), common::coarse_record(p));
                }
                let path = std::path::Path::new(p);
                let name = path.file_stem().unwrap().to_string_lossy().into_owned();
                (name, read(path))
            })
            .collect(),
        Err(_) => vec![
            (
                "shipped".into(),
                read(&common::shared_record("RSN787_LOMAP_SLC270.AT2")),
            ),
            (
                "b1".into(),
                common::broadband_record(&mut common::Rng(0xb0ad1e), 20.0, 0.005),
            ),
            (
                "b2".into(),
                common::broadband_record(&mut common::Rng(0xf1e1d5e), 20.0, 0.005),
            ),
        ],
    };
    for (name, gm) in &records {
        for scene in &scenes {
            let p = match scene.as_str() {
                "n0" => common::graded_stack(0),
                "n8s" => common::graded_stack_static_above_kinetic(),
                "n8" => common::graded_stack(8),
                _ => common::graded_stack(2),
            };
            let pieces = common::record_pieces(gm);
            let run = |way: &str| match way {
                "percall" => {
                    let mut sim = Simulator::new(&p, &Settings::default()).unwrap();
                    for (t1, exc) in &pieces {
                        sim.advance(*t1, exc).unwrap();
                    }
                    black_box(sim.outputs().peak_up);
                }
                "onecall" => {
                    let mut sim = Simulator::new(&p, &Settings::default()).unwrap();
                    sim.advance_pieces(pieces.iter().copied()).unwrap();
                    black_box(sim.outputs().peak_up);
                }
                "floor" => {
                    let omega = 2.0 * std::f64::consts::PI / p.tp;
                    black_box(sdof::response(
                        omega,
                        p.zeta,
                        gm.time[1] - gm.time[0],
                        black_box(&gm.accel),
                    ));
                }
                _ => {
                    let mut sim = Simulator::new(&p, &Settings::default()).unwrap();
                    record::run(&mut sim, gm, 1.0).unwrap();
                    black_box(sim.outputs().peak_up);
                }
            };
            // percall and onecall against the record path; the others
            // against the floor.
            let other = if scene == "percall" || scene == "onecall" {
                "record"
            } else {
                "floor"
            };
            // Untimed rounds first (as the bench's warm-up): the processor's
            // clock and the caches settle.
            let warm = Instant::now();
            while warm.elapsed().as_secs_f64() < 0.2 {
                run(scene);
                run(other);
            }
            let (mut a, mut b) = (Vec::new(), Vec::new());
            for _ in 0..rounds {
                let t = Instant::now();
                for _ in 0..reps {
                    run(scene);
                }
                a.push(t.elapsed().as_secs_f64() / reps as f64);
                let t = Instant::now();
                for _ in 0..reps {
                    run(other);
                }
                b.push(t.elapsed().as_secs_f64() / reps as f64);
            }
            let (ma, mb) = (common::median(a), common::median(b));
            let mut sim = Simulator::new(&p, &Settings::default()).unwrap();
            record::run(&mut sim, gm, 1.0).unwrap();
            println!(
                "{name:8} {scene:8} {:8.1} us / {other} {:8.1} us = {:.2}x, {} switches, {} samples",
                ma * 1e6,
                mb * 1e6,
                ma / mb,
                sim.stats().events,
                gm.accel.len()
            );
        }
    }
}
