//! The engine's AVX-512 copies (`stacked_live_load::isa`) against its
//! baseline x86-64 code: the same IEEE operations in the same order, so every
//! output must agree bit for bit. On a processor without AVX-512 both runs
//! take the baseline code (the test says so and still runs them).
#[allow(dead_code)]
mod common;

use common::Rng;
use stacked_live_load::{ground::record, isa, Outputs, Params, Settings, Simulator, Support};

/// A random stack of `n` blocks, mus >= muk (equal on about half of the
/// interfaces), on the structure or on a prescribed support.
fn random_scene(rng: &mut Rng, n: usize, support: Support) -> Params {
    let mut p = Params {
        n_blocks: n,
        tp: rng.uniform(0.2, 1.5),
        zeta: rng.uniform(0.0, 0.1),
        support,
        ..Params::default()
    };
    for j in 0..n {
        p.alpha[j] = rng.uniform(0.05, 0.4);
        p.muk[j] = rng.uniform(0.02, 0.3);
        p.mus[j] = p.muk[j]
            * if rng.next_f64() < 0.5 {
                1.0
            } else {
                rng.uniform(1.0, 1.5)
            };
    }
    p
}

/// Every output of a scene over a record, the whole record in one call and
/// one call per sample (the driver's two ways).
fn outputs(p: &Params, gm: &stacked_live_load::GroundMotion) -> [Outputs; 2] {
    let mut whole = Simulator::new(p, &Settings::default()).unwrap();
    record::run(&mut whole, gm, 1.0).unwrap();
    let mut per_call = Simulator::new(p, &Settings::default()).unwrap();
    for (t1, exc) in common::record_pieces(gm) {
        per_call.advance(t1, &exc).unwrap();
    }
    [whole.outputs(), per_call.outputs()]
}

#[test]
fn the_avx512_copies_give_the_baselines_results_bit_for_bit() {
    if !isa::wide_registers_available() {
        eprintln!("no AVX-512 here: both runs take the baseline code");
    }
    // Fresh seeded inputs: broadband records at three spacings, random
    // scenes of 0..8 blocks (mus >= muk), and the bench's stacks.
    let mut rng = common::Rng(0x15a_2026);
    let mut scenes = vec![
        common::graded_stack(2),
        common::graded_stack(8),
        common::graded_stack_static_above_kinetic(),
    ];
    for n in 0..=8 {
        scenes.push(random_scene(&mut rng, n, Support::Structure));
    }
    for n in [1, 3, 8] {
        scenes.push(random_scene(&mut rng, n, Support::Prescribed));
    }
    let records: Vec<_> = [0.005, 0.01, 0.02]
        .iter()
        .map(|&dt| common::broadband_record(&mut rng, 8.0, dt))
        .collect();
    for (i, p) in scenes.iter().enumerate() {
        for gm in &records {
            isa::allow_wide_registers(true);
            let wide = outputs(p, gm);
            isa::allow_wide_registers(false);
            let narrow = outputs(p, gm);
            isa::allow_wide_registers(true);
            // Debug formatting prints every f64 exactly (shortest round trip).
            assert_eq!(format!("{wide:?}"), format!("{narrow:?}"), "scene {i}");
        }
    }
}
