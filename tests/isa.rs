//! The engine's AVX2 and AVX-512 copies (`stacked_live_load::isa`) against
//! its baseline x86-64 code: the same IEEE operations in the same order, so
//! every output must agree bit for bit. A copy the processor lacks is not run
//! (the test says so); the baseline is compared with every one it has.
mod common;

use common::{random_stack, Rng};
use stacked_live_load::{
    ground::record,
    isa::{self, Isa},
    Excitation, Outputs, Params, Settings, Simulator, Support,
};

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

/// A master's communication steps of random length, each with its own `ag`
/// and `Fext` and their slopes (each continues or jumps).
fn master_inputs(rng: &mut Rng, duration: f64, mass: f64) -> Vec<(f64, Excitation)> {
    let (mut t, mut ag, mut fext) = (0.0, 0.0, 0.0);
    let mut pieces = vec![];
    while t < duration {
        let h = rng.uniform(0.001, 0.05);
        let (ag_rate, fext_rate) = (rng.uniform(-40.0, 40.0), mass * rng.uniform(-20.0, 20.0));
        if rng.next_f64() < 0.3 {
            (ag, fext) = (rng.uniform(-3.0, 3.0), mass * rng.uniform(-2.0, 2.0));
        }
        pieces.push((
            t + h,
            Excitation {
                ag,
                ag_rate,
                fext,
                fext_rate,
            },
        ));
        (t, ag, fext) = (t + h, ag + ag_rate * h, fext + fext_rate * h);
        // Bounded inputs: a ramp turns back at 3 m/s2 (or its force).
        (ag, fext) = (ag.clamp(-3.0, 3.0), fext.clamp(-2.0 * mass, 2.0 * mass));
    }
    pieces
}

#[test]
fn the_wider_copies_give_the_baselines_results_bit_for_bit() {
    let wider: Vec<Isa> = [Isa::Avx2, Isa::Avx512]
        .into_iter()
        .filter(|&w| w <= isa::available())
        .collect();
    eprintln!("copies compared with the baseline here: {wider:?}");
    // Fresh seeded inputs: broadband records at three spacings, random
    // scenes of 0..8 blocks (mus >= muk), and the bench's stacks.
    let mut rng = common::Rng(0x15a_2026);
    let mut scenes = vec![
        common::graded_stack(2),
        common::graded_stack(8),
        common::graded_stack_static_above_kinetic(),
    ];
    for n in 0..=8 {
        scenes.push(random_stack(&mut rng, n, Support::Structure));
    }
    for n in [1, 3, 8] {
        scenes.push(random_stack(&mut rng, n, Support::Prescribed));
    }
    let records: Vec<_> = [0.005, 0.01, 0.02]
        .iter()
        .map(|&dt| common::broadband_record(&mut rng, 8.0, dt))
        .collect();
    // Each copy's outputs, then the widest allowed again.
    let with = |copy: Isa, run: &dyn Fn() -> String| {
        isa::allow_up_to(copy);
        assert_eq!(isa::chosen(), copy);
        let out = run();
        isa::allow_up_to(Isa::Avx512);
        out
    };
    for (i, p) in scenes.iter().enumerate() {
        for gm in &records {
            // Debug formatting prints every f64 exactly (shortest round trip).
            let run = || format!("{:?}", outputs(p, gm));
            let baseline = with(Isa::Baseline, &run);
            for &copy in &wider {
                assert_eq!(with(copy, &run), baseline, "scene {i}, {copy:?}");
            }
        }
        // A master's inputs with slopes and jumps (no `Fext` on a support).
        let mut inputs = master_inputs(&mut rng, 6.0, p.mp);
        if p.support == Support::Prescribed {
            inputs
                .iter_mut()
                .for_each(|(_, e)| (e.fext, e.fext_rate) = (0.0, 0.0));
        }
        let run = || {
            let mut sim = Simulator::new(p, &Settings::default()).unwrap();
            sim.advance_pieces(inputs.iter().copied()).unwrap();
            format!("{:?}", sim.outputs())
        };
        let baseline = with(Isa::Baseline, &run);
        for &copy in &wider {
            assert_eq!(
                with(copy, &run),
                baseline,
                "scene {i}, a master's inputs, {copy:?}"
            );
        }
    }
}
