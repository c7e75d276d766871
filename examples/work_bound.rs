//! What the work bound of one call means in time (docs/robustness.md,
//! "Bounded work per call"): the chattering case, an 8-block stack
//! under a ±5 m/s² square wave at 1 kHz, asked for in one `fmi2DoStep`.
//!
//! `cargo run --release --example work_bound -- [SECONDS] [N_BLOCKS] [TP]`
//! (default 310 s, 8 blocks, Tp = 1 ms: a structure that follows the
//! ground, internal steps of 3.2 µs, so that 310 s is just inside the bound
//! counted up front). Prints the wall time of the call, its status,
//! the work it counted and, when it finished, the switches.
use stacked_live_load::fmi::instance::{Instance, LogSink, Status};
use stacked_live_load::fmi::variables::Id;
use stacked_live_load::ground::{record, synthetic};
use stacked_live_load::{limits, GroundMotion, Params, Settings, Simulator};
use std::sync::{Arc, Mutex};
use std::time::Instant;

#[derive(Clone, Default)]
struct Last(Arc<Mutex<String>>);

impl LogSink for Last {
    fn log(&self, _: Status, _: &str, message: &str) {
        *self.0.lock().unwrap() = message.to_string();
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let seconds: f64 = args.next().map_or(310.0, |s| s.parse().unwrap());
    let n_blocks: i32 = args.next().map_or(8, |s| s.parse().unwrap());
    let tp: f64 = args.next().map_or(1e-3, |s| s.parse().unwrap());
    let dir = std::env::temp_dir().join(format!("sll_work_bound_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("square.csv");
    let wave = synthetic::square_wave(seconds, 1000.0, 5.0);
    let text: String = (wave.time.iter().zip(&wave.accel))
        .map(|(t, a)| format!("{t:.9},{a}\n"))
        .collect();
    std::fs::write(&file, text).unwrap();

    let log = Last::default();
    let mut inst = Instance::new("work_bound", None, Box::new(log.clone()), false);
    assert_eq!(inst.setup_experiment(0.0, None), Status::Ok);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    assert_eq!(
        inst.set_integer(&[Id::NBlocks.vr()], &[n_blocks]),
        Status::Ok
    );
    assert_eq!(inst.set_real(&[Id::Tp.vr()], &[tp]), Status::Ok);
    // MU=x: every interface's friction coefficient (static and kinetic).
    if let Some(mu) = std::env::var("MU").ok().and_then(|s| s.parse::<f64>().ok()) {
        for j in 1..=8 {
            inst.set_real(&[Id::Mus(j).vr(), Id::Muk(j).vr()], &[mu, mu]);
        }
    }
    let path = file.display().to_string();
    assert_eq!(inst.set_string(&[Id::RecordFile.vr()], &[path]), Status::Ok);
    assert_eq!(
        inst.exit_initialization_mode(),
        Status::Ok,
        "{}",
        log.0.lock().unwrap()
    );

    let started = Instant::now();
    let status = inst.do_step(0.0, seconds);
    let wall = started.elapsed().as_secs_f64();
    println!(
        "{n_blocks} blocks, Tp = {tp} s, {seconds} s of a ±5 m/s² 1 kHz square wave in one \
         fmi2DoStep:"
    );
    println!("  status {status:?} after {wall:.3} s");
    if status == Status::Ok {
        let mut events = [0];
        inst.get_integer(&[Id::NEvents.vr()], &mut events);
        println!("  {} switches", events[0]);
    } else {
        println!("  {}", log.0.lock().unwrap());
    }

    // The same scene on the engine directly, without a bound: what the
    // work counts and what it costs (ENGINE=1).
    if std::env::var("ENGINE").is_ok_and(|v| v == "1") {
        let mut p = Params {
            n_blocks: n_blocks as usize,
            tp,
            ..Params::default()
        };
        if let Some(mu) = std::env::var("MU").ok().and_then(|s| s.parse::<f64>().ok()) {
            p.mus = [mu; 8];
            p.muk = [mu; 8];
        }
        let gm = GroundMotion::read(&file, p.g).unwrap();
        let mut sim = Simulator::new(&p, &Settings::default()).unwrap();
        let started = Instant::now();
        record::run(&mut sim, &gm, 1.0).unwrap();
        let wall = started.elapsed().as_secs_f64();
        let st = sim.stats();
        let work = sim.work();
        let tries = (work - st.steps - limits::SWITCH_WORK * st.events) / limits::TRY_WORK;
        println!(
            "  engine alone: {wall:.3} s, {} internal steps, {} switches, {tries} resolver tries, \
             work {work:.3e} units ({:.1} ns per unit; {:.1} tries per switch)",
            st.steps,
            st.events,
            1e9 * wall / work as f64,
            tries as f64 / st.events.max(1) as f64
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
