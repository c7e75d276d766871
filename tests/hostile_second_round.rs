//! Issue 24, the second hostile review: time, saved states, inputs and
//! setters. Resource locations, records and work (with the cases that run
//! in a child process) are in `tests/hostile_second_round_host.rs`.

mod common;
use common::second::{get, outputs, set, temp_dir, write_csv};
use common::started;
use stacked_live_load::fmi::instance::{Instance, Status};
use stacked_live_load::fmi::variables::Id;
use stacked_live_load::ground::synthetic;
use stacked_live_load::limits;
use std::path::Path;

fn next_up(x: f64) -> f64 {
    f64::from_bits(if x >= 0.0 {
        x.to_bits() + 1
    } else {
        x.to_bits() - 1
    })
}

fn next_down(x: f64) -> f64 {
    -next_up(-x)
}

// ---- 1. time ----

#[test]
fn a_point_beyond_rounding_is_refused_and_a_step_of_zero_never_moves_time() {
    // The issue: fmi2DoStep(-1e-12, 0) right after initialization took the
    // FMU below startTime. Expected: refused, the time stays exactly 0.
    let (mut inst, log) = started(0.0, |_| {});
    assert_eq!(inst.do_step(-1e-12, 0.0), Status::Error);
    assert!(
        log.last().contains("currentCommunicationPoint = -1e-12"),
        "{}",
        log.last()
    );
    assert_eq!(inst.last_successful_time().to_bits(), 0f64.to_bits());
    // Near 1e9 s the old tolerance was a whole second.
    let (mut inst, log) = started(1e9, |inst| {
        set(inst, Id::Ag, 2.0);
    });
    let before = outputs(&mut inst);
    for t in [1e9 + 0.5, 1e9 - 1e-3, 1e9 + 1e-6] {
        assert_eq!(inst.do_step(t, 0.0), Status::Error, "{t}");
        assert!(
            log.last().contains("does not match the FMU's time"),
            "{}",
            log.last()
        );
    }
    // Within rounding (4 units in the last place) a step of 0 is accepted and
    // moves nothing: not the time, not the state.
    for t in [1e9, next_up(1e9), next_down(next_down(1e9))] {
        assert_eq!(inst.do_step(t, 0.0), Status::Ok, "{}", log.last());
        assert_eq!(inst.last_successful_time(), 1e9);
        assert_eq!(outputs(&mut inst), before);
    }
    // A positive step below the resolution of time there does not advance.
    assert_eq!(inst.do_step(1e9, 1e-8), Status::Error);
    assert!(log.last().contains("resolution of time"), "{}", log.last());
    assert_eq!(inst.do_step(next_up(1e9), 0.25), Status::Ok);
    assert_eq!(inst.last_successful_time(), 1e9 + 0.25);
}

/// 2000 steps of `h` under a record and a varying input, the master's
/// points given by `point(i, fmu_time)`; the Real outputs after every step.
fn run_points(
    start: f64,
    h: f64,
    record: &Path,
    point: impl Fn(usize, f64) -> f64,
) -> Vec<Vec<f64>> {
    let (mut inst, log) = started(start, |inst| {
        inst.set_string(&[Id::RecordFile.vr()], &[record.display().to_string()]);
    });
    (0..2000)
        .map(|i| {
            set(&mut inst, Id::Ag, 2.0 * (i as f64 / 37.0).sin());
            let t = point(i, inst.last_successful_time());
            assert_eq!(inst.do_step(t, h), Status::Ok, "step {i}: {}", log.last());
            outputs(&mut inst)
        })
        .collect()
}

#[test]
fn results_depend_on_the_step_sizes_only_and_the_clock_does_not_drift() {
    // Expected: a master passing the FMU's own time, one passing
    // start + i h, and one passing that off by one unit in the last place
    // either way get bit-identical results at every step.
    let record = temp_dir().join("drift.csv");
    write_csv(&record, &synthetic::broadband(6.0, 0.005, 3.0));
    for (start, h) in [(0.0, 0.01), (2.5, 0.003), (-1.0, 0.01)] {
        let exact = run_points(start, h, &record, |_, now| now);
        let computed = run_points(start, h, &record, |i, _| start + i as f64 * h);
        let jittered = run_points(start, h, &record, |i, _| {
            let t = start + i as f64 * h;
            [t, next_up(t), next_down(t)][i % 3]
        });
        assert!(
            exact == computed,
            "start {start}: start + i h changed the results"
        );
        assert!(
            exact == jittered,
            "start {start}: one ulp of jitter changed the results"
        );
    }
    // The FMU's clock stays within rounding of the master's after them.
    let (mut inst, log) = started(2.5, |_| {});
    for i in 0..20000 {
        let t = 2.5 + i as f64 * 1e-3;
        assert_eq!(inst.do_step(t, 1e-3), Status::Ok, "{i}: {}", log.last());
    }
    let drift = inst.last_successful_time() - (2.5 + 20000.0 * 1e-3);
    assert!(
        drift.abs() <= limits::time_tolerance(22.5, 2.5, 20000),
        "{drift:e}"
    );
    // A master whose clock runs 1e-12 fast is refused at its first point,
    // and its own saved state still reads back.
    let (mut inst, log) = started(0.0, |_| {});
    assert_eq!(inst.do_step(0.0, 0.01), Status::Ok);
    assert_eq!(inst.do_step(0.01 * (1.0 + 1e-12), 0.01), Status::Error);
    assert!(log.last().contains("does not match"), "{}", log.last());
    let blob = Instance::serialize(&inst.save().unwrap());
    assert!(Instance::deserialize(&blob).is_ok());
}

#[test]
fn the_time_tolerance_is_rounding_and_grows_with_the_steps() {
    // Expected: (k + 4) units in the last place of max(|t|, |start|),
    // at most 1e-9 of it; nothing at t = start = 0.
    let u = limits::ulp(1.0);
    assert_eq!(u, f64::EPSILON);
    assert_eq!(limits::time_tolerance(1.0, 0.0, 0), 4.0 * u);
    assert_eq!(limits::time_tolerance(0.5, -1.0, 10), 14.0 * u);
    assert_eq!(limits::time_tolerance(1.0, 0.0, u64::MAX), 1e-9);
    assert!(limits::time_tolerance(0.0, 0.0, 100) < 1e-320);
    assert_eq!(limits::ulp(1e9), 1.1920928955078125e-7);
}

// ---- 2. saved states ----

/// Where the 8 bytes of `x` sit in `blob` (exactly once).
fn offset_of(blob: &[u8], x: f64) -> usize {
    let needle = x.to_le_bytes();
    let hits: Vec<usize> = (0..blob.len() - 7)
        .filter(|&i| blob[i..i + 8] == needle)
        .collect();
    assert_eq!(hits.len(), 1, "{x} at {hits:?}");
    hits[0]
}

fn with_word(blob: &[u8], at: usize, word: [u8; 8]) -> Vec<u8> {
    let mut bad = blob.to_vec();
    bad[at..at + 8].copy_from_slice(&word);
    bad
}

#[test]
fn every_field_of_a_saved_state_is_checked_against_the_setters_ranges() {
    // A stepped state with distinctive values where the checks look: the
    // start time, an absent block's parameter, the inputs and a slope.
    let start = 3.0625;
    let (mut inst, log) = started(start, |inst| {
        set(inst, Id::Alpha(8), 0.123456789);
        set(inst, Id::Ag, 1.5);
    });
    for i in 0..7 {
        assert_eq!(
            inst.do_step(start + i as f64 * 0.05, 0.05),
            Status::Ok,
            "{}",
            log.last()
        );
    }
    set(&mut inst, Id::Ag, 1.2345e-3);
    set(&mut inst, Id::Fext, 98765.4321);
    inst.set_input_derivatives(&[Id::Ag.vr()], &[1], &[7.25e-2]);
    let blob = Instance::serialize(&inst.save().unwrap());
    assert!(Instance::deserialize(&blob).is_ok());
    let times = offset_of(&blob, start); // start, stop, time, stop flag, steps, tSwitch
    let (time, t_switch) = (times + 16, times + 33);
    let now = inst.last_successful_time();
    let f = |x: f64| x.to_le_bytes();
    let refused: Vec<(&str, usize, [u8; 8])> = vec![
        ("tSwitch NaN", t_switch, f(f64::NAN)),
        ("tSwitch inf", t_switch, f(f64::INFINITY)),
        ("tSwitch after the time", t_switch, f(now + 1.0)),
        ("tSwitch before the start", t_switch, f(start - 1.0)),
        ("time one ulp off the simulator's", time, f(next_up(now))),
        (
            "absent alpha[8] NaN",
            offset_of(&blob, 0.123456789),
            f(f64::NAN),
        ),
        (
            "absent alpha[8] 1e300",
            offset_of(&blob, 0.123456789),
            f(1e300),
        ),
        ("absent alpha[8] -1", offset_of(&blob, 0.123456789), f(-1.0)),
        ("ag 1e300", offset_of(&blob, 1.2345e-3), f(1e300)),
        ("ag beyond its range", offset_of(&blob, 1.2345e-3), f(2e6)),
        (
            "Fext beyond its range",
            offset_of(&blob, 98765.4321),
            f(-2e18),
        ),
        ("der(ag) 1e300", offset_of(&blob, 7.25e-2), f(1e300)),
        ("der(ag) NaN", offset_of(&blob, 7.25e-2), f(f64::NAN)),
        (
            "version 3",
            8,
            [3, 0, 0, 0, blob[12], blob[13], blob[14], blob[15]],
        ),
    ];
    for (what, at, word) in refused {
        let e = match Instance::deserialize(&with_word(&blob, at, word)) {
            Ok(_) => panic!("{what}: accepted"),
            Err(e) => e,
        };
        assert!(!e.is_empty() && e.len() < 300, "{what}: {e}");
    }
    // Values inside the ranges are a state the FMU could have reached.
    let ag_in_range = with_word(&blob, offset_of(&blob, 1.2345e-3), f(-9.5e5));
    let state = Instance::deserialize(&ag_in_range).expect("ag within its range");
    assert_eq!(inst.restore(&state), Status::Ok);
    assert_eq!(get(&mut inst, Id::Ag), -9.5e5);
    // Any count of steps only widens the time tolerance, up to its cap.
    let steps = with_word(&blob, times + 25, u64::MAX.to_le_bytes());
    assert!(Instance::deserialize(&steps).is_ok());
    // A stop time is a flag and a value: a NaN or a stop before the time is
    // refused, an unknown flag too.
    let (mut inst, _) = common::instance("stop");
    assert_eq!(inst.setup_experiment(0.0, Some(12.75)), Status::Ok);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(inst.exit_initialization_mode(), Status::Ok);
    assert_eq!(inst.do_step(0.0, 0.5), Status::Ok);
    let blob = Instance::serialize(&inst.save().unwrap());
    let stop = offset_of(&blob, 12.75);
    for (what, bad) in [
        ("stop NaN", with_word(&blob, stop, f(f64::NAN))),
        ("stop before the time", with_word(&blob, stop, f(0.25))),
        ("stop flag 7", {
            let mut b = blob.clone();
            b[stop + 16] = 7;
            b
        }),
    ] {
        assert!(Instance::deserialize(&bad).is_err(), "{what}");
    }
}

// ---- 6. inputs and setters ----

#[test]
fn setters_are_all_or_nothing() {
    let (mut inst, log) = common::instance("setters");
    // One bad entry: nothing is set, and the bad one is named.
    let (tp, mp) = (Id::Tp.vr(), Id::Mp.vr());
    assert_eq!(inst.set_real(&[tp, mp], &[0.7, f64::NAN]), Status::Error);
    assert!(log.last().contains("mp = NaN"), "{}", log.last());
    assert_eq!(inst.set_real(&[tp, 999_999], &[0.7, 1.0]), Status::Error);
    assert_eq!(
        inst.set_real(&[tp, Id::Up.vr()], &[0.7, 1.0]),
        Status::Error
    );
    let (nb, solver) = (Id::NBlocks.vr(), Id::Solver.vr());
    assert_eq!(inst.set_integer(&[nb, solver], &[5, 9]), Status::Error);
    assert!(log.last().contains("solver = 9"), "{}", log.last());
    let rf = Id::RecordFile.vr();
    let strings = ["/tmp/x.csv".to_string(), "a".repeat(5000)];
    assert_eq!(inst.set_string(&[rf, rf], &strings), Status::Error);
    assert_eq!(
        inst.set_string(&[rf, tp], &["/tmp/x.csv".into(), "y".into()]),
        Status::Error
    );
    let ders = inst.set_input_derivatives(&[Id::Ag.vr(), Id::Fext.vr()], &[1, 1], &[3.0, 1e300]);
    assert_eq!(ders, Status::Error);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(inst.exit_initialization_mode(), Status::Ok);
    assert_eq!(
        (get(&mut inst, Id::Tp), get(&mut inst, Id::Mp)),
        (0.5, 1000.0)
    );
    let mut ints = [0; 2];
    assert_eq!(inst.get_integer(&[nb, solver], &mut ints), Status::Ok);
    assert_eq!(ints, [2, 1]);
    assert_eq!(inst.get_string(&[rf]).unwrap(), vec![String::new()]);
    // der(ag) = 3 was not set: a step leaves ag where it was.
    assert_eq!(inst.do_step(0.0, 1.0), Status::Ok);
    assert_eq!(get(&mut inst, Id::Ag), 0.0);
    // All good entries: all set.
    let (mut inst, _) = common::instance("setters");
    assert_eq!(inst.set_real(&[tp, mp], &[0.7, 2000.0]), Status::Ok);
    assert_eq!(inst.set_integer(&[nb, solver], &[5, 2]), Status::Ok);
}

#[test]
fn input_slopes_keep_the_inputs_within_their_ranges() {
    // The issue: der(ag) took ag to 5e12 over a long step, a value
    // fmi2SetReal then refused. Expected: the step is refused, naming the
    // slope and the range; nothing changed; a shorter step reaches the end
    // of the range exactly, and that value can be set again.
    let (mut inst, log) = started(0.0, |_| {});
    for (input, slope, h, end) in [(Id::Ag, 1e9, 1e-3, 1e6), (Id::Fext, -1e21, 1e-3, -1e18)] {
        let name = input.name();
        assert_eq!(
            inst.set_input_derivatives(&[input.vr()], &[1], &[slope]),
            Status::Ok
        );
        let now = inst.last_successful_time();
        assert_eq!(inst.do_step(now, 1.0), Status::Error);
        let m = log.last();
        assert!(
            m.contains(&format!("der({name}) = ")) && m.contains("outside its range"),
            "{m}"
        );
        assert_eq!(inst.last_successful_time(), now);
        assert_eq!(get(&mut inst, input), 0.0);
        assert_eq!(inst.do_step(now, h), Status::Ok, "{}", log.last());
        let x = get(&mut inst, input);
        assert!((x - end).abs() <= 1e-9 * end.abs(), "{name} = {x}");
        assert_eq!(set(&mut inst, input, x), Status::Ok, "{}", log.last());
        assert_eq!(set(&mut inst, input, 0.0), Status::Ok);
    }
}

#[test]
fn a_ramp_to_the_end_of_a_range_later_on_leaves_a_state_that_is_accepted() {
    // Found by a fuzzing master (session 20): away from t = 0 the step's
    // length in the FMU's clock, (t + h) - t, differs from h by rounding, and
    // a ramp checked as x + x' h within its range ended an ulp past it:
    // fmi2DoStep said OK, then fmi2GetReal gave a value fmi2SetReal refused
    // and the FMU refused its own saved state. Expected: the input ends
    // within its range (here exactly at its end, as the master computed),
    // can be set again, and the saved state is accepted.
    for (input, t0, slope, h, limit) in [
        (Id::Ag, 1.7, 20810895.459684774, 0.048051752599363985, 1e6),
        (Id::Ag, 3.3, 949913074.2068369, 0.0010527279044295552, 1e6),
        (
            Id::Fext,
            0.1,
            -1.1945912595734372e19,
            0.08371064093982057,
            1e18,
        ),
        (
            Id::Fext,
            3.3,
            -1.1945912595734372e19,
            0.08371064093982057,
            1e18,
        ),
    ] {
        let name = input.name();
        let (mut inst, log) = started(0.0, |_| {});
        assert_eq!(inst.do_step(0.0, t0), Status::Ok);
        let now = inst.last_successful_time();
        // The case's premise: over the clock's length the ramp leaves the range.
        assert!((slope * ((now + h) - now)).abs() > limit, "{name} at {t0}");
        assert!((slope * h).abs() <= limit);
        assert_eq!(set(&mut inst, input, 0.0), Status::Ok);
        let ders = inst.set_input_derivatives(&[input.vr()], &[1], &[slope]);
        assert_eq!(ders, Status::Ok);
        assert_eq!(inst.do_step(now, h), Status::Ok, "{}", log.last());
        let x = get(&mut inst, input);
        assert_eq!(x, slope * h, "{name} at {t0}");
        assert_eq!(set(&mut inst, input, x), Status::Ok, "{}", log.last());
        let blob = Instance::serialize(&inst.save().unwrap());
        let state = Instance::deserialize(&blob);
        assert!(state.is_ok(), "{name} at {t0}: {:?}", state.err());
        assert_eq!(inst.restore(&state.unwrap()), Status::Ok, "{}", log.last());
    }
}

#[test]
fn running_peaks_never_fall_after_a_step_of_zero_length() {
    // Found by a fuzzing master (session 20): fmi2DoStep(t, 0) after a jump
    // of Fext showed the jumped absolute acceleration in peakApAbs, and the
    // peak fell back when the master set Fext again at the same instant: a
    // step of length 0 took no substep, and the engine's running peak never
    // saw the value the step committed. Expected: the peak after the
    // committed step stays, whatever the inputs set next; the step after it
    // goes on from there (a tentative input, never stepped with, leaves no
    // mark: the outputs follow the inputs set).
    let (mut inst, log) = started(0.0, |inst| {
        set(inst, Id::Ag, 1.0);
    });
    assert_eq!(inst.do_step(0.0, 0.1), Status::Ok);
    let before = get(&mut inst, Id::PeakApAbs);
    set(&mut inst, Id::Fext, 4.0e5);
    assert!(
        get(&mut inst, Id::PeakApAbs) > 2.0 * before,
        "the jump shows"
    );
    set(&mut inst, Id::Fext, 0.0);
    assert_eq!(
        get(&mut inst, Id::PeakApAbs),
        before,
        "a tentative input leaves no mark"
    );
    set(&mut inst, Id::Fext, 4.0e5);
    assert_eq!(inst.do_step(0.1, 0.0), Status::Ok, "{}", log.last());
    let committed = get(&mut inst, Id::PeakApAbs);
    assert!(committed > 2.0 * before);
    set(&mut inst, Id::Fext, 0.0);
    assert_eq!(get(&mut inst, Id::PeakApAbs), committed);
    assert_eq!(inst.do_step(0.1, 0.0), Status::Ok);
    assert_eq!(get(&mut inst, Id::PeakApAbs), committed);
    assert_eq!(inst.do_step(0.1, 0.05), Status::Ok);
    assert!(get(&mut inst, Id::PeakApAbs) >= committed);
}
