//! FMI 3.0 Co-Simulation through the instance layer: with `earlyReturnAllowed`
//! every `fmi3DoStep` returns at the first stick/slip switch inside it, at the
//! switch time of the independent exact reference (`common::Exact`, events by
//! bisection on the matrix-exponential solution, to about 1e-14 s) within
//! 1e-9 s; the results on the communication grid equal those of stepping
//! without early return (the FMI 2.0 behaviour); with Event Mode the outputs
//! at an early return are the left limit and fmi3UpdateDiscreteStates
//! resolves the switch.

mod common;
use common::*;
use stacked_live_load::fmi::instance::{Instance, NullSink, Phase, Status, StepRequest};
use stacked_live_load::fmi::variables::Id;
use stacked_live_load::*;
use std::path::{Path, PathBuf};

/// Tolerance on a switch time (s): the issue's.
const TIME_TOL: f64 = 1e-9;
/// Switches this close to a communication point stay in the step that ends
/// there (no early return): the FMU's EDGE.
const EDGE: f64 = 1e-10;
/// Length of the run (s).
const SECONDS: f64 = 10.0;

/// The first [`SECONDS`] of the embedded default record (PGA 0.21 g: both
/// blocks of the paper's stack slip many times), as a CSV file for `recordFile`.
fn record(tag: &str) -> (GroundMotion, PathBuf) {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("resources/default_record.csv");
    let gm = truncate(&GroundMotion::read(&path, 9.81).unwrap(), SECONDS);
    let file = std::env::temp_dir().join(format!("sll_fmi3_{tag}_{}.csv", std::process::id()));
    let mut text = String::from("time,accel\n");
    for (t, a) in gm.time.iter().zip(&gm.accel) {
        text.push_str(&format!("{t:?},{a:?}\n"));
    }
    std::fs::write(&file, text).unwrap();
    (gm, file)
}

fn scenes() -> Vec<(&'static str, Params)> {
    let mut static_kinetic = Params::default();
    static_kinetic.mus[..2].copy_from_slice(&[0.15, 0.08]);
    static_kinetic.muk[..2].copy_from_slice(&[0.1, 0.05]);
    vec![
        ("paper Fig. 5a stack", Params::default()),
        ("stack, mus > muk", static_kinetic),
    ]
}

fn instance(p: &Params, file: &Path, early: bool, event_mode: bool) -> Instance {
    let mut inst = Instance::new("fmi3", None, Box::new(NullSink), false);
    inst.use_fmi3(early, event_mode);
    assert_eq!(
        inst.set_integer(&[Id::NBlocks.vr()], &[p.n_blocks as i32]),
        Status::Ok
    );
    for j in 1..=p.n_blocks {
        let vrs = [Id::Alpha(j).vr(), Id::Mus(j).vr(), Id::Muk(j).vr()];
        let x = [p.alpha[j - 1], p.mus[j - 1], p.muk[j - 1]];
        assert_eq!(inst.set_real(&vrs, &x), Status::Ok);
    }
    let file = file.to_str().unwrap().to_string();
    assert_eq!(inst.set_string(&[Id::RecordFile.vr()], &[file]), Status::Ok);
    assert_eq!(inst.setup_experiment(0.0, Some(SECONDS)), Status::Ok);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(inst.exit_initialization_mode_fmi3(), Status::Ok);
    if event_mode {
        assert_eq!(inst.phase(), Phase::EventMode);
        assert_eq!(inst.update_discrete_states(), Status::Ok);
        assert_eq!(inst.enter_step_mode(), Status::Ok);
    }
    inst
}

fn real(inst: &mut Instance, id: Id) -> f64 {
    let mut x = [0.0];
    assert_eq!(inst.get_real(&[id.vr()], &mut x), Status::Ok);
    x[0]
}

fn n_events(inst: &mut Instance) -> i32 {
    let mut x = [0];
    assert_eq!(inst.get_integer(&[Id::NEvents.vr()], &mut x), Status::Ok);
    x[0]
}

/// A master on a grid of `h` that goes on from every early return; the
/// early-return times and (up, slip[1], slip[2]) at every grid point.
struct Run {
    early: Vec<f64>,
    grid: Vec<[f64; 3]>,
    /// nEvents read at each early return before and after the event is handled.
    events_across: Vec<(i32, i32)>,
}

fn run(p: &Params, file: &Path, h: f64, early: bool, event_mode: bool) -> Run {
    let mut inst = instance(p, file, early, event_mode);
    let mut out = Run {
        early: vec![],
        grid: vec![],
        events_across: vec![],
    };
    let n = (SECONDS / h).round() as usize;
    let mut t = 0.0;
    for k in 1..=n {
        let target = k as f64 * h;
        loop {
            let o = inst.do_step_fmi3(StepRequest { t, h: target - t });
            assert_eq!(o.status, Status::Ok, "step from {t}");
            t = o.last_successful_time;
            if !o.early_return {
                break;
            }
            assert!(early, "no early return unless allowed");
            assert!(o.last_successful_time < target);
            out.early.push(t);
            assert_eq!(o.event_handling_needed, event_mode);
            if event_mode {
                let before = n_events(&mut inst);
                assert_eq!(inst.enter_event_mode(), Status::Ok);
                assert_eq!(inst.update_discrete_states(), Status::Ok);
                assert_eq!(inst.enter_step_mode(), Status::Ok);
                out.events_across.push((before, n_events(&mut inst)));
            }
        }
        let o = [Id::Up, Id::Slip(1), Id::Slip(2)].map(|id| real(&mut inst, id));
        out.grid.push(o);
    }
    out
}

#[test]
fn early_returns_land_on_the_exact_switch_times() {
    let (gm, file) = record("times");
    for (name, p) in scenes() {
        let exact = Exact::new(&p).run(&gm, 8);
        let h = 0.005;
        let r = run(&p, &file, h, true, false);
        // Every early return is at a switch of the reference.
        let mut worst: f64 = 0.0;
        for &t in &r.early {
            let d = exact
                .event_times
                .iter()
                .map(|&te| (te - t).abs())
                .fold(f64::INFINITY, f64::min);
            assert!(
                d <= TIME_TOL,
                "{name}: early return at {t} is {d:e} s from every switch"
            );
            worst = worst.max(d);
        }
        // Every switch of the reference has its early return, but those
        // within EDGE of a grid point (they stay in the step ending there).
        let mut covered = 0;
        for &te in &exact.event_times {
            let off_grid = (te / h - (te / h).round()).abs() * h;
            if off_grid <= EDGE + TIME_TOL {
                continue;
            }
            let d = r
                .early
                .iter()
                .map(|&t| (te - t).abs())
                .fold(f64::INFINITY, f64::min);
            assert!(
                d <= TIME_TOL,
                "{name}: no early return at the switch {te} (nearest {d:e} s off)"
            );
            covered += 1;
        }
        println!(
            "{name}: {} switches in the reference, {} early returns, {covered} matched, worst |dt| = {worst:.2e} s",
            exact.event_times.len(),
            r.early.len()
        );
        assert!(
            covered >= 20,
            "{name}: the scene must switch often ({covered})"
        );
    }
    let _ = std::fs::remove_file(file);
}

#[test]
fn one_long_step_per_call_returns_at_the_same_switches() {
    // A master that asks for the whole rest of the record at every call
    // (probed in windows inside): the same early returns as on the 5 ms grid.
    let (_, file) = record("long");
    let p = Params::default();
    let grid = run(&p, &file, 0.005, true, false);
    let mut inst = instance(&p, &file, true, false);
    let (mut t, mut early) = (0.0, vec![]);
    let started = std::time::Instant::now();
    while t < SECONDS {
        let o = inst.do_step_fmi3(StepRequest { t, h: SECONDS - t });
        assert_eq!(o.status, Status::Ok);
        t = o.last_successful_time;
        if o.early_return {
            early.push(t);
        }
    }
    let seconds = started.elapsed().as_secs_f64();
    assert_eq!(t, SECONDS);
    assert_eq!(early.len(), grid.early.len());
    let worst = early
        .iter()
        .zip(&grid.early)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    println!(
        "{} early returns from whole-rest steps, worst |dt| to the 5 ms grid's {worst:.2e} s, {seconds:.3} s",
        early.len()
    );
    assert!(worst <= TIME_TOL);
    let up = real(&mut inst, Id::Up);
    let want = grid.grid.last().unwrap()[0];
    assert!(
        (up - want).abs() <= 1e-9 * want.abs().max(1e-3),
        "{up} vs {want}"
    );
    let _ = std::fs::remove_file(file);
}

#[test]
fn grid_results_equal_stepping_without_early_return() {
    let (_, file) = record("grid");
    for (name, p) in scenes() {
        let plain = run(&p, &file, 0.01, false, false);
        let early = run(&p, &file, 0.01, true, false);
        assert!(plain.early.is_empty());
        let peak = plain.grid.iter().map(|o| o[0].abs()).fold(0.0, f64::max);
        let mut worst: f64 = 0.0;
        for (a, b) in plain.grid.iter().zip(&early.grid) {
            for i in 0..3 {
                worst = worst.max((a[i] - b[i]).abs());
            }
        }
        println!("{name}: largest grid difference {worst:.2e} m (peak up {peak:.4} m)");
        // Splitting a step at its switch changes only the internal steps:
        // differences at the engine's accuracy (about 1e-11 relative).
        assert!(worst <= 1e-9 * peak, "{name}: {worst:e}");
    }
    let _ = std::fs::remove_file(file);
}

#[test]
fn event_mode_shows_the_left_limit_until_the_update() {
    let (_, file) = record("events");
    let p = Params::default();
    let r = run(&p, &file, 0.01, true, true);
    let plain = run(&p, &file, 0.01, true, false);
    // The same early returns as without Event Mode.
    assert_eq!(r.early, plain.early);
    // Before fmi3UpdateDiscreteStates the switch has not been counted, after
    // it it has (one switch, or more at the same instant).
    for &(before, after) in &r.events_across {
        assert!(after > before, "nEvents {before} -> {after}");
    }
    println!("{} events handled in Event Mode", r.events_across.len());
    assert!(r.events_across.len() >= 20);
    let _ = std::fs::remove_file(file);
}
