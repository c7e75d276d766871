//! FMU benchmarks (issue #3), through the exported C functions: 4000
//! fmi2SetReal + fmi2DoStep calls of 0.005 s (a 20 s record held sample by
//! sample, as an importer drives it), and the same record through recordFile
//! in one fmi2DoStep; the engine alone on the same record is the baseline.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use stacked_live_load::fmi::c_api::*;
use stacked_live_load::{ground::record, GroundMotion, Params, Settings, Simulator};
use std::ffi::CString;
use std::path::PathBuf;

fn record_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/ground_motions/RSN787_LOMAP_SLC270.AT2")
}

/// The first 20 s (4001 samples at 0.005 s), written as CSV for recordFile.
fn record_20s() -> (GroundMotion, PathBuf) {
    let gm = GroundMotion::read(&record_path(), 9.81)
        .expect("the benchmark reads ../shared/ground_motions");
    let gm = GroundMotion {
        time: gm.time[..4001].to_vec(),
        accel: gm.accel[..4001].to_vec(),
    };
    let csv = std::env::temp_dir().join("sll_bench_record.csv");
    let text: String = gm
        .time
        .iter()
        .zip(&gm.accel)
        .map(|(t, a)| format!("{t:?},{a:?}\n"))
        .collect();
    std::fs::write(&csv, text).unwrap();
    (gm, csv)
}

unsafe fn instance(record_file: Option<&CString>) -> fmi2Component {
    let callbacks = Box::leak(Box::new(fmi2CallbackFunctions {
        logger: None,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: std::ptr::null_mut(),
    }));
    let guid = CString::new(GUID).unwrap();
    let c = fmi2Instantiate(
        c"bench".as_ptr(),
        1,
        guid.as_ptr(),
        std::ptr::null(),
        callbacks,
        0,
        0,
    );
    assert!(!c.is_null());
    fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0);
    fmi2EnterInitializationMode(c);
    if let Some(file) = record_file {
        let vr = 600;
        let p = file.as_ptr();
        assert_eq!(fmi2SetString(c, &vr, 1, &p), 0);
    }
    assert_eq!(fmi2ExitInitializationMode(c), 0);
    c
}

fn benches(c: &mut Criterion) {
    let (gm, csv) = record_20s();
    let csv = CString::new(csv.to_str().unwrap()).unwrap();
    let mut g = c.benchmark_group("FMU, 20 s record at 0.005 s");
    g.bench_function("baseline: engine alone, linear record", |b| {
        b.iter(|| {
            let mut sim = Simulator::new(&Params::default(), &Settings::default()).unwrap();
            record::run(&mut sim, black_box(&gm), 1.0).unwrap();
            sim.outputs().peak_up
        })
    });
    // As a study runs it: the FMU loaded once, fmi2Reset between runs (the
    // record, read once, stays cached under its file name).
    let c = unsafe { instance(Some(&csv)) };
    g.bench_function("recordFile in one fmi2DoStep, after fmi2Reset", |b| {
        b.iter(|| unsafe {
            fmi2Reset(c);
            fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0);
            fmi2EnterInitializationMode(c);
            let (file_vr, p) = (600, csv.as_ptr());
            fmi2SetString(c, &file_vr, 1, &p);
            fmi2ExitInitializationMode(c);
            assert_eq!(fmi2DoStep(c, 0.0, 20.0, 1), 0);
            let (vr, mut up) = (204, 0.0);
            fmi2GetReal(c, &vr, 1, &mut up);
            up
        })
    });
    unsafe { fmi2FreeInstance(c) };
    g.bench_function("4000 x (fmi2SetReal + fmi2DoStep + fmi2GetReal)", |b| {
        b.iter(|| unsafe {
            let c = instance(None);
            let (ag, up) = (100, 200);
            let mut out = 0.0;
            for (i, a) in gm.accel[..4000].iter().enumerate() {
                fmi2SetReal(c, &ag, 1, a);
                fmi2DoStep(c, i as f64 * 0.005, 0.005, 1);
                fmi2GetReal(c, &up, 1, &mut out);
            }
            fmi2FreeInstance(c);
            out
        })
    });
    g.finish();
}

criterion_group!(fmu, benches);
criterion_main!(fmu);
