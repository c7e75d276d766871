//! The C header works from C: a small program built with `cc` includes
//! `include/StackedLiveLoad.h`, loads the library with dlopen and checks a
//! number against a closed form (see tests/c/run_fmu.c).

use std::path::{Path, PathBuf};
use std::process::Command;

/// The cdylib that this `cargo test` built: rustc emits it beside the rlib
/// in target/<profile>/deps/, where this test binary lives too.
fn library() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let lib = exe.parent().unwrap().join("libstacked_live_load.so");
    assert!(lib.exists(), "{} not built", lib.display());
    lib
}

#[test]
fn c_program_runs_a_simulation_through_the_header() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::env::temp_dir().join(format!("sll_run_fmu_{}", std::process::id()));
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let status = Command::new(cc)
        .args(["-std=gnu11", "-Wall", "-Werror", "-I"])
        .arg(root.join("include"))
        .arg(root.join("tests/c/run_fmu.c"))
        .args(["-ldl", "-lm", "-o"])
        .arg(&out)
        .status()
        .expect("a C compiler (cc) is needed");
    assert!(
        status.success(),
        "the C program must compile against the header"
    );
    let run = Command::new(&out)
        .arg(library())
        .arg(stacked_live_load::fmi::c_api::GUID)
        .output()
        .unwrap();
    let _ = std::fs::remove_file(&out);
    println!("{}", String::from_utf8_lossy(&run.stdout));
    assert!(
        run.status.success(),
        "exit {:?}: {}",
        run.status.code(),
        String::from_utf8_lossy(&run.stderr)
    );
}

/// StackOnFloor through the C ABI from C: the same library, instantiated with
/// the StackOnFloor GUID (tests/c/run_floor.c); every number it prints is
/// the engine's stack on a prescribed support under the same inputs, bit
/// for bit, and d floorForce / d ag = -attachedMass times the support law's
/// gain (1 unless the inputs' jump switched the mode with a mobility).
#[test]
fn c_program_runs_stack_on_floor_bit_for_bit_with_the_engine() {
    use stacked_live_load::{Excitation, Params, Settings, Simulator, Support};
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::env::temp_dir().join(format!("sll_run_floor_{}", std::process::id()));
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let status = Command::new(cc)
        .args(["-std=gnu11", "-Wall", "-Werror", "-I"])
        .arg(root.join("include"))
        .arg(root.join("tests/c/run_floor.c"))
        .args(["-ldl", "-o"])
        .arg(&out)
        .status()
        .expect("a C compiler (cc) is needed");
    assert!(
        status.success(),
        "run_floor.c must compile against the header"
    );
    let run = Command::new(&out)
        .arg(library())
        .arg(stacked_live_load::fmi::c_api::FLOOR_GUID)
        .output()
        .unwrap();
    let _ = std::fs::remove_file(&out);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        run.status.success(),
        "exit {:?}: {stderr}",
        run.status.code()
    );
    // The refused GUID and the refused mass were logged as errors (3).
    assert_eq!(
        stderr.matches("[3 logStatusError] logged").count(),
        2,
        "{stderr}"
    );

    let mut p = Params {
        n_blocks: 3,
        mp: 1.0,
        support: Support::Prescribed,
        ..Params::default()
    };
    p.alpha[..3].copy_from_slice(&[400.0, 150.0, 75.0]);
    p.mus[..3].copy_from_slice(&[0.3, 0.2, 0.1]);
    p.muk[..3].copy_from_slice(&[0.25, 0.2, 0.08]);
    let mut sim = Simulator::new(&p, &Settings::default()).unwrap();
    let stdout = String::from_utf8(run.stdout).unwrap();
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 300);
    for (k, line) in lines.iter().enumerate() {
        let a = 0.5 * ((k as i64 * 37) % 17 - 8) as f64;
        let slope = 10.0 * ((k as i64 * 13) % 11 - 5) as f64;
        let exc = Excitation {
            ag: a,
            ag_rate: slope,
            ..Default::default()
        };
        let mobility = if k < 150 { 0.0 } else { 2e-3 };
        sim.set_support_mobility(mobility).unwrap();
        // As fmi2DoStep: the jump of ag at the communication point first
        // (the mode it gives is the step's reference), then the step.
        let now = sim.time();
        sim.advance(now, &exc).unwrap();
        sim.advance(now + 0.01, &exc).unwrap();
        // The outputs as the next step starts, as fmi2GetReal shows them
        // (inputs held at their ends; the reference of the support's law
        // is the mode shown): ports' rule, not a copy.
        let held = Excitation {
            ag: sim.ag_now(),
            ag_rate: slope,
            ..Default::default()
        };
        let shown =
            stacked_live_load::fmi::ports::exact_at_step_start(&sim, &held, mobility).unwrap();
        let o = shown.outputs();
        let gain =
            stacked_live_load::physics::mode::Dynamics::new(shown.system(), shown.mode()).ag_gain;
        let expected = [
            o.floor_force,
            o.attached_mass,
            o.sliding_force,
            o.ab_abs[0],
            o.force[0],
            o.ub[2],
            -o.attached_mass * gain,
        ];
        let got: Vec<f64> = line.split(' ').map(|x| x.parse().unwrap()).collect();
        for (i, (g, e)) in got.iter().zip(expected).enumerate() {
            assert_eq!(
                g.to_bits(),
                e.to_bits(),
                "step {k}, column {i}: C {g:e}, engine {e:e}"
            );
        }
    }
    assert!(sim.outputs().n_events > 10, "the scene switches");
}
