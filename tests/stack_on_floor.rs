//! StackOnFloor, the second model of the binary, through the instance's safe
//! API: it is the engine's stack on a prescribed support bit for bit, its
//! force on the floor balances the blocks' momentum, its directional
//! derivatives are those of a finite difference within a mode, and the
//! dependencies its model description declares are the ones its outputs
//! show when an input changes at a communication point.

mod common;
use common::Capture;
use stacked_live_load::fmi::instance::{Instance, Status};
use stacked_live_load::fmi::variables::{Causality, Id, Kind, Model};
use stacked_live_load::{Excitation, Params, Settings, Simulator, Support, MAX_BLOCKS};

fn floor_instance() -> (Instance, Capture) {
    let (mut inst, log) = common::instance("floor");
    inst.use_model(Model::Floor);
    (inst, log)
}

/// A StackOnFloor initialized after `setup`.
fn started(setup: impl FnOnce(&mut Instance)) -> (Instance, Capture) {
    let (mut inst, log) = floor_instance();
    assert_eq!(inst.setup_experiment(0.0, None), Status::Ok);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    setup(&mut inst);
    assert_eq!(
        inst.exit_initialization_mode(),
        Status::Ok,
        "{}",
        log.last()
    );
    (inst, log)
}

fn real(inst: &mut Instance, id: Id) -> f64 {
    let mut out = [f64::NAN];
    assert_eq!(inst.get_real(&[id.vr()], &mut out), Status::Ok);
    out[0]
}

fn stuck(inst: &mut Instance, j: usize) -> bool {
    let mut out = [0];
    assert_eq!(inst.get_boolean(&[Id::Stuck(j).vr()], &mut out), Status::Ok);
    out[0] != 0
}

fn set(inst: &mut Instance, id: Id, x: f64) -> Status {
    inst.set_real(&[id.vr()], &[x])
}

/// Three blocks of different masses whose interfaces slip at different
/// accelerations (mu g = 2.94, 1.96, 0.98 m/s2), static above kinetic.
const MASSES: [f64; 3] = [400.0, 150.0, 75.0];
const MUS: [f64; 3] = [0.3, 0.2, 0.1];
const MUK: [f64; 3] = [0.25, 0.2, 0.08];

fn scene(inst: &mut Instance) {
    assert_eq!(inst.set_integer(&[Id::NBlocks.vr()], &[3]), Status::Ok);
    for j in 1..=3 {
        assert_eq!(set(inst, Id::M(j), MASSES[j - 1]), Status::Ok);
        assert_eq!(set(inst, Id::Mus(j), MUS[j - 1]), Status::Ok);
        assert_eq!(set(inst, Id::Muk(j), MUK[j - 1]), Status::Ok);
    }
}

/// The same scene for the engine: block j's mass is `alpha[j-1] * mp`.
fn engine_params() -> Params {
    let mut p = Params {
        n_blocks: 3,
        mp: 1.0,
        support: Support::Prescribed,
        ..Params::default()
    };
    for j in 0..3 {
        p.alpha[j] = MASSES[j];
        p.mus[j] = MUS[j];
        p.muk[j] = MUK[j];
    }
    p
}

/// A floor acceleration as a master gives it: a value and a slope per
/// communication step of 10 ms, with jumps between steps (a partner's floor
/// under a 1.5 Hz shaking of 4 m/s2 and sampling offsets).
fn input(k: usize) -> (f64, f64) {
    let t = k as f64 * 0.01;
    let a = 4.0 * (2.0 * std::f64::consts::PI * 1.5 * t).sin();
    let jump = if k % 7 == 3 { 0.8 } else { 0.0 };
    (
        a + jump,
        4.0 * 2.0 * std::f64::consts::PI * 1.5 * (2.0 * std::f64::consts::PI * 1.5 * t).cos(),
    )
}

const H: f64 = 0.01;

#[test]
fn stack_on_floor_is_the_engines_prescribed_support_bit_for_bit() {
    let (mut inst, log) = started(scene);
    let mut sim = Simulator::new(&engine_params(), &Settings::default()).unwrap();
    let mut switches = 0;
    for k in 0..300 {
        let (ag, rate) = input(k);
        // A mobility that changes once, halfway: it enters the mode choice.
        let mobility = if k < 150 { 0.0 } else { 2e-3 };
        assert_eq!(set(&mut inst, Id::Ag, ag), Status::Ok);
        assert_eq!(set(&mut inst, Id::SupportMobility, mobility), Status::Ok);
        assert_eq!(
            inst.set_input_derivatives(&[Id::Ag.vr()], &[1], &[rate]),
            Status::Ok
        );
        assert_eq!(inst.do_step(k as f64 * H, H), Status::Ok, "{}", log.last());
        let exc = Excitation {
            ag,
            ag_rate: rate,
            ..Default::default()
        };
        sim.set_support_mobility(mobility).unwrap();
        // As fmi2DoStep: the jump of ag at the communication point first (the
        // mode it gives is the step's reference of the support's law), then
        // the step; the outputs as the next step starts, as fmi2GetReal
        // shows them (ports' rule, the inputs held at their ends).
        let now = sim.time();
        sim.advance(now, &exc).unwrap();
        sim.advance(now + H, &exc).unwrap();
        let held = Excitation {
            ag: sim.ag_now(),
            ..exc
        };
        let o = stacked_live_load::fmi::ports::outputs_at_step_start(
            &stacked_live_load::solver::Solver::Exact(sim.clone()),
            &held,
            mobility,
        )
        .unwrap();
        let mut ids = vec![
            (Id::FloorForce, o.floor_force),
            (Id::AttachedMass, o.attached_mass),
            (Id::SlidingForce, o.sliding_force),
            (Id::Einput, o.e_input),
            (Id::Ekinetic, o.e_kinetic),
            (Id::Efriction, o.e_friction),
        ];
        for j in 1..=3 {
            let b = j - 1;
            ids.extend([
                (Id::Ub(j), o.ub[b]),
                (Id::Vb(j), o.vb[b]),
                (Id::Slip(j), o.slip[b]),
                (Id::AbAbs(j), o.ab_abs[b]),
                (Id::F(j), o.force[b]),
                (Id::PeakSlip(j), o.peak_slip[b]),
            ]);
        }
        for (id, expected) in ids {
            let got = real(&mut inst, id);
            assert_eq!(
                got.to_bits(),
                expected.to_bits(),
                "{} at step {k}: FMU {got:e}, engine {expected:e}",
                id.name()
            );
        }
        for j in 1..=3 {
            assert_eq!(stuck(&mut inst, j), o.stuck[j - 1]);
        }
        let mut events = [0];
        assert_eq!(
            inst.get_integer(&[Id::NEvents.vr()], &mut events),
            Status::Ok
        );
        assert_eq!(events[0] as u64, o.n_events);
        switches = o.n_events;
    }
    assert!(switches > 10, "the scene switches modes ({switches})");
}

/// `floorForce = -sum m_j abAbs[j]` (the blocks' momentum balance) and
/// `slidingForce = floorForce + attachedMass ag`, at every communication
/// point, with jumps of ag set before the outputs are read.
#[test]
fn floor_force_balances_the_blocks_momentum() {
    let (mut inst, _log) = started(scene);
    let mut attached_seen = [false; 2];
    for k in 0..300 {
        let (ag, rate) = input(k);
        set(&mut inst, Id::Ag, ag);
        inst.set_input_derivatives(&[Id::Ag.vr()], &[1], &[rate]);
        let force = real(&mut inst, Id::FloorForce);
        let momentum: Vec<f64> = (1..=3)
            .map(|j| MASSES[j - 1] * real(&mut inst, Id::AbAbs(j)))
            .collect();
        let sum: f64 = momentum.iter().sum();
        let scale = momentum.iter().map(|x| x.abs()).sum::<f64>().max(1.0);
        assert!(
            (force + sum).abs() <= 1e-12 * scale,
            "step {k}: floorForce {force:e}, -sum m a {:e}",
            -sum
        );
        let attached = real(&mut inst, Id::AttachedMass);
        let sliding = real(&mut inst, Id::SlidingForce);
        assert!(
            (sliding - (force + attached * ag)).abs()
                <= 1e-12 * (sliding.abs() + force.abs() + 1.0),
            "step {k}: slidingForce {sliding:e}, floorForce + attachedMass ag {:e}",
            force + attached * ag
        );
        attached_seen[usize::from(attached > 0.0)] = true;
        assert_eq!(inst.do_step(k as f64 * H, H), Status::Ok);
    }
    assert_eq!(attached_seen, [true, true], "both regimes are met");
}

/// The directional derivatives of every Real output with respect to `ag`
/// against a central finite difference of `ag` set at a communication point
/// (within a mode: the stick flags are the same at both ends), and
/// `d floorForce / d ag = -attachedMass` exactly. The outputs are affine in
/// `ag` within a mode, so the difference is exact up to rounding: tolerance
/// 1e-11 of the outputs' scale over the increment.
#[test]
fn directional_derivatives_match_finite_differences_within_a_mode() {
    let (mut inst, log) = started(scene);
    let reals: Vec<Id> = Model::Floor
        .table()
        .into_iter()
        .map(|v| v.id)
        .filter(|id| id.causality() == Causality::Output && id.kind() == Kind::Real)
        .collect();
    let unknowns: Vec<u32> = reals.iter().map(|id| id.vr()).collect();
    let mut checked_attached = 0;
    for k in 0..200 {
        let (ag, _) = input(k);
        assert_eq!(inst.do_step(k as f64 * H, H), Status::Ok);
        set(&mut inst, Id::Ag, ag);
        let flags: Vec<bool> = (1..=3).map(|j| stuck(&mut inst, j)).collect();
        let mut dd = vec![f64::NAN; unknowns.len()];
        assert_eq!(
            inst.directional_derivative(&unknowns, &[Id::Ag.vr()], &[1.0], &mut dd),
            Status::Ok,
            "{}",
            log.last()
        );
        // With respect to supportMobility: 0 within a mode.
        let mut dm = vec![f64::NAN; unknowns.len()];
        assert_eq!(
            inst.directional_derivative(&unknowns, &[Id::SupportMobility.vr()], &[1.0], &mut dm),
            Status::Ok
        );
        assert!(dm.iter().all(|&x| x == 0.0));
        let attached = real(&mut inst, Id::AttachedMass);
        assert_eq!(dd[0], -attached, "d floorForce / d ag = -attachedMass");
        let delta = 1e-4;
        let mut at = |a: f64| {
            set(&mut inst, Id::Ag, a);
            let values: Vec<f64> = reals.iter().map(|&id| real(&mut inst, id)).collect();
            let flags: Vec<bool> = (1..=3).map(|j| stuck(&mut inst, j)).collect();
            (values, flags)
        };
        let (plus, flags_plus) = at(ag + delta);
        let (minus, flags_minus) = at(ag - delta);
        set(&mut inst, Id::Ag, ag);
        if flags_plus != flags || flags_minus != flags {
            continue; // at a stick's capacity: not within a mode
        }
        for (i, id) in reals.iter().enumerate() {
            let fd = (plus[i] - minus[i]) / (2.0 * delta);
            let scale = plus[i].abs().max(minus[i].abs()).max(1.0);
            assert!(
                (fd - dd[i]).abs() <= 1e-11 * scale / delta,
                "d {} / d ag at step {k}: directional {:e}, finite difference {fd:e}",
                id.name(),
                dd[i]
            );
        }
        if attached > 0.0 {
            checked_attached += 1;
        }
    }
    assert!(
        checked_attached > 20,
        "{checked_attached} points with blocks attached"
    );
}

#[test]
fn directional_derivative_refuses_what_it_does_not_provide() {
    let (mut inst, log) = started(scene);
    let mut out = [0.0];
    // A parameter as known, an integer or Boolean as unknown, the wrong count.
    let refused = [
        (Id::FloorForce, Id::M(1), "m[1] is not an input"),
        (Id::NEvents, Id::Ag, "nEvents is not a Real output"),
        (Id::Stuck(1), Id::Ag, "stuck[1] is not a Real output"),
        (Id::Ag, Id::Ag, "ag is not a Real output"),
    ];
    for (unknown, known, message) in refused {
        assert_eq!(
            inst.directional_derivative(&[unknown.vr()], &[known.vr()], &[1.0], &mut out),
            Status::Error
        );
        assert!(log.last().contains(message), "{}", log.last());
    }
    assert_eq!(
        inst.directional_derivative(&[Id::FloorForce.vr()], &[Id::Ag.vr()], &[], &mut out),
        Status::Error
    );
    assert_eq!(
        inst.directional_derivative(
            &[Id::FloorForce.vr()],
            &[Id::Ag.vr()],
            &[f64::NAN],
            &mut out
        ),
        Status::Error
    );
    // The storey's: baseShear depends on no input; solver 3 has none.
    let (mut storey, _) = common::started(0.0, |_| {});
    assert_eq!(
        storey.directional_derivative(&[Id::BaseShear.vr()], &[Id::Fext.vr()], &[1.0], &mut out),
        Status::Ok
    );
    assert_eq!(out[0], 0.0);
    assert_eq!(
        storey.directional_derivative(&[Id::ApAbs.vr()], &[Id::Mp.vr()], &[1.0], &mut out),
        Status::Error
    );
    let (mut storey, log) = common::started(0.0, |inst| {
        inst.set_integer(&[Id::Solver.vr()], &[3]);
    });
    assert_eq!(
        storey.directional_derivative(&[Id::ApAbs.vr()], &[Id::Fext.vr()], &[1.0], &mut out),
        Status::Error
    );
    assert!(log.last().contains("not by solver 3"), "{}", log.last());
}

/// The dependencies in the generated model descriptions (FMI 2.0 by index,
/// FMI 3.0 by value reference) are [`Model::input_dependencies`], and they
/// are honest: an output that declares none does not move when `ag` or
/// `supportMobility` changes at a communication point; every output that
/// declares `ag` moves for some change of it.
#[test]
fn declared_dependencies_are_the_generated_ones_and_hold() {
    use stacked_live_load::fmi::{model_description, model_description_fmi3};
    let table = Model::Floor.table();
    let xml2 = model_description::model_description_of(Model::Floor);
    let xml3 = model_description_fmi3::model_description_of(Model::Floor);
    let outputs2 = section(&xml2, "<Outputs>", "</Outputs>");
    let outputs3: String = xml3
        .lines()
        .filter(|l| l.trim_start().starts_with("<Output "))
        .collect::<Vec<_>>()
        .join("\n");
    for (i, v) in table.iter().enumerate() {
        if v.id.causality() != Causality::Output {
            continue;
        }
        let deps = Model::Floor.input_dependencies(v.id);
        let index_of = |id: Id| table.iter().position(|w| w.id == id).unwrap() + 1;
        let by_index: Vec<String> = deps.iter().map(|&d| index_of(d).to_string()).collect();
        let line2 = format!(
            "index=\"{}\" dependencies=\"{}\"",
            i + 1,
            by_index.join(" ")
        );
        assert!(outputs2.contains(&line2), "FMI 2.0: {line2}");
        let by_vr: Vec<String> = deps.iter().map(|d| d.vr().to_string()).collect();
        let line3 = format!(
            "valueReference=\"{}\" dependencies=\"{}\"",
            v.id.vr(),
            by_vr.join(" ")
        );
        assert!(outputs3.contains(&line3), "FMI 3.0: {line3}");
    }
    let floor_deps = [
        Id::FloorForce,
        Id::AttachedMass,
        Id::SlidingForce,
        Id::AbAbs(1),
        Id::F(1),
        Id::Stuck(1),
    ];
    for id in floor_deps {
        assert_eq!(
            Model::Floor.input_dependencies(id),
            &[Id::Ag, Id::SupportMobility]
        );
    }
    assert!(Model::Floor.input_dependencies(Id::Ub(1)).is_empty());

    // Honest: read every output before and after an input change at a
    // communication point.
    let (mut inst, _) = started(scene);
    let outputs: Vec<Id> = table
        .iter()
        .map(|v| v.id)
        .filter(|id| id.causality() == Causality::Output)
        .collect();
    let read = |inst: &mut Instance| -> Vec<f64> {
        outputs
            .iter()
            .map(|&id| match id.kind() {
                Kind::Real => real(inst, id),
                Kind::Boolean => f64::from(u8::from(stuck(inst, id.block().unwrap()))),
                _ => {
                    let mut x = [0];
                    assert_eq!(inst.get_integer(&[id.vr()], &mut x), Status::Ok);
                    f64::from(x[0])
                }
            })
            .collect()
    };
    let mut moved = vec![false; outputs.len()];
    for k in 0..150 {
        let (ag, _) = input(k);
        set(&mut inst, Id::Ag, ag);
        assert_eq!(inst.do_step(k as f64 * H, H), Status::Ok);
        let before = read(&mut inst);
        for (input, value) in [
            (Id::Ag, ag + 3.0),
            (Id::Ag, ag - 5.0),
            (Id::SupportMobility, 0.01),
        ] {
            set(&mut inst, input, value);
            let after = read(&mut inst);
            for (i, &id) in outputs.iter().enumerate() {
                if after[i].to_bits() != before[i].to_bits() {
                    assert!(
                        Model::Floor.input_dependencies(id).contains(&input),
                        "{} moved with {} but declares no dependency on it",
                        id.name(),
                        input.name()
                    );
                    moved[i] = true;
                }
            }
            set(&mut inst, Id::SupportMobility, 0.0);
            set(&mut inst, Id::Ag, ag);
        }
    }
    for id in [
        Id::FloorForce,
        Id::AttachedMass,
        Id::SlidingForce,
        Id::AbAbs(1),
        Id::F(1),
        Id::Stuck(1),
    ] {
        let i = outputs.iter().position(|&o| o == id).unwrap();
        assert!(moved[i], "{} never moved with its inputs", id.name());
    }
}

fn section<'a>(xml: &'a str, open: &str, close: &str) -> &'a str {
    let a = xml.find(open).unwrap();
    let b = xml[a..].find(close).unwrap() + a;
    &xml[a..b]
}

#[test]
fn variables_are_the_floor_table_only() {
    let (mut inst, log) = floor_instance();
    // Storey-only variables are unknown to StackOnFloor.
    for id in [
        Id::Mp,
        Id::Tp,
        Id::Zeta,
        Id::Fext,
        Id::Alpha(1),
        Id::MaxStep,
    ] {
        assert_eq!(set(&mut inst, id, 1.0), Status::Error);
        assert!(
            log.last().contains("unknown value reference"),
            "{}",
            log.last()
        );
    }
    assert_eq!(inst.set_integer(&[Id::Solver.vr()], &[1]), Status::Error);
    // Defaults: 2 blocks of 250 kg, the storey's friction.
    let mut n = [0];
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(inst.get_integer(&[Id::NBlocks.vr()], &mut n), Status::Ok);
    assert_eq!(n[0], 2);
    assert_eq!(real(&mut inst, Id::M(1)), 250.0);
    assert_eq!(real(&mut inst, Id::SupportMobility), 0.0);
    // At rest, with no ag: every block attached, nothing on the floor.
    assert_eq!(real(&mut inst, Id::AttachedMass), 500.0);
    assert_eq!(real(&mut inst, Id::FloorForce), 0.0);
    let names: Vec<String> = Model::Floor
        .table()
        .iter()
        .map(|v| v.name.clone())
        .collect();
    for name in [
        "mp",
        "Tp",
        "zeta",
        "Fext",
        "up",
        "baseShear",
        "solver",
        "alpha[1]",
    ] {
        assert!(!names.contains(&name.to_string()), "{name}");
    }
    assert_eq!(MAX_BLOCKS, 8);
}

/// Saved states round-trip, and a state of one model is refused by the other.
#[test]
fn saved_states_continue_bit_for_bit_and_stay_with_their_model() {
    let (mut inst, log) = started(scene);
    for k in 0..50 {
        let (ag, rate) = input(k);
        set(&mut inst, Id::Ag, ag);
        inst.set_input_derivatives(&[Id::Ag.vr()], &[1], &[rate]);
        assert_eq!(inst.do_step(k as f64 * H, H), Status::Ok);
    }
    set(&mut inst, Id::SupportMobility, 1e-3);
    let saved = inst.save().unwrap();
    let bytes = Instance::serialize(&saved);
    let back = Instance::deserialize(&bytes).unwrap();
    let run = |inst: &mut Instance| {
        for k in 50..100 {
            let (ag, rate) = input(k);
            set(inst, Id::Ag, ag);
            inst.set_input_derivatives(&[Id::Ag.vr()], &[1], &[rate]);
            assert_eq!(inst.do_step(k as f64 * H, H), Status::Ok);
        }
        real(inst, Id::FloorForce)
    };
    let first = run(&mut inst);
    assert_eq!(inst.restore(&back), Status::Ok, "{}", log.last());
    assert_eq!(real(&mut inst, Id::SupportMobility), 1e-3);
    assert_eq!(run(&mut inst).to_bits(), first.to_bits());
    let (mut storey, log) = common::started(0.0, |_| {});
    assert_eq!(storey.restore(&back), Status::Error);
    assert!(
        log.last().contains("saved by a StackOnFloor instance"),
        "{}",
        log.last()
    );
}

/// fmi2GetRealOutputDerivatives: the first derivative of each continuous
/// output against a finite difference over a short step without a switch.
#[test]
fn output_derivatives_match_the_motion() {
    let (mut inst, log) = started(scene);
    let continuous: Vec<Id> = Model::Floor
        .table()
        .into_iter()
        .map(|v| v.id)
        .filter(|id| id.causality() == Causality::Output && id.is_continuous())
        .collect();
    let vrs: Vec<u32> = continuous.iter().map(|id| id.vr()).collect();
    let mut checked = 0;
    for k in 0..200 {
        let (ag, rate) = input(k);
        set(&mut inst, Id::Ag, ag);
        inst.set_input_derivatives(&[Id::Ag.vr()], &[1], &[rate]);
        let mut d1 = vec![f64::NAN; vrs.len()];
        assert_eq!(
            inst.get_output_derivatives(&vrs, &vec![1; vrs.len()], &mut d1),
            Status::Ok,
            "{}",
            log.last()
        );
        let mut d2 = vec![f64::NAN; vrs.len()];
        assert_eq!(
            inst.get_output_derivatives(&vrs, &vec![2; vrs.len()], &mut d2),
            Status::Ok
        );
        let before: Vec<f64> = continuous.iter().map(|&id| real(&mut inst, id)).collect();
        let mut events = [0];
        inst.get_integer(&[Id::NEvents.vr()], &mut events);
        let h = 1e-6;
        let t = inst.last_successful_time();
        assert_eq!(inst.do_step(t, h), Status::Ok);
        let mut events_after = [0];
        inst.get_integer(&[Id::NEvents.vr()], &mut events_after);
        set(&mut inst, Id::Ag, ag + rate * h);
        let after: Vec<f64> = continuous.iter().map(|&id| real(&mut inst, id)).collect();
        if events_after == events {
            // Taylor: (x(t+h) - x(t)) / h = x' + x'' h / 2 + O(h^2) (the
            // peaks' second derivative aside, every output is at most
            // quadratic in time over a step without a switch; 1e-9 of the
            // values' scale over h covers their rounding).
            for (i, id) in continuous.iter().enumerate() {
                let fd = (after[i] - before[i]) / h;
                let expected = d1[i] + 0.5 * d2[i] * h;
                let scale = before[i].abs().max(after[i].abs());
                assert!(
                    (fd - expected).abs() <= 1e-9 * expected.abs() + 1e-12 * scale / h + 1e-12,
                    "d {}/dt at step {k}: {:e} (+ h/2 {:e}), finite difference {fd:e}",
                    id.name(),
                    d1[i],
                    d2[i]
                );
            }
            checked += 1;
        }
        let t = inst.last_successful_time();
        assert_eq!(inst.do_step(t, H - h), Status::Ok);
    }
    assert!(checked > 150);
}

/// FMI 3.0 with early return: StackOnFloor returns at every switch its FMI
/// 2.0 counterpart reports in `tSwitch` (within 1e-9 s), driven by a record
/// of the floor's acceleration (the default record: `recordFile`), and ends
/// at the same state on the communication grid up to the switch times'
/// rounding.
#[test]
fn fmi3_returns_early_at_every_switch() {
    use stacked_live_load::fmi::instance::StepRequest;
    let record = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("resources/default_record.csv")
        .display()
        .to_string();
    let start = |early: bool| {
        let (mut inst, log) = floor_instance();
        inst.use_model(Model::Floor);
        if early {
            inst.use_fmi3(true, false);
        }
        assert_eq!(inst.setup_experiment(0.0, None), Status::Ok);
        assert_eq!(inst.enter_initialization_mode(), Status::Ok);
        scene(&mut inst);
        assert_eq!(
            inst.set_string(&[Id::RecordFile.vr()], std::slice::from_ref(&record)),
            Status::Ok
        );
        assert_eq!(
            inst.exit_initialization_mode(),
            Status::Ok,
            "{}",
            log.last()
        );
        inst
    };
    // FMI 2.0: the switch times of each 20 ms step.
    let mut fmi2 = start(false);
    let mut switches = vec![];
    let h = 0.02;
    for k in 0..300 {
        let t = k as f64 * h;
        assert_eq!(fmi2.do_step(t, h), Status::Ok);
        let ts = real(&mut fmi2, Id::TSwitch);
        if ts < t + h - 1e-10 {
            switches.push(ts);
        }
    }
    // FMI 3.0: an early return at each, none elsewhere.
    let mut fmi3 = start(true);
    fmi3.use_fmi3(true, false);
    let mut returns = vec![];
    for k in 0..300 {
        let end = (k + 1) as f64 * h;
        loop {
            let t = fmi3.last_successful_time();
            let out = fmi3.do_step_fmi3(StepRequest { t, h: end - t });
            assert_eq!(out.status, Status::Ok);
            if !out.early_return {
                break;
            }
            returns.push(out.last_successful_time);
        }
    }
    assert!(switches.len() > 5, "{} switches", switches.len());
    assert!(returns.len() >= switches.len(), "{} returns", returns.len());
    for ts in &switches {
        assert!(
            returns.iter().any(|r| (r - ts).abs() <= 1e-9),
            "no early return at the switch at {ts}"
        );
    }
    let (a, b) = (
        real(&mut fmi2, Id::Efriction),
        real(&mut fmi3, Id::Efriction),
    );
    assert!((a - b).abs() <= 1e-6 * a.abs(), "Efriction {a} vs {b}");
}
