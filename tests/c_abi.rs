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
