//! Helpers of the second hostile round's tests (`tests/hostile_second_round*.rs`).

use super::{Capture, GroundMotion};
use stacked_live_load::fmi::instance::{Instance, Status};
use stacked_live_load::fmi::variables::{self, Causality, Id, Kind};
use std::path::{Path, PathBuf};

/// This process's scratch folder.
pub fn temp_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sll_second_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub fn set(inst: &mut Instance, id: Id, x: f64) -> Status {
    inst.set_real(&[id.vr()], &[x])
}

pub fn get(inst: &mut Instance, id: Id) -> f64 {
    let mut x = [f64::NAN];
    assert_eq!(inst.get_real(&[id.vr()], &mut x), Status::Ok);
    x[0]
}

/// Every Real output, in the variable table's order.
pub fn outputs(inst: &mut Instance) -> Vec<f64> {
    let vrs: Vec<u32> = variables::table()
        .into_iter()
        .filter(|v| v.id.kind() == Kind::Real && v.id.causality() == Causality::Output)
        .map(|v| v.id.vr())
        .collect();
    let mut out = vec![f64::NAN; vrs.len()];
    assert_eq!(inst.get_real(&vrs, &mut out), Status::Ok);
    out
}

/// A record as a CSV file, every digit kept.
pub fn write_csv(path: &Path, gm: &GroundMotion) {
    let text: String = (gm.time.iter().zip(&gm.accel))
        .map(|(t, a)| format!("{t:.17e},{a:.17e}\n"))
        .collect();
    std::fs::write(path, text).unwrap();
}

/// Initialization with `recordFile = file` in an instance given `location`.
pub fn init_with(location: Option<&str>, file: &str) -> (Status, String) {
    let log = Capture::default();
    let mut inst = Instance::new("loc", location, Box::new(log.clone()), false);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    inst.set_string(&[Id::RecordFile.vr()], &[file.to_string()]);
    (inst.exit_initialization_mode(), log.last())
}
