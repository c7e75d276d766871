//! Issue 13: the FMU inside somebody else's process. Every hostile input
//! must end in a clear fmi2Error (or a correct, finite fmi2OK), quickly, with
//! the process alive and its memory bounded. Cases that could hang or abort
//! run in a child process (this test binary again, test `child_entry`, with
//! `SLL_HOSTILE_CASE` set) under a wall-clock limit and a 4 GiB address-space
//! limit: a hang fails on the time limit, an abort on the exit status.
//!
//! The fuzz of saved states and call sequences runs a bounded, seeded number
//! of cases; `SLL_FUZZ_CASES=200000 cargo test --test hostile_inputs fuzz`
//! runs a longer one (`SLL_FUZZ_SEED` picks another seed).

mod common;
use common::Capture;
use common::Rng;
use stacked_live_load::fmi::instance::{Instance, Phase, Status};
use stacked_live_load::fmi::variables::{self, Causality, Id, Kind};
use stacked_live_load::limits;
use stacked_live_load::GroundMotion;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

fn instance() -> (Instance, Capture) {
    common::instance("hostile")
}

fn set(inst: &mut Instance, id: Id, x: f64) -> Status {
    inst.set_real(&[id.vr()], &[x])
}

/// Initializes with `setup`; returns the status of fmi2ExitInitializationMode.
fn init(setup: impl FnOnce(&mut Instance)) -> (Instance, Capture, Status) {
    let (mut inst, log) = instance();
    assert_eq!(inst.setup_experiment(0.0, None), Status::Ok);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    setup(&mut inst);
    let status = inst.exit_initialization_mode();
    (inst, log, status)
}

fn real_outputs() -> Vec<Id> {
    variables::table()
        .into_iter()
        .filter(|v| v.id.kind() == Kind::Real && v.id.causality() == Causality::Output)
        .map(|v| v.id)
        .collect()
}

/// Every Real output; fails the test on a non-finite one.
fn assert_outputs_finite(inst: &mut Instance, what: &str) {
    let ids = real_outputs();
    let vrs: Vec<u32> = ids.iter().map(|id| id.vr()).collect();
    let mut out = vec![f64::NAN; vrs.len()];
    assert_eq!(inst.get_real(&vrs, &mut out), Status::Ok, "{what}");
    for (id, x) in ids.iter().zip(&out) {
        assert!(x.is_finite(), "{what}: {} = {x} behind fmi2OK", id.name());
    }
}

/// Every output derivative (orders 1 and 2) of the continuous outputs:
/// fails the test on a non-finite one behind fmi2OK (solver 3 has none).
fn assert_derivatives_finite(inst: &mut Instance, what: &str) {
    let ids: Vec<Id> = real_outputs()
        .into_iter()
        .filter(|id| id.is_continuous())
        .collect();
    for order in [1, 2] {
        let vrs: Vec<u32> = ids.iter().map(|id| id.vr()).collect();
        let mut out = vec![f64::NAN; vrs.len()];
        if inst.get_output_derivatives(&vrs, &vec![order; vrs.len()], &mut out) == Status::Ok {
            for (id, x) in ids.iter().zip(&out) {
                assert!(
                    x.is_finite(),
                    "{what}: d{order} {} = {x} behind fmi2OK",
                    id.name()
                );
            }
        }
    }
}

fn temp_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sll_hostile_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Initialization with `recordFile = path`: must fail with a message that
/// contains every one of `expected`, and return that message.
fn record_refused(path: &Path, expected: &[&str]) -> String {
    let (_, log, status) = init(|inst| {
        inst.set_string(&[Id::RecordFile.vr()], &[path.display().to_string()]);
    });
    let message = log.last();
    assert_eq!(status, Status::Error, "{}: {message}", path.display());
    assert!(
        message.starts_with("fmi2ExitInitializationMode: recordFile: "),
        "{message}"
    );
    for e in expected {
        assert!(message.contains(e), "expected `{e}` in: {message}");
    }
    message
}

// ---- the child-process harness ----

/// Runs case `case` in a child process ([`common::in_child`]).
fn in_child(case: &str, limit: Duration) {
    common::in_child(case, limit, &temp_dir(), |_| {});
}

/// The entry point of the child processes (does nothing in a normal run).
#[test]
fn child_entry() {
    if let Ok(case) = std::env::var("SLL_HOSTILE_CASE") {
        run_case(&case);
    }
}

fn run_case(case: &str) {
    let dir = temp_dir();
    match case {
        #[cfg(unix)] // (a named pipe: Unix only)
        "fifo" => {
            let fifo = dir.join("record.AT2");
            let c = std::ffi::CString::new(fifo.display().to_string()).unwrap();
            assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
            record_refused(&fifo, &["is not a regular file"]);
        }
        "dev_zero" => {
            record_refused(Path::new("/dev/zero"), &["/dev/zero", "not a regular file"]);
        }
        "directory" => {
            record_refused(&dir, &["not a regular file"]);
        }
        "no_newline" => {
            // 256 MiB without a newline (sparse: zero bytes).
            let file = dir.join("long.csv");
            let f = std::fs::File::create(&file).unwrap();
            f.set_len(256 << 20).unwrap();
            let m = record_refused(&file, &[":1: the line is longer than 4096 bytes"]);
            assert!(m.len() < 300 + file.display().to_string().len(), "{m}");
        }
        "too_big" => {
            let file = dir.join("huge.csv");
            let f = std::fs::File::create(&file).unwrap();
            f.set_len(limits::MAX_RECORD_BYTES + 1).unwrap();
            record_refused(&file, &["more than the limit of 536870912 bytes"]);
        }
        "npts_huge" => {
            let file = dir.join("huge_npts.AT2");
            std::fs::write(
                &file,
                "h\nh\nh\nNPTS= 1000000000000, DT= .0100 SEC\n.1 .2\n",
            )
            .unwrap();
            record_refused(&file, &[":4: NPTS = 1e12 is not allowed"]);
        }
        "npts_within_limit_but_not_in_the_file" => {
            let file = dir.join("short.AT2");
            std::fs::write(&file, "h\nh\nh\nNPTS= 9000000, DT= .0100 SEC\n.1 .2\n").unwrap();
            record_refused(&file, &[":4: NPTS = 9000000 but the file has only"]);
        }
        "work_bound" => {
            // Inside every range, but 1e4 s at Tp = 1 ms needs 1.3e8 substeps.
            let (mut inst, log, status) = init(|inst| {
                set(inst, Id::Tp, 1e-3);
            });
            assert_eq!(status, Status::Ok);
            let started = Instant::now();
            assert_eq!(inst.do_step(0.0, 1e4), Status::Error);
            assert!(log.last().contains("internal steps"), "{}", log.last());
            assert!(log.last().contains("limit of 1e8"), "{}", log.last());
            assert!(started.elapsed() < Duration::from_secs(1));
            // The instance was not harmed: shorter steps go on.
            assert_eq!(inst.do_step(0.0, 1.0), Status::Ok, "{}", log.last());
        }
        "solver3_stiff" => {
            // Stiff regularized friction: the step follows the stability
            // bound, and a run beyond the work bound is refused up front.
            let (mut inst, log, status) = init(|inst| {
                inst.set_integer(&[Id::Solver.vr()], &[3]);
                set(inst, Id::FrictionEps, 1e-5);
                set(inst, Id::Mus(1), 5.0);
                set(inst, Id::Muk(1), 5.0);
                set(inst, Id::Ag, 3.0);
            });
            assert_eq!(status, Status::Ok, "{}", log.last());
            assert_eq!(inst.do_step(0.0, 1e4), Status::Error);
            assert!(log.last().contains("internal steps"), "{}", log.last());
            assert_eq!(inst.do_step(0.0, 0.05), Status::Ok, "{}", log.last());
            assert_outputs_finite(&mut inst, "stiff solver 3");
        }
        "fuzz_states" => fuzz_saved_states(fuzz_cases(2000)),
        "fuzz_calls" => fuzz_call_sequences(fuzz_cases(2000)),
        other => panic!("unknown case {other}"),
    }
    // The child's own folder (its process id): nothing else uses it.
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn record_files_never_block_abort_or_read_unbounded() {
    for case in [
        "fifo",
        "dev_zero",
        "directory",
        "no_newline",
        "too_big",
        "npts_huge",
        "npts_within_limit_but_not_in_the_file",
    ] {
        in_child(case, Duration::from_secs(20));
    }
}

#[test]
fn work_beyond_the_bound_is_refused_quickly() {
    in_child("work_bound", Duration::from_secs(20));
    in_child("solver3_stiff", Duration::from_secs(60));
}

#[test]
fn messages_quote_a_few_characters_with_the_line_number() {
    let dir = temp_dir();
    let secret = "root:x:0:0:root:/root:/bin/bash:a-secret-that-must-not-leak";
    let cases: [(&str, String, &str); 5] = [
        (
            "passwd",
            format!("{secret}\nsecond\n"),
            ":1: expected two numbers",
        ),
        (
            "key.AT2",
            format!("h\nh\nh\n{secret}\n"),
            ":4: expected NPTS and DT",
        ),
        (
            "values.AT2",
            format!("h\nh\nh\nNPTS= 2, DT= .01\n0.1 {secret}\n"),
            ":5: expected a number",
        ),
        (
            "csv",
            format!("time,accel\n0,0\n0.01,{secret}\n"),
            ":3: expected two numbers",
        ),
        (
            "inf.csv",
            "0,0\n0.01,1e400\n".to_string(),
            ":2: value `1e400` is not an acceleration",
        ),
    ];
    for (name, text, expected) in cases {
        let file = dir.join(name);
        std::fs::write(&file, text).unwrap();
        let m = record_refused(&file, &[expected]);
        assert!(!m.contains("a-secret"), "{m}");
        // What the file holds appears only inside the quote.
        let quoted = m.split('`').nth(1).unwrap_or("");
        assert!(quoted.chars().count() <= limits::MAX_QUOTE_CHARS + 3, "{m}");
    }
}

#[test]
fn record_limits_on_time_steps_and_values() {
    let dir = temp_dir();
    for (name, text, expected) in [
        (
            "dt.AT2",
            "h\nh\nh\nNPTS= 2, DT= 1e-9\n1 2\n",
            ":4: DT = 1e-9 is not allowed",
        ),
        (
            "zero_dt.csv",
            "0,0\n1e-9,1\n",
            ":2: time 1e-9 does not increase",
        ),
        ("late.csv", "0,0\n1e7,1\n", ":2: time `1e7` is not allowed"),
        (
            "big.AT2",
            "h\nh\nh\nNPTS= 2, DT= 0.01\n1 1e6\n",
            ":5: value `1e6` is not an acceleration",
        ),
    ] {
        let file = dir.join(name);
        std::fs::write(&file, text).unwrap();
        record_refused(&file, &[expected]);
    }
    // A real record still reads (the shared Kobe record, 0.01 s, in g).
    let gm = common::read_shared("RSN1106_KOBE_KJM000.AT2", 9.81);
    assert!(gm.time.len() > 1000 && gm.pga() > 5.0);
}

#[test]
fn times_out_of_range_or_below_their_resolution_are_refused() {
    // At t = 1e16 s a step of 1 s rounds back to t: it would return OK
    // without simulating anything. Start and stop times are limited to
    // 1e9 s (limits::MAX_TIME), named with the range.
    let (mut inst, log) = instance();
    assert_eq!(inst.setup_experiment(1e16, None), Status::Error);
    assert!(log.last().contains("startTime = 1e16"), "{}", log.last());
    assert!(log.last().contains("1e9"), "{}", log.last());
    let (mut inst, log) = instance();
    assert_eq!(inst.setup_experiment(0.0, Some(1e300)), Status::Error);
    assert!(log.last().len() < 200, "{}", log.last());
    // Within the range, a step below the resolution of time is refused by
    // name (at 1e9 s a double resolves about 1.2e-7 s).
    let (mut inst, log) = instance();
    assert_eq!(inst.setup_experiment(1e9, None), Status::Ok);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(inst.exit_initialization_mode(), Status::Ok);
    assert_eq!(inst.do_step(1e9, 1e-8), Status::Error);
    assert!(log.last().contains("resolution of time"), "{}", log.last());
    assert_eq!(inst.do_step(1e9, 0.01), Status::Ok, "{}", log.last());
}

#[test]
fn record_headers_and_marks_from_the_review() {
    // Found in review: a byte-order mark before a CSV's first line, an AT2
    // with one sample (a CSV needs two), a 300-digit DT copied into the log.
    let dir = temp_dir();
    let csv = dir.join("bom.csv");
    std::fs::write(&csv, "\u{feff}time,accel\n0,0\n0.01,1\n").unwrap();
    let gm = GroundMotion::read(&csv, 9.81).expect("a CSV with a byte-order mark reads");
    assert_eq!((gm.time.len(), gm.accel[1]), (2, 1.0));
    let one = dir.join("one.AT2");
    std::fs::write(&one, "h\nh\nh\nNPTS= 1, DT= .01\n0.1\n").unwrap();
    let e = GroundMotion::read(&one, 9.81).unwrap_err().to_string();
    assert!(e.contains("NPTS = 1 is not allowed"), "{e}");
    let huge = dir.join("huge_dt.AT2");
    std::fs::write(&huge, "h\nh\nh\nNPTS= 2, DT= 1e300\n0.1 0.2\n").unwrap();
    let e = GroundMotion::read(&huge, 9.81).unwrap_err().to_string();
    assert!(e.contains("DT = 1e300 is not allowed"), "{e}");
    assert!(e.len() < 250, "{e}");
}

#[test]
fn a_long_recordfile_string_is_refused() {
    let (mut inst, log) = instance();
    let long = "a".repeat(limits::MAX_PATH_BYTES + 1);
    assert_eq!(
        inst.set_string(&[Id::RecordFile.vr()], &[long]),
        Status::Error
    );
    assert!(log.last().contains("at most 4096 bytes"), "{}", log.last());
    assert!(log.last().len() < 200);
}

#[test]
fn parameters_outside_their_range_are_refused_naming_range() {
    let cases: [(Id, f64, &str); 14] = [
        (Id::Tp, 5e-324, "Tp = 5e-324 "),
        (Id::Tp, 1e-9, "Tp = 1e-9 "),
        (Id::Tp, 1e4, "Tp = 10000"),
        (Id::MaxStep, 1e-12, "maxStep = 1e-12 "),
        (Id::RecordScale, 1e200, "recordScale = 1e200 "),
        (Id::Mp, 1e300, "mp = 1e300 "),
        (Id::G, 0.0, "g = 0"),
        (Id::G, 1e6, "g = 1000000 "),
        (Id::Alpha(3), 1e-12, "alpha[3] = 1e-12 "),
        (Id::Mus(2), 1e12, "mus[2] = 1e12 "),
        (Id::Zeta, -0.1, "zeta = -0.1"),
        (Id::FrictionEps, 1e-9, "frictionEps = 1e-9 "),
        // Inputs too: an absurd force or acceleration would overflow the energies.
        (Id::Fext, 1e300, "Fext = 1e300 "),
        (Id::Ag, -1e300, "ag = -1e300 "),
    ];
    for (id, value, expected) in cases {
        let (mut inst, log) = instance();
        assert_eq!(set(&mut inst, id, value), Status::Error, "{expected}");
        let m = log.last();
        assert!(m.starts_with(&format!("fmi2SetReal: {expected}")), "{m}");
        assert!(m.contains("it must be"), "{m}");
        // Numbers in exponent form where decimals would run long.
        assert!(m.len() < 160, "{m}");
    }
    // Both ends of every range are allowed, values just outside are not.
    for &(name, lo, hi, _) in &stacked_live_load::physics::params::RANGES {
        use stacked_live_load::physics::params::check_scalar;
        let hi_ok = if name == "zeta" {
            hi * (1.0 - 1e-12)
        } else {
            hi
        };
        assert!(
            check_scalar(name, lo).is_ok() && check_scalar(name, hi_ok).is_ok(),
            "{name}"
        );
        let below = if lo == 0.0 {
            -1e-300
        } else {
            lo - lo.abs() * 1e-9
        };
        assert!(check_scalar(name, below).is_err(), "{name} below {lo}");
        assert!(
            check_scalar(name, hi + hi.abs() * 1e-9).is_err(),
            "{name} above {hi}"
        );
    }
}

#[test]
fn what_the_existing_uses_need_stays_allowed() {
    // Stability map: Tp 0.01-10 s, communication steps 1e-4-1 s, maxStep
    // down to 1e-5 (the references); closed forms: alpha 1e-6 and 1e9,
    // mu 1e6 (rigid). Each initializes and steps to a finite result.
    for (tp, max_step, alpha, mu, h) in [
        (0.01, 1e-5, 0.5, 0.15, 1e-4),
        (10.0, 0.0, 1e-6, 1e6, 1.0),
        (0.01, 0.0, 1e9, 0.1, 1.0),
        (1.0, 1.0, 0.5, 0.1, 0.3),
    ] {
        let (mut inst, log, status) = init(|inst| {
            set(inst, Id::Tp, tp);
            set(inst, Id::MaxStep, max_step);
            set(inst, Id::Alpha(1), alpha);
            set(inst, Id::Mus(1), mu);
            set(inst, Id::Muk(1), mu);
            set(inst, Id::Ag, 2.0);
        });
        assert_eq!(status, Status::Ok, "{}", log.last());
        assert_eq!(inst.do_step(0.0, h), Status::Ok, "{}", log.last());
        assert_outputs_finite(&mut inst, "existing use");
    }
}

#[test]
fn non_finite_results_are_an_error_naming_the_variable_and_time() {
    // An input of 1e300 m/s2 would overflow the energies: it is refused when
    // set (the input ranges), so no step can start from it.
    let (mut inst, log, status) = init(|_| {});
    assert_eq!(status, Status::Ok);
    assert_eq!(set(&mut inst, Id::Ag, 1e300), Status::Error);
    assert!(log.last().contains("ag = "), "{}", log.last());
    // The largest allowed inputs and slopes, on the heaviest scene: finite.
    // (The slopes take each input from one end of its range to its middle.)
    let (mut inst, log, status) = init(|inst| {
        set(inst, Id::Mp, 1e12);
        set(inst, Id::Alpha(1), 1e9);
        set(inst, Id::Ag, -1e6);
        set(inst, Id::Fext, -1e18);
    });
    assert_eq!(status, Status::Ok, "{}", log.last());
    assert_eq!(
        inst.set_input_derivatives(&[Id::Ag.vr(), Id::Fext.vr()], &[1, 1], &[1e9, 1e21]),
        Status::Ok
    );
    assert_eq!(inst.do_step(0.0, 1e-3), Status::Ok, "{}", log.last());
    let mut inputs = [0.0; 2];
    assert_eq!(
        inst.get_real(&[Id::Ag.vr(), Id::Fext.vr()], &mut inputs),
        Status::Ok
    );
    assert_eq!(inputs, [-1e6 + 1e9 * 1e-3, -1e18 + 1e21 * 1e-3]);
    assert!(
        inputs[0].abs() < 1e-6 && inputs[1].abs() < 1e6,
        "{inputs:?}"
    );
    assert_eq!(inst.do_step(1e-3, 1.0), Status::Ok, "{}", log.last());
    assert_outputs_finite(&mut inst, "largest inputs");
    // (The check behind every step, `limits::first_non_finite`, is unit-tested
    // in src/limits.rs; corrupted saved states reach it in the fuzz below.)
    // The largest record values at the largest recordScale stay finite.
    let file = temp_dir().join("loud.csv");
    std::fs::write(
        &file,
        "0,0
0.01,1e6
0.02,-1e6
0.03,0
",
    )
    .unwrap();
    let (mut inst, log, status) = init(|inst| {
        set(inst, Id::RecordScale, 1e3);
        set(inst, Id::Tp, 1e3);
        inst.set_string(&[Id::RecordFile.vr()], &[file.display().to_string()]);
    });
    assert_eq!(status, Status::Ok, "{}", log.last());
    assert_eq!(inst.do_step(0.0, 1.0), Status::Ok, "{}", log.last());
    assert_outputs_finite(&mut inst, "loudest record");
    // A force that would overflow the acceleration is refused when set.
    let (mut inst, log) = instance();
    set(&mut inst, Id::Mp, 1e-3);
    assert_eq!(set(&mut inst, Id::Fext, 1e308), Status::Error);
    assert!(log.last().contains("Fext = "), "{}", log.last());
}

#[test]
fn solver_3_closes_its_energy_balance_on_1_to_8_blocks() {
    // The issue measured the balance off by 130 % of the input with 8 blocks
    // at the default settings: the step ignored the stiffness of the upper
    // interfaces. The tolerance, 1e-5 of the input energy, is solver 3's
    // documented one (docs/robustness.md; measured worst 6.3e-7 here).
    let dir = temp_dir();
    let gm = common::broadband(5.0, 0.005, 0.4 * 9.81);
    let file = dir.join("broadband.csv");
    let text: String = gm
        .time
        .iter()
        .zip(&gm.accel)
        .map(|(t, a)| format!("{t:.17e},{a:.17e}\n"))
        .collect();
    std::fs::write(&file, text).unwrap();
    for n in 1..=8 {
        let (mut inst, log, status) = init(|inst| {
            inst.set_integer(&[Id::Solver.vr(), Id::NBlocks.vr()], &[3, n]);
            inst.set_string(&[Id::RecordFile.vr()], &[file.display().to_string()]);
        });
        assert_eq!(status, Status::Ok, "{}", log.last());
        assert_eq!(
            inst.do_step(0.0, gm.duration()),
            Status::Ok,
            "{}",
            log.last()
        );
        assert_outputs_finite(&mut inst, "solver 3");
        let ids = [
            Id::Einput,
            Id::Ekinetic,
            Id::Estrain,
            Id::Eviscous,
            Id::Efriction,
        ];
        let mut e = [0.0; 5];
        let vrs: Vec<u32> = ids.iter().map(|id| id.vr()).collect();
        assert_eq!(inst.get_real(&vrs, &mut e), Status::Ok);
        let residual = (e[0] - e[1..].iter().sum::<f64>()) / e[0];
        eprintln!("solver 3, {n} blocks: energy residual {residual:.2e} of the input");
        assert!(residual.abs() < 1e-5, "{n} blocks: residual {residual:e}");
    }
    // A scene whose stable step would be below 1e-7 s is refused, by name.
    let (_, log, status) = init(|inst| {
        inst.set_integer(&[Id::Solver.vr()], &[3]);
        set(inst, Id::FrictionEps, 1e-7);
        set(inst, Id::Mus(1), 1e6);
        set(inst, Id::Muk(1), 1e6);
    });
    assert_eq!(status, Status::Error);
    assert!(
        log.last().contains("frictionEps = 1e-7 is not allowed"),
        "{}",
        log.last()
    );
    assert!(
        log.last().contains("interface 1 is the stiffest"),
        "{}",
        log.last()
    );
}

// ---- saved states and call sequences ----

fn fuzz_cases(default: usize) -> usize {
    std::env::var("SLL_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

fn fuzz_seed() -> u64 {
    std::env::var("SLL_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0x5EED_1313)
}

/// A random scene (any solver, 0..8 blocks), initialized with a fresh
/// seeded record and stepped a random time; returns it and its record file.
fn random_instance(rng: &mut Rng, dir: &Path) -> Instance {
    let (mut inst, _) = instance();
    let start = [0.0, 2.5, -1.0][rng.below(3)];
    assert_eq!(inst.setup_experiment(start, Some(start + 50.0)), Status::Ok);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    let n = rng.below(9) as i32;
    let solver = 1 + rng.below(3) as i32;
    inst.set_integer(&[Id::NBlocks.vr(), Id::Solver.vr()], &[n, solver]);
    set(&mut inst, Id::Tp, 10f64.powf(rng.uniform(-1.5, 0.7)));
    for j in 1..=8 {
        set(&mut inst, Id::Alpha(j), 10f64.powf(rng.uniform(-1.5, 0.3)));
        let mu = if rng.below(8) == 0 {
            0.0
        } else {
            rng.uniform(0.02, 0.4)
        };
        set(&mut inst, Id::Mus(j), mu * rng.uniform(1.0, 1.5));
        set(&mut inst, Id::Muk(j), mu);
    }
    if rng.below(2) == 0 {
        let seed = rng.below(16);
        let file = dir.join(format!("fuzz_{seed}.csv"));
        if !file.exists() {
            let gm =
                stacked_live_load::ground::synthetic::broadband(4.0, 0.01, rng.uniform(1.0, 8.0));
            let text: String = gm
                .time
                .iter()
                .zip(&gm.accel)
                .map(|(t, a)| format!("{t},{a}\n"))
                .collect();
            std::fs::write(&file, text).unwrap();
        }
        inst.set_string(&[Id::RecordFile.vr()], &[file.display().to_string()]);
    }
    assert_eq!(inst.exit_initialization_mode(), Status::Ok);
    let mut t = start;
    for _ in 0..rng.below(6) {
        set(&mut inst, Id::Ag, rng.uniform(-6.0, 6.0));
        let h = [0.01, 0.1, 0.37][rng.below(3)];
        assert_eq!(inst.do_step(t, h), Status::Ok);
        t += h;
    }
    inst
}

/// One 8-byte word or a byte of `blob` replaced, or the blob cut or extended.
fn mutate(rng: &mut Rng, blob: &mut Vec<u8>) {
    let specials = [
        f64::NAN,
        f64::INFINITY,
        -f64::INFINITY,
        -0.0,
        5e-324,
        1e-300,
        1e300,
        -1.0,
        1e9,
        0.5,
    ];
    match rng.below(6) {
        0 | 1 => {
            let at = rng.below(blob.len().saturating_sub(8).max(1));
            let x: f64 = specials[rng.below(specials.len())];
            blob[at..at + 8].copy_from_slice(&x.to_le_bytes());
        }
        2 => {
            let at = rng.below(blob.len().saturating_sub(8).max(1));
            let word = (rng.next_f64() * u64::MAX as f64) as u64;
            blob[at..at + 8].copy_from_slice(&word.to_le_bytes());
        }
        3 => {
            let at = rng.below(blob.len());
            blob[at] ^= 1 << rng.below(8);
        }
        4 => blob.truncate(rng.below(blob.len())),
        _ => blob.extend((0..rng.below(16)).map(|i| i as u8)),
    }
}

/// Restores `blob` into a fresh instance and steps it: any outcome but a
/// panic, a hang, or fmi2OK with a non-finite output is fine.
fn try_blob(blob: &[u8], rng: &mut Rng) -> bool {
    let Ok(state) = Instance::deserialize(blob) else {
        return false;
    };
    let (mut inst, _) = instance();
    if inst.restore(&state) != Status::Ok {
        return true;
    }
    if inst.phase() == Phase::StepComplete || inst.phase() == Phase::InitializationMode {
        if inst.phase() == Phase::InitializationMode
            && inst.exit_initialization_mode() != Status::Ok
        {
            return true;
        }
        let t = inst.last_successful_time();
        let h = [0.0, 0.01, 0.2][rng.below(3)];
        if inst.do_step(t, h) == Status::Ok {
            assert_outputs_finite(&mut inst, "after a restored state");
            assert_derivatives_finite(&mut inst, "after a restored state");
        }
    }
    true
}

fn fuzz_saved_states(cases: usize) {
    let dir = temp_dir();
    let mut rng = Rng(fuzz_seed());
    let (mut accepted, mut refused) = (0, 0);
    for case in 0..cases {
        let mut inst = random_instance(&mut rng, &dir);
        let state = inst.save().unwrap();
        let blob = Instance::serialize(&state);
        // An untouched blob is always accepted and round-trips.
        let back = Instance::deserialize(&blob)
            .unwrap_or_else(|e| panic!("case {case}: a valid state refused: {e}"));
        assert_eq!(Instance::serialize(&back), blob);
        let mut bad = blob.clone();
        mutate(&mut rng, &mut bad);
        if bad == blob {
            continue;
        }
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            try_blob(&bad, &mut Rng(case as u64 + 1))
        }));
        match result {
            Ok(true) => accepted += 1,
            Ok(false) => refused += 1,
            Err(_) => panic!(
                "case {case}: a mutated state panicked (seed {})",
                fuzz_seed()
            ),
        }
    }
    eprintln!("{cases} mutated states: {refused} refused, {accepted} accepted and stepped");
}

fn fuzz_call_sequences(cases: usize) {
    let dir = temp_dir();
    let mut rng = Rng(fuzz_seed() ^ 0xCA11);
    let hostile = [
        f64::NAN,
        f64::INFINITY,
        0.0,
        -1.0,
        5e-324,
        1e-12,
        1e-3,
        0.5,
        1e3,
        1e300,
    ];
    let params = [
        Id::Mp,
        Id::Tp,
        Id::Zeta,
        Id::G,
        Id::RecordScale,
        Id::MaxStep,
        Id::FrictionEps,
        Id::Alpha(2),
        Id::Mus(1),
        Id::Muk(1),
        Id::Ag,
        Id::Fext,
    ];
    for case in 0..cases {
        let mut inst = random_instance(&mut rng, &dir);
        let mut saved = inst.save().ok();
        for _ in 0..8 {
            let t = inst.last_successful_time();
            let status = match rng.below(9) {
                0 => set(
                    &mut inst,
                    params[rng.below(params.len())],
                    hostile[rng.below(hostile.len())],
                ),
                1 => inst.do_step(t, [0.0, 1e-3, 0.05, 1.0][rng.below(4)]),
                2 if rng.below(2) == 0 => inst.do_step(t + hostile[rng.below(hostile.len())], 0.01),
                // A point a few units in the last place off, a step of 0 or not.
                2 => {
                    let ulps = rng.below(13) as i64 - 6;
                    let off = f64::from_bits((t.to_bits() as i64 + ulps) as u64);
                    inst.do_step(off, [0.0, 0.01][rng.below(2)])
                }
                3 => {
                    saved = inst.save().ok();
                    Status::Ok
                }
                4 => saved.as_ref().map_or(Status::Ok, |s| inst.restore(s)),
                5 => inst.reset(),
                6 => inst.enter_initialization_mode(),
                7 => inst.exit_initialization_mode(),
                _ => inst.set_input_derivatives(
                    &[Id::Ag.vr()],
                    &[1],
                    &[hostile[rng.below(hostile.len())]],
                ),
            };
            let readable = matches!(inst.phase(), Phase::StepComplete);
            if status == Status::Ok && readable {
                assert_outputs_finite(&mut inst, &format!("call sequence case {case}"));
            }
            // The FMU never refuses its own state, and its time never falls
            // below the start.
            if let Ok(state) = inst.save() {
                let blob = Instance::serialize(&state);
                if let Err(e) = Instance::deserialize(&blob) {
                    panic!("call sequence case {case}: its own state refused: {e}");
                }
            }
            let start = if inst.phase() == Phase::Instantiated {
                0.0
            } else {
                -1.0
            };
            assert!(inst.last_successful_time() >= start, "case {case}");
        }
    }
    eprintln!("{cases} call sequences of 8 calls");
}

#[test]
fn fuzz_saved_states_and_call_sequences_in_a_child() {
    // 2000 cases each (about 10 s and 20 s); a hang is caught by the time
    // limit, which grows with SLL_FUZZ_CASES.
    let limit = Duration::from_secs(300 * (fuzz_cases(2000) as u64).div_ceil(2000));
    in_child("fuzz_states", limit);
    in_child("fuzz_calls", limit);
}

#[test]
fn a_sweep_over_every_offset_of_a_saved_state_never_panics_or_gives_nan() {
    // A sweep of one stepped state: the 8 bytes at every offset set to NaN,
    // to 1e300 and to -1 in turn. Nothing panics, and whatever is accepted
    // steps to fmi2Error or to finite outputs (`try_blob`). (Most offsets
    // straddle two fields, so a NaN written there need not make one.)
    let dir = temp_dir();
    let mut rng = Rng(7);
    let mut inst = loop {
        let inst = random_instance(&mut rng, &dir);
        if inst.phase() == Phase::StepComplete && inst.last_successful_time() > 0.5 {
            break inst;
        }
    };
    let blob = Instance::serialize(&inst.save().unwrap());
    let mut refused_nan = 0;
    for at in (12..blob.len() - 8).step_by(1) {
        for x in [f64::NAN, 1e300, -1.0] {
            let mut bad = blob.clone();
            bad[at..at + 8].copy_from_slice(&x.to_le_bytes());
            let accepted = try_blob(&bad, &mut Rng(at as u64));
            if x.is_nan() && !accepted {
                refused_nan += 1;
            }
        }
    }
    eprintln!("{} offsets: NaN refused at {refused_nan}", blob.len() - 20);
    assert_eq!(inst.do_step(inst.last_successful_time(), 0.01), Status::Ok);
}

// ---- StackOnFloor (the second model of the binary) ----

fn floor_instance() -> (Instance, Capture) {
    let (mut inst, log) = instance();
    inst.use_model(variables::Model::Floor);
    (inst, log)
}

fn floor_init(setup: impl FnOnce(&mut Instance)) -> (Instance, Capture, Status) {
    let (mut inst, log) = floor_instance();
    assert_eq!(inst.setup_experiment(0.0, None), Status::Ok);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    setup(&mut inst);
    let status = inst.exit_initialization_mode();
    (inst, log, status)
}

/// Every Real output of StackOnFloor; fails the test on a non-finite one.
fn assert_floor_outputs_finite(inst: &mut Instance, what: &str) {
    let ids: Vec<Id> = variables::Model::Floor
        .table()
        .into_iter()
        .filter(|v| v.id.kind() == Kind::Real && v.id.causality() == Causality::Output)
        .map(|v| v.id)
        .collect();
    let vrs: Vec<u32> = ids.iter().map(|id| id.vr()).collect();
    let mut out = vec![f64::NAN; vrs.len()];
    assert_eq!(inst.get_real(&vrs, &mut out), Status::Ok, "{what}");
    for (id, x) in ids.iter().zip(&out) {
        assert!(x.is_finite(), "{what}: {} = {x} behind fmi2OK", id.name());
    }
    let continuous: Vec<u32> = ids
        .iter()
        .filter(|id| id.is_continuous())
        .map(|id| id.vr())
        .collect();
    for order in [1, 2] {
        let mut d = vec![f64::NAN; continuous.len()];
        let orders = vec![order; continuous.len()];
        assert_eq!(
            inst.get_output_derivatives(&continuous, &orders, &mut d),
            Status::Ok,
            "{what}"
        );
        assert!(d.iter().all(|x| x.is_finite()), "{what}: derivatives {d:?}");
    }
    let mut dd = vec![f64::NAN; vrs.len()];
    assert_eq!(
        inst.directional_derivative(&vrs, &[Id::Ag.vr()], &[1.0], &mut dd),
        Status::Ok,
        "{what}"
    );
    assert!(dd.iter().all(|x| x.is_finite()), "{what}: {dd:?}");
}

#[test]
fn stack_on_floor_refuses_hostile_inputs_by_name() {
    // Values refused when set, naming the variable and its range; the
    // instance keeps its previous value and stays usable.
    let cases: [(Id, f64, &str); 10] = [
        (Id::Ag, f64::NAN, "ag = NaN"),
        (Id::Ag, 1e7, "ag = 10000000 "),
        (Id::Ag, f64::INFINITY, "ag = inf"),
        (Id::M(2), -250.0, "m[2] = -250 "),
        (Id::M(1), 0.0, "m[1] = 0 "),
        (Id::M(8), 1e12, "m[8] = 1e12 "),
        (Id::SupportMobility, -1e-3, "supportMobility = -0.001 "),
        (Id::SupportMobility, f64::NAN, "supportMobility = NaN"),
        (Id::SupportMobility, 1e10, "supportMobility = 1e10 "),
        (Id::G, 0.0, "g = 0"),
    ];
    for (id, value, expected) in cases {
        let (mut inst, log) = floor_instance();
        assert_eq!(set(&mut inst, id, value), Status::Error, "{expected}");
        let m = log.last();
        assert!(m.starts_with(&format!("fmi2SetReal: {expected}")), "{m}");
        assert!(m.contains("it must be"), "{m}");
    }
    let (mut inst, log) = floor_instance();
    assert_eq!(set(&mut inst, Id::M(2), -1.0), Status::Error);
    assert!(log.last().contains("(kg)"), "{}", log.last());
    // nBlocks 0 and 9: a stack on a floor has 1 to 8 blocks.
    for n in [0, 9, -1] {
        let (mut inst, log) = floor_instance();
        assert_eq!(inst.set_integer(&[Id::NBlocks.vr()], &[n]), Status::Error);
        assert!(
            log.last().contains(&format!(
                "nBlocks = {n} is not allowed: it must be an integer from 1 to 8"
            )),
            "{}",
            log.last()
        );
    }
    // muk > mus: refused at the end of initialization, naming muk[1].
    let (_, log, status) = floor_init(|inst| {
        set(inst, Id::Mus(1), 0.1);
        set(inst, Id::Muk(1), 0.2);
    });
    assert_eq!(status, Status::Error);
    assert!(
        log.last()
            .starts_with("fmi2ExitInitializationMode: muk[1] = 0.2 is not allowed"),
        "{}",
        log.last()
    );
    // Storey-only variables do not exist here; nor does a derivative of the
    // mobility; a slope that takes ag out of its range is refused.
    let (mut inst, log, status) = floor_init(|_| {});
    assert_eq!(status, Status::Ok);
    assert_eq!(set(&mut inst, Id::Fext, 1.0), Status::Error);
    assert!(
        log.last().contains("unknown value reference 101"),
        "{}",
        log.last()
    );
    assert_eq!(
        inst.set_input_derivatives(&[Id::SupportMobility.vr()], &[1], &[1.0]),
        Status::Error
    );
    assert!(log
        .last()
        .contains("supportMobility is not a continuous Real input"));
    assert_eq!(
        inst.set_input_derivatives(&[Id::Ag.vr()], &[1], &[f64::NAN]),
        Status::Error
    );
    set(&mut inst, Id::Ag, 9e5);
    assert_eq!(
        inst.set_input_derivatives(&[Id::Ag.vr()], &[1], &[1e9]),
        Status::Ok
    );
    assert_eq!(inst.do_step(0.0, 1.0), Status::Error);
    assert!(log.last().contains("outside its range"), "{}", log.last());
    assert_eq!(inst.phase(), Phase::StepComplete);
    assert_floor_outputs_finite(&mut inst, "after refused inputs");

    // The largest allowed values: finite outputs, derivatives and
    // directional derivatives behind fmi2OK.
    let (mut inst, log, status) = floor_init(|inst| {
        inst.set_integer(&[Id::NBlocks.vr()], &[8]);
        for j in 1..=8 {
            set(inst, Id::M(j), if j % 2 == 0 { 1e9 } else { 1e-9 });
            set(inst, Id::Mus(j), 0.3);
            set(inst, Id::Muk(j), 0.2);
        }
        set(inst, Id::SupportMobility, 1e9);
    });
    assert_eq!(status, Status::Ok, "{}", log.last());
    for (k, ag) in [1e6, -1e6, 0.0, 3.0, -1e6].into_iter().enumerate() {
        set(&mut inst, Id::Ag, ag);
        assert_floor_outputs_finite(&mut inst, "largest values, before a step");
        assert_eq!(
            inst.do_step(k as f64 * 0.1, 0.1),
            Status::Ok,
            "{}",
            log.last()
        );
        assert_floor_outputs_finite(&mut inst, "largest values");
    }
}

/// Mutated saved states of StackOnFloor, restored into a StackOnFloor: any
/// outcome but a panic or fmi2OK with a non-finite output.
#[test]
fn stack_on_floor_saved_states_survive_mutation() {
    let mut rng = Rng(fuzz_seed() ^ 0xF100);
    for case in 0..fuzz_cases(300) {
        let (mut inst, _, status) = floor_init(|inst| {
            let n = 1 + rng.below(8) as i32;
            inst.set_integer(&[Id::NBlocks.vr()], &[n]);
            for j in 1..=8 {
                set(inst, Id::M(j), 10f64.powf(rng.uniform(0.0, 3.0)));
                let mu = rng.uniform(0.02, 0.4);
                set(inst, Id::Mus(j), mu * rng.uniform(1.0, 1.5));
                set(inst, Id::Muk(j), mu);
            }
        });
        assert_eq!(status, Status::Ok);
        let mut t = 0.0;
        for _ in 0..rng.below(6) {
            set(&mut inst, Id::Ag, rng.uniform(-6.0, 6.0));
            set(&mut inst, Id::SupportMobility, rng.uniform(0.0, 0.01));
            assert_eq!(inst.do_step(t, 0.05), Status::Ok);
            t += 0.05;
        }
        let blob = Instance::serialize(&inst.save().unwrap());
        let mut bad = blob.clone();
        mutate(&mut rng, &mut bad);
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let Ok(state) = Instance::deserialize(&bad) else {
                return;
            };
            let (mut fresh, _) = floor_instance();
            if fresh.restore(&state) != Status::Ok || fresh.phase() != Phase::StepComplete {
                return;
            }
            let t = fresh.last_successful_time();
            if fresh.do_step(t, 0.01) == Status::Ok {
                assert_floor_outputs_finite(&mut fresh, "after a restored state");
            }
        }));
        assert!(result.is_ok(), "case {case}: a mutated state panicked");
    }
}

/// Through the C ABI: the StackOnFloor GUID gives a StackOnFloor; a GUID of
/// neither model is refused with a logged reason naming both.
#[test]
fn the_guid_picks_the_model_and_a_wrong_one_is_refused() {
    use stacked_live_load::fmi::c_api;
    use std::ffi::{c_char, c_void, CStr, CString};
    unsafe extern "C" fn logger(
        env: *mut c_void,
        _status: i32,
        _category: *const c_char,
        message: *const c_char,
    ) {
        let log = &mut *(env as *mut Vec<String>);
        log.push(CStr::from_ptr(message).to_string_lossy().into_owned());
    }
    let mut log: Vec<String> = vec![];
    let env = &mut log as *mut Vec<String> as *mut c_void;
    let instantiate = |token: &str| {
        let token = CString::new(token).unwrap();
        unsafe {
            c_api::fmi3::fmi3InstantiateCoSimulation(
                c"g".as_ptr(),
                token.as_ptr(),
                std::ptr::null(),
                false,
                false,
                false,
                false,
                std::ptr::null(),
                0,
                env,
                Some(logger),
                std::ptr::null(),
            )
        }
    };
    let bad = instantiate("{00000000-0000-0000-0000-000000000000}");
    assert!(bad.is_null());
    let floor = instantiate(c_api::FLOOR_GUID);
    assert!(!floor.is_null());
    unsafe {
        // mp (a storey parameter) is unknown to a StackOnFloor.
        assert_eq!(
            c_api::fmi3::fmi3SetFloat64(floor, [1].as_ptr(), 1, [2.0].as_ptr(), 1),
            3
        );
        assert_eq!(
            c_api::fmi3::fmi3SetFloat64(floor, [Id::M(1).vr()].as_ptr(), 1, [-1.0].as_ptr(), 1),
            3
        );
        c_api::fmi3::fmi3FreeInstance(floor);
    }
    let log = unsafe { &*(env as *mut Vec<String>) };
    assert!(
        log[0].contains("does not match any of this binary's models")
            && log[0].contains(c_api::GUID)
            && log[0].contains(c_api::FLOOR_GUID),
        "{}",
        log[0]
    );
    assert!(log[1].contains("unknown value reference 1"), "{}", log[1]);
    assert!(log[2].contains("m[1] = -1 is not allowed"), "{}", log[2]);
}
