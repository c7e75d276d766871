//! The FMU instance through its safe API (the C ABI is a thin layer over it;
//! the C program and the fmpy suite exercise the ABI itself).

mod common;
use common::Capture;
use stacked_live_load::fmi::instance::{Instance, Phase, Status};
use stacked_live_load::fmi::variables::Id;
use stacked_live_load::{ground::record, GroundMotion, Params, Settings, Simulator};

fn instance() -> (Instance, Capture) {
    common::instance("test")
}

fn initialized_with_log(setup: impl FnOnce(&mut Instance)) -> (Instance, Capture) {
    common::started(0.0, setup)
}

fn initialized(setup: impl FnOnce(&mut Instance)) -> Instance {
    initialized_with_log(setup).0
}

fn real(inst: &mut Instance, id: Id) -> f64 {
    let mut out = [f64::NAN];
    assert_eq!(inst.get_real(&[id.vr()], &mut out), Status::Ok);
    out[0]
}

fn set(inst: &mut Instance, id: Id, x: f64) -> Status {
    inst.set_real(&[id.vr()], &[x])
}

#[test]
fn illegal_calls_are_refused_with_the_function_name() {
    let (mut inst, log) = instance();
    assert_eq!(inst.do_step(0.0, 0.01), Status::Error);
    assert!(log
        .last()
        .starts_with("fmi2DoStep: not allowed in state Instantiated"));
    assert_eq!(inst.exit_initialization_mode(), Status::Error);
    assert!(log.last().starts_with("fmi2ExitInitializationMode"));
    let (mut inst, log) = initialized_with_log(|_| {});
    assert_eq!(set(&mut inst, Id::Mp, 2000.0), Status::Error);
    assert!(log
        .last()
        .contains("mp cannot be set in state StepComplete"));
    assert_eq!(set(&mut inst, Id::Up, 1.0), Status::Error);
    assert!(log.last().contains("up is an output"));
    assert_eq!(inst.set_real(&[9999], &[1.0]), Status::Error);
    assert!(log.last().contains("unknown value reference 9999"));
    assert_eq!(inst.do_step(0.5, 0.01), Status::Error);
    assert!(log.last().contains("does not match the FMU's time 0"));
    // Inputs stay settable while stepping.
    assert_eq!(set(&mut inst, Id::Ag, 1.0), Status::Ok);
    assert_eq!(inst.do_step(0.0, 0.01), Status::Ok);
    assert_eq!(inst.terminate(), Status::Ok);
    assert_eq!(inst.phase(), Phase::Terminated);
    assert_eq!(inst.do_step(0.01, 0.01), Status::Error);
}

#[test]
fn every_invalid_parameter_is_rejected_naming_the_variable() {
    let cases: Vec<(Id, f64, &str)> = vec![
        (Id::Mp, -1.0, "mp = -1"),
        (Id::Mp, f64::NAN, "mp = NaN"),
        (Id::Tp, 0.0, "Tp = 0"),
        (Id::Zeta, 1.0, "zeta = 1"),
        (Id::G, f64::INFINITY, "g = inf"),
        (Id::Alpha(2), 0.0, "alpha[2] = 0"),
        (Id::Mus(1), -0.1, "mus[1] = -0.1"),
        (Id::Muk(3), f64::NAN, "muk[3] = NaN"),
        (Id::MaxStep, -0.01, "maxStep = -0.01"),
        (Id::FrictionEps, 0.0, "frictionEps = 0"),
        (Id::RecordScale, f64::NAN, "recordScale = NaN"),
        (Id::Ag, f64::NAN, "ag = NaN"),
    ];
    for (id, value, expected) in cases {
        let (mut inst, log) = instance();
        assert_eq!(set(&mut inst, id, value), Status::Error, "{expected}");
        assert!(
            log.last().starts_with(&format!("fmi2SetReal: {expected}")),
            "{}",
            log.last()
        );
        assert!(
            log.last().contains("must be"),
            "the allowed range is stated: {}",
            log.last()
        );
    }
    let (mut inst, log) = instance();
    assert_eq!(inst.set_integer(&[Id::NBlocks.vr()], &[9]), Status::Error);
    assert!(log
        .last()
        .contains("nBlocks = 9 is not allowed: it must be an integer from 0 to 8"));
    assert_eq!(inst.set_integer(&[Id::Solver.vr()], &[4]), Status::Error);
    assert!(log.last().contains("solver = 4 is not allowed"));
    // A cross-field rule is checked when initialization ends.
    inst.enter_initialization_mode();
    set(&mut inst, Id::Muk(1), 0.2);
    assert_eq!(inst.exit_initialization_mode(), Status::Error);
    assert!(
        log.last().contains("muk[1] = 0.2 is not allowed"),
        "{}",
        log.last()
    );
}

#[test]
fn unreadable_records_fail_initialization_with_file_and_line() {
    let dir = std::env::temp_dir().join(format!("sll_records_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "time,accel\n0,0\n0.01,oops\n").unwrap();
    for (file, expected) in [
        (
            dir.join("missing.AT2"),
            "missing.AT2: cannot read the file".to_string(),
        ),
        (
            bad.clone(),
            format!("{}:3: expected two numbers", bad.display()),
        ),
    ] {
        let (mut inst, log) = instance();
        inst.enter_initialization_mode();
        inst.set_string(&[Id::RecordFile.vr()], &[file.display().to_string()]);
        assert_eq!(inst.exit_initialization_mode(), Status::Error);
        assert!(log.last().contains(&expected), "{}", log.last());
        assert!(log
            .last()
            .starts_with("fmi2ExitInitializationMode: recordFile: "));
    }
}

#[test]
fn entries_beyond_n_blocks_read_zero_and_false() {
    let mut inst = initialized(|i| {
        set(i, Id::Ag, 2.0);
    });
    inst.do_step(0.0, 0.5);
    for j in 3..=8 {
        for id in [
            Id::Ub(j),
            Id::Vb(j),
            Id::Slip(j),
            Id::AbAbs(j),
            Id::F(j),
            Id::PeakSlip(j),
        ] {
            assert_eq!(real(&mut inst, id), 0.0);
        }
        let mut b = [7];
        inst.get_boolean(&[Id::Stuck(j).vr()], &mut b);
        assert_eq!(b[0], 0);
    }
    assert!(real(&mut inst, Id::Ub(1)) != 0.0);
}

fn outputs(inst: &mut Instance) -> Vec<f64> {
    let ids = [
        Id::Up,
        Id::Vp,
        Id::ApAbs,
        Id::PeakUp,
        Id::Slip(1),
        Id::Slip(2),
        Id::Einput,
        Id::Efriction,
    ];
    ids.iter().map(|&id| real(inst, id)).collect()
}

fn drive(inst: &mut Instance, t0: f64, steps: usize) {
    for i in 0..steps {
        let t = t0 + i as f64 * 0.01;
        set(inst, Id::Ag, 4.0 * (7.0 * t).sin());
        assert_eq!(inst.do_step(t, 0.01), Status::Ok);
    }
}

#[test]
fn saved_states_restore_and_serialize_bit_for_bit() {
    let mut inst = initialized(|_| {});
    drive(&mut inst, 0.0, 50);
    let saved = inst.save().unwrap();
    let bytes = Instance::serialize(&saved);
    drive(&mut inst, 0.5, 50);
    let reference = outputs(&mut inst);
    inst.restore(&saved);
    drive(&mut inst, 0.5, 50);
    assert_eq!(outputs(&mut inst), reference, "get/set FMU state");
    let restored = Instance::deserialize(&bytes).unwrap();
    let mut other = initialized(|i| {
        set(i, Id::Mp, 5.0); // overwritten by the state
    });
    other.restore(&restored);
    drive(&mut other, 0.5, 50);
    assert_eq!(
        outputs(&mut other),
        reference,
        "serialized and deserialized"
    );
    assert!(Instance::deserialize(&bytes[..bytes.len() - 3]).is_err());
    assert!(Instance::deserialize(b"not a state at all").is_err());
}

#[test]
fn reset_and_rerun_gives_identical_results() {
    let mut inst = initialized(|i| {
        set(i, Id::Alpha(1), 0.4);
    });
    drive(&mut inst, 0.0, 80);
    let first = outputs(&mut inst);
    assert_eq!(inst.reset(), Status::Ok);
    assert_eq!(inst.phase(), Phase::Instantiated);
    assert_eq!(
        real_param(&mut inst, Id::Alpha(1)),
        0.25,
        "defaults restored"
    );
    inst.enter_initialization_mode();
    set(&mut inst, Id::Alpha(1), 0.4);
    inst.exit_initialization_mode();
    drive(&mut inst, 0.0, 80);
    assert_eq!(outputs(&mut inst), first);
}

fn real_param(inst: &mut Instance, id: Id) -> f64 {
    inst.enter_initialization_mode();
    let x = real(inst, id);
    inst.reset();
    x
}

#[test]
fn record_in_one_step_equals_the_engine_and_an_input_derivative_driver() {
    // Oracle for the FMU plumbing: the engine driven by the same record
    // directly (linear between samples).
    let path = common::shared_record("RSN28_PARKF_C12050.AT2");
    let gm = common::truncate(&GroundMotion::read(&path, 9.81).unwrap(), 10.0);
    let mut engine = Simulator::new(&Params::default(), &Settings::default()).unwrap();
    record::run(&mut engine, &gm, 2.0).unwrap();
    let e = engine.outputs();

    let mut one_step = initialized(|i| {
        i.set_string(&[Id::RecordFile.vr()], &[path.display().to_string()]);
        set(i, Id::RecordScale, 2.0);
    });
    assert_eq!(one_step.do_step(0.0, 10.0), Status::Ok);
    assert_eq!(real(&mut one_step, Id::PeakUp), e.peak_up);
    assert_eq!(real(&mut one_step, Id::Up), e.up);

    // The same record given as an input with its slope every sample.
    let mut driver = initialized(|_| {});
    for w in gm.time.windows(2).zip(gm.accel.windows(2)) {
        let ((t0, t1), (a0, a1)) = ((w.0[0], w.0[1]), (w.1[0], w.1[1]));
        set(&mut driver, Id::Ag, 2.0 * a0);
        driver.set_input_derivatives(&[Id::Ag.vr()], &[1], &[2.0 * (a1 - a0) / (t1 - t0)]);
        assert_eq!(driver.do_step(t0, t1 - t0), Status::Ok);
    }
    let peak = real(&mut driver, Id::PeakUp);
    assert!(
        common::rel(peak, e.peak_up) < 1e-12,
        "{peak} vs {}",
        e.peak_up
    );
    assert!((real(&mut driver, Id::Up) - e.up).abs() < 1e-12 * e.peak_up);
}

#[test]
fn instances_in_several_threads_do_not_interfere() {
    let run = |alpha: f64| {
        let mut inst = initialized(|i| {
            set(i, Id::Alpha(1), alpha);
        });
        drive(&mut inst, 0.0, 200);
        outputs(&mut inst)
    };
    let expected: Vec<Vec<f64>> = [0.1, 0.3, 0.5, 0.7].iter().map(|&a| run(a)).collect();
    let handles: Vec<_> = [0.1, 0.3, 0.5, 0.7]
        .into_iter()
        .map(|a| std::thread::spawn(move || run(a)))
        .collect();
    for (h, e) in handles.into_iter().zip(expected) {
        assert_eq!(h.join().unwrap(), e);
    }
}

#[test]
fn a_record_rewritten_between_runs_is_read_again() {
    // fmi2Reset keeps a parsed record; it must not outlive a change of the file.
    // Oracle: a held 1 m/s2 step, then a 2 m/s2 step, as fresh instances see them.
    let dir = std::env::temp_dir().join(format!("sll_rewrite_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("step.csv");
    let write = |a: f64, n: usize| {
        let rows: String = (0..n)
            .map(|i| format!("{},{a}\n", i as f64 * 0.01))
            .collect();
        std::fs::write(&path, format!("time,accel\n{rows}")).unwrap();
    };
    let run = |inst: &mut Instance| {
        assert_eq!(inst.setup_experiment(0.0, None), Status::Ok);
        assert_eq!(inst.enter_initialization_mode(), Status::Ok);
        inst.set_string(&[Id::RecordFile.vr()], &[path.display().to_string()]);
        assert_eq!(inst.exit_initialization_mode(), Status::Ok);
        assert_eq!(inst.do_step(0.0, 0.5), Status::Ok);
        real(inst, Id::PeakUp)
    };
    write(1.0, 101);
    let (mut reused, _) = instance();
    let first = run(&mut reused);
    write(2.0, 102); // another size, and usually another modification time
    reused.reset();
    let second = run(&mut reused);
    let (mut fresh, _) = instance();
    assert_eq!(second, run(&mut fresh));
    assert!(second > 1.5 * first, "{second} vs {first}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_ramp_of_fext_through_input_derivatives_is_exact_in_one_step() {
    // Issue #21, as a master drives the FMU: default scene, no record,
    // der(Fext) = 1e6 N/s set with fmi2SetRealInputDerivatives, one
    // fmi2DoStep(0, 0.05). Expected: the same drift and friction work as the
    // ramp given in 400 steps (held inputs re-set at each, their derivative
    // too) and as the engine's exact reference (tests/inputs_with_slopes.rs
    // checks the engine against it); Efriction positive; the FMU's own
    // saved state accepted. The defect gave up 0.0136 m and Efriction
    // -0.070 J against 0.0196 m and +8.87 J.
    let ramp = |steps: usize| {
        let mut inst = initialized(|_| {});
        let h = 0.05 / steps as f64;
        for k in 0..steps {
            let t = k as f64 * h;
            assert_eq!(set(&mut inst, Id::Fext, 1e6 * t), Status::Ok);
            let der = inst.set_input_derivatives(&[Id::Fext.vr()], &[1], &[1e6]);
            assert_eq!(der, Status::Ok);
            assert_eq!(inst.do_step(t, h), Status::Ok);
        }
        let state = inst.save().unwrap();
        let bytes = Instance::serialize(&state);
        let back = Instance::deserialize(&bytes).expect("own saved state");
        assert_eq!(inst.restore(&back), Status::Ok);
        (real(&mut inst, Id::Up), real(&mut inst, Id::Efriction))
    };
    let (up1, ef1) = ramp(1);
    let (up400, ef400) = ramp(400);
    assert!((up1 - up400).abs() < 1e-9 * up400.abs(), "{up1} {up400}");
    assert!((ef1 - ef400).abs() < 1e-9 * ef400, "{ef1} {ef400}");
    assert!(ef1 > 8.0 && up1 > 0.019, "{up1} {ef1}");
}
