//! The FMU as a coupling partner (docs/coupling-ports.md): `tSwitch`, output
//! derivatives and declared dependencies, through the instance's safe API.

mod common;
use common::Rng;
use stacked_live_load::instance::{Instance, NullSink, SavedState, Status};
use stacked_live_load::variables::Id;

/// A seeded broadband ground acceleration (m/s2): a sum of sines with random
/// frequencies (0.5-8 Hz), amplitudes and phases, ramped in over 0.2 s.
struct Signal(Vec<(f64, f64, f64)>);

impl Signal {
    fn new(seed: u64, amplitude: f64) -> Signal {
        let mut rng = Rng(seed);
        let terms = (0..8)
            .map(|_| {
                let f = rng.uniform(0.5, 8.0);
                let phase = rng.uniform(0.0, 6.28);
                (
                    2.0 * std::f64::consts::PI * f,
                    amplitude / 8.0 * rng.uniform(0.5, 1.5),
                    phase,
                )
            })
            .collect();
        Signal(terms)
    }

    fn at(&self, t: f64) -> f64 {
        let ramp = (t / 0.2).min(1.0);
        ramp * self
            .0
            .iter()
            .map(|&(w, a, p)| a * (w * t + p).sin())
            .sum::<f64>()
    }
}

fn initialized(ints: &[(Id, i32)], reals: &[(Id, f64)]) -> Instance {
    let mut inst = Instance::new("coupling", None, Box::new(NullSink), false);
    assert_eq!(inst.setup_experiment(0.0, None), Status::Ok);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    for &(id, x) in ints {
        assert_eq!(inst.set_integer(&[id.vr()], &[x]), Status::Ok, "{id:?}");
    }
    for &(id, x) in reals {
        assert_eq!(inst.set_real(&[id.vr()], &[x]), Status::Ok, "{id:?}");
    }
    assert_eq!(inst.exit_initialization_mode(), Status::Ok);
    inst
}

fn real(inst: &mut Instance, id: Id) -> f64 {
    let mut out = [f64::NAN];
    assert_eq!(inst.get_real(&[id.vr()], &mut out), Status::Ok, "{id:?}");
    out[0]
}

fn events(inst: &mut Instance) -> i32 {
    let mut out = [0];
    assert_eq!(inst.get_integer(&[Id::NEvents.vr()], &mut out), Status::Ok);
    out[0]
}

/// Sets `ag` and its slope for the linear piece of `signal` over [t0, t1],
/// then steps to `t` (<= t1) along that same piece.
fn step_along(inst: &mut Instance, signal: &Signal, t0: f64, t1: f64, from: f64, to: f64) {
    let (a0, a1) = (signal.at(t0), signal.at(t1));
    let slope = (a1 - a0) / (t1 - t0);
    assert_eq!(set(inst, Id::Ag, a0 + slope * (from - t0)), Status::Ok);
    assert_eq!(
        inst.set_input_derivatives(&[Id::Ag.vr()], &[1], &[slope]),
        Status::Ok
    );
    assert_eq!(inst.do_step(from, to - from), Status::Ok);
}

fn set(inst: &mut Instance, id: Id, x: f64) -> Status {
    inst.set_real(&[id.vr()], &[x])
}

fn restore(inst: &mut Instance, state: &SavedState) {
    assert_eq!(inst.restore(state), Status::Ok);
}

#[test]
fn t_switch_lands_a_rolled_back_master_on_the_switch() {
    // Stacks that stick and slide under a seeded broadband ground motion,
    // driven by a master with macro step H = 0.02 s and linear inputs.
    // Every macro step with a switch reports its first one strictly inside;
    // rolled back, a step to just before it sees none, and a step just past
    // it sees exactly one, at the same time to 1e-10 s (the event location
    // tolerance is 1e-12 s; the two runs take different internal steps).
    let scenes: [(i32, &[(Id, f64)]); 3] = [
        (1, &[(Id::Mus(1), 0.15), (Id::Muk(1), 0.1)]),
        (2, &[]),
        (
            3,
            &[(Id::Alpha(3), 0.1), (Id::Mus(3), 0.08), (Id::Muk(3), 0.08)],
        ),
    ];
    let h = 0.02;
    let mut checked = 0;
    for (k, (n, reals)) in scenes.into_iter().enumerate() {
        let mut inst = initialized(&[(Id::NBlocks, n)], reals);
        let signal = Signal::new(11 + k as u64, 4.0);
        assert_eq!(real(&mut inst, Id::TSwitch), 0.0, "before any step");
        for i in 0..100 {
            let (t0, t1) = (i as f64 * h, (i + 1) as f64 * h);
            let saved = inst.save().unwrap();
            let before = events(&mut inst);
            step_along(&mut inst, &signal, t0, t1, t0, t1);
            let t_switch = real(&mut inst, Id::TSwitch);
            if events(&mut inst) == before {
                assert_eq!(t_switch, t1, "no switch: tSwitch is the step's end");
                continue;
            }
            assert!(
                t0 < t_switch && t_switch <= t1,
                "{t_switch} in ({t0}, {t1}]"
            );
            restore(&mut inst, &saved);
            let just_before = t_switch - 1e-9;
            if just_before > t0 {
                step_along(&mut inst, &signal, t0, t1, t0, just_before);
                assert_eq!(events(&mut inst), before, "a switch before tSwitch");
                assert_eq!(real(&mut inst, Id::TSwitch), just_before);
            }
            let from = just_before.max(t0);
            step_along(&mut inst, &signal, t0, t1, from, t_switch + 1e-9);
            assert_eq!(events(&mut inst), before + 1, "one switch right after");
            let again = real(&mut inst, Id::TSwitch);
            assert!(
                (again - t_switch).abs() < 1e-10,
                "switch at {again}, first seen at {t_switch}"
            );
            checked += 1;
            // Continue the macro step from there, as an event-aware master would.
            step_along(&mut inst, &signal, t0, t1, t_switch + 1e-9, t1);
        }
    }
    eprintln!("{checked} macro steps with a switch checked");
    assert!(checked >= 10, "only {checked} macro steps had a switch");
}

#[test]
fn t_switch_is_saved_and_restored_with_the_state() {
    let mut inst = initialized(&[], &[]);
    let signal = Signal::new(5, 4.0);
    let mut t = 0.0;
    while real(&mut inst, Id::TSwitch) == t {
        step_along(&mut inst, &signal, t, t + 0.05, t, t + 0.05);
        t += 0.05;
        assert!(t < 3.0, "no switch in 3 s");
    }
    let t_switch = real(&mut inst, Id::TSwitch);
    let bytes = Instance::serialize(&inst.save().unwrap());
    step_along(&mut inst, &signal, t, t + 0.05, t, t + 0.05);
    restore(&mut inst, &Instance::deserialize(&bytes).unwrap());
    assert_eq!(real(&mut inst, Id::TSwitch), t_switch);
}
