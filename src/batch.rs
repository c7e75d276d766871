//! A batch entry point beside the FMI API: many parameter sets over one
//! record in one call, for parametric studies, where the FMI calls and the
//! importer's own overhead per simulation (Python and ctypes in
//! `scripts/study_tasks.py`) would cost more than the simulation itself.
//!
//! Each set runs the whole record from rest with the default solver (the
//! exact engine), exactly as an FMU instance with those
//! parameters and `recordFile` does in one `fmi2DoStep` over the record.
#![allow(non_snake_case, clippy::missing_safety_doc)]

use crate::fmi::c_api::catch_quietly;
use crate::ground::record::{self, GroundMotion};
use crate::limits;
use crate::physics::params::{check_scalar, Params, Settings, MAX_BLOCKS};
use crate::{SimError, Simulator};
use std::ffi::{c_char, c_int, CStr};

/// One parameter set (all doubles, in this order: the C layout is 28
/// consecutive doubles). Entries beyond `nBlocks` are ignored.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SllBatchParams {
    /// Blocks in the stack: an integer 0..8.
    pub nBlocks: f64,
    /// Structure mass (kg).
    pub mp: f64,
    /// Bare period (s).
    pub Tp: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// Block mass / mp, blocks 1..8.
    pub alpha: [f64; 8],
    /// Static friction of interfaces 1..8.
    pub mus: [f64; 8],
    /// Kinetic friction of interfaces 1..8.
    pub muk: [f64; 8],
}

/// The results of one set (13 consecutive doubles in C).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SllBatchOutputs {
    /// Largest |up| (m).
    pub peakUp: f64,
    /// Largest |apAbs| (m/s²).
    pub peakApAbs: f64,
    /// Input energy at the end (J).
    pub Einput: f64,
    /// Stick/slip switches.
    pub nEvents: f64,
    /// Switches decided by the selection rule.
    pub nAmbiguous: f64,
    /// Largest |slip| at interfaces 1..8 (0 beyond nBlocks).
    pub peakSlip: [f64; 8],
}

/// Doubles per parameter set (the Python side, `scripts/sll`, passes flat
/// arrays of this layout).
pub const BATCH_PARAMS: usize = std::mem::size_of::<SllBatchParams>() / 8;
/// Doubles per result.
pub const BATCH_OUTPUTS: usize = std::mem::size_of::<SllBatchOutputs>() / 8;
// The arrays are 8 long in C (the header has no MAX_BLOCKS).
const _: () = assert!(MAX_BLOCKS == 8 && BATCH_PARAMS == 28 && BATCH_OUTPUTS == 13);

/// Runs `nSets` parameter sets over one record.
///
/// - `recordFile`: a PEER `.AT2` (in g, converted with `g`) or CSV
///   `time,accel` (m/s²) file, as the FMU's `recordFile` (an absolute or
///   working-directory-relative path); multiplied by `recordScale`.
/// - `params`: `nSets` parameter sets ([`SllBatchParams`]).
/// - `outputs`: room for `nSets` results ([`SllBatchOutputs`]).
/// - `message`, `messageSize`: a buffer for the error message (may be NULL).
///
/// Returns 0 (fmi2OK), or 3 (fmi2Error) with a message naming the set and
/// the variable and its allowed range, or the record's file, line and
/// problem. Every set is checked before any runs: a bad one writes no
/// result; where a run fails (the work bound spent), the results of the
/// sets before it are written. The path is UTF-8, as an FMU's strings. One call
/// does at most the work of one `fmi2DoStep` (`limits::MAX_STEPS_PER_CALL`):
/// refused up front from the sets' internal steps and the record's samples,
/// stopped when switches spend the rest. A panic never crosses this
/// boundary (it is reported as an error, nothing is printed).
#[no_mangle]
pub unsafe extern "C" fn sllRunBatch(
    recordFile: *const c_char,
    g: f64,
    recordScale: f64,
    nSets: c_int,
    params: *const SllBatchParams,
    outputs: *mut SllBatchOutputs,
    message: *mut c_char,
    messageSize: usize,
) -> c_int {
    let result = catch_quietly(|| {
        if recordFile.is_null() || (nSets > 0 && (params.is_null() || outputs.is_null())) {
            return Err("recordFile, params and outputs must not be NULL".to_string());
        }
        if nSets < 0 {
            return Err(format!("nSets = {nSets} is not allowed: it must be >= 0"));
        }
        // The FMU's ranges (params::RANGES), with their messages.
        check_scalar("g", g).map_err(|e| e.to_string())?;
        check_scalar("recordScale", recordScale).map_err(|e| e.to_string())?;
        let path = CStr::from_ptr(recordFile)
            .to_str()
            .map_err(|_| "recordFile is not UTF-8 text".to_string())?;
        let gm = GroundMotion::read(std::path::Path::new(path), g)
            .map_err(|e| format!("recordFile: {e}"))?;
        let n = nSets as usize;
        let params = std::slice::from_raw_parts(params, n);
        let outputs = std::slice::from_raw_parts_mut(outputs, n);
        // The work bound of one call, up front: every set's internal steps
        // over the record and its samples, and building it.
        let mut estimate = 0.0;
        for (set, p) in params.iter().enumerate() {
            let sim = simulator(p, g).map_err(|e| format!("set {set}: {e}"))?;
            let steps =
                limits::work_estimate(gm.duration(), sim.max_internal_step(), gm.time.len(), 1.0);
            estimate += steps + SET_WORK;
            if estimate > limits::MAX_STEPS_PER_CALL {
                return Err(format!(
                    "the sets up to set {set} would take about {estimate:.3e} internal steps \
                     (set {set}: internal step {:.3e} s over the record's {} s and {} samples), \
                     more than the limit of {:e} per call: split the sets into several calls, \
                     or shorten the record",
                    sim.max_internal_step(),
                    limits::Num(gm.duration()),
                    gm.time.len(),
                    limits::MAX_STEPS_PER_CALL
                ));
            }
        }
        // And as it is done (switches count too): what is left of it.
        let mut left = limits::MAX_STEPS_PER_CALL as u64;
        for (set, (p, out)) in params.iter().zip(outputs.iter_mut()).enumerate() {
            run_set(p, g, &gm, recordScale, out, &mut left)
                .map_err(|e| format!("set {set}: {e}"))?;
        }
        Ok(())
    });
    let error = match result {
        Ok(Ok(())) => return 0,
        Ok(Err(e)) => e,
        Err(text) => format!("internal error (a panic was caught): {text}"),
    };
    if !message.is_null() && messageSize > 0 {
        let text = format!("sllRunBatch: {error}");
        // Cut at a character's boundary: the buffer holds UTF-8 text.
        let mut len = text.len().min(messageSize - 1);
        while !text.is_char_boundary(len) {
            len -= 1;
        }
        std::ptr::copy_nonoverlapping(text.as_ptr() as *const c_char, message, len);
        *message.add(len) = 0;
    }
    3
}

/// The work of building one set's simulator, counted up front (in internal
/// steps: a few microseconds).
const SET_WORK: f64 = 64.0;

/// The simulator of one parameter set.
fn simulator(p: &SllBatchParams, g: f64) -> Result<Simulator, String> {
    let n = p.nBlocks;
    if !(n.fract() == 0.0 && (0.0..=MAX_BLOCKS as f64).contains(&n)) {
        return Err(format!(
            "nBlocks = {n} is not allowed: it must be an integer from 0 to 8"
        ));
    }
    // Entries beyond nBlocks are ignored (the default scene's values stand).
    let b = n as usize;
    let mut params = Params {
        n_blocks: b,
        mp: p.mp,
        tp: p.Tp,
        zeta: p.zeta,
        g,
        ..Params::default()
    };
    params.alpha[..b].copy_from_slice(&p.alpha[..b]);
    params.mus[..b].copy_from_slice(&p.mus[..b]);
    params.muk[..b].copy_from_slice(&p.muk[..b]);
    Simulator::new(&params, &Settings::default()).map_err(|e| e.to_string())
}

/// One parameter set over the record, within `left` units of work (what
/// it does is taken from `left`).
fn run_set(
    p: &SllBatchParams,
    g: f64,
    gm: &GroundMotion,
    scale: f64,
    out: &mut SllBatchOutputs,
    left: &mut u64,
) -> Result<(), String> {
    let mut sim = simulator(p, g)?;
    sim.set_work_budget(*left);
    let result = record::run(&mut sim, gm, scale);
    *left = left.saturating_sub(sim.work());
    match result {
        Ok(()) => {}
        Err(SimError::WorkLimit { t }) => {
            return Err(format!(
                "stopped at t = {} s of the record: the stick/slip switches spent the work \
                 bound of one call ({:e} internal steps' worth, a few seconds); split the sets \
                 into several calls",
                limits::Num(t),
                limits::MAX_STEPS_PER_CALL
            ))
        }
        Err(e) => return Err(e.to_string()),
    }
    let o = sim.outputs();
    *out = SllBatchOutputs {
        peakUp: o.peak_up,
        peakApAbs: o.peak_ap_abs,
        Einput: o.e_input,
        nEvents: o.n_events as f64,
        nAmbiguous: o.n_ambiguous as f64,
        peakSlip: o.peak_slip,
    };
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::CString;

    #[test]
    fn a_batch_equals_single_runs_and_names_a_bad_set() {
        // Expected values: the engine run set by set (what the FMU does with
        // `recordFile` in one step), bit for bit.
        let dir = std::env::temp_dir().join(format!("sll_batch_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("rec.csv");
        let gm = crate::ground::synthetic::broadband(4.0, 0.01, 3.0);
        let csv: String = gm
            .time
            .iter()
            .zip(&gm.accel)
            .map(|(t, a)| format!("{t:.17e},{a:.17e}\n"))
            .collect();
        std::fs::write(&file, csv).unwrap();
        let read = GroundMotion::read(&file, 9.81).unwrap();
        let mut sets = Vec::new();
        for (n, tp) in [(0usize, 0.3), (2, 0.5), (3, 1.2)] {
            sets.push(SllBatchParams {
                nBlocks: n as f64,
                mp: 1000.0,
                Tp: tp,
                zeta: 0.05,
                alpha: [0.2; 8],
                mus: [0.1; 8],
                muk: [0.08; 8],
            });
        }
        let mut out = vec![SllBatchOutputs::default(); 3];
        let path = CString::new(file.to_str().unwrap()).unwrap();
        let mut msg = [0 as c_char; 200];
        let run = |sets: &[SllBatchParams],
                   out: &mut [SllBatchOutputs],
                   msg: &mut [c_char; 200]| unsafe {
            sllRunBatch(
                path.as_ptr(),
                9.81,
                1.0,
                3,
                sets.as_ptr(),
                out.as_mut_ptr(),
                msg.as_mut_ptr(),
                200,
            )
        };
        let status = run(&sets, &mut out, &mut msg);
        assert_eq!(status, 0);
        for (p, got) in sets.iter().zip(&out) {
            let mut want = SllBatchOutputs::default();
            run_set(p, 9.81, &read, 1.0, &mut want, &mut { u64::MAX }).unwrap();
            assert_eq!(got, &want);
        }
        assert!(out[1].nEvents > 0.0, "the 2-block set switches");
        // A bad set is named with its variable.
        sets[1].Tp = -1.0;
        out.fill(SllBatchOutputs::default());
        let status = run(&sets, &mut out, &mut msg);
        let text = unsafe { CStr::from_ptr(msg.as_ptr()) }.to_string_lossy();
        assert_eq!(status, 3);
        assert!(text.starts_with("sllRunBatch: set 1: Tp = -1"), "{text}");
        // Checked before any runs: no result written (set 0's stays as it was).
        assert_eq!(out[0], SllBatchOutputs::default());
        // A path that is not UTF-8 is named so; a message cut inside a
        // character ends before it (the buffer holds UTF-8 text).
        let mut call = |file: &CString, msg: &mut [c_char; 200], size: usize| {
            msg.fill(1);
            let (sets, out) = (sets.as_ptr(), out.as_mut_ptr());
            let status = unsafe {
                sllRunBatch(
                    file.as_ptr(),
                    9.81,
                    1.0,
                    0,
                    sets,
                    out,
                    msg.as_mut_ptr(),
                    size,
                )
            };
            assert_eq!(status, 3);
            let bytes = unsafe { CStr::from_ptr(msg.as_ptr()) }.to_bytes();
            std::str::from_utf8(bytes).expect("UTF-8").to_string()
        };
        let latin1 = CString::new(b"caf\xe9.csv".to_vec()).unwrap();
        assert!(call(&latin1, &mut msg, 200).contains("recordFile is not UTF-8 text"));
        let missing = CString::new("/nonexistent/caf\u{e9}.csv").unwrap();
        let whole = call(&missing, &mut msg, 200);
        let at = whole.find('\u{e9}').expect("the path in the message");
        assert_eq!(call(&missing, &mut msg, at + 2), whole[..at]);
        let status = unsafe {
            sllRunBatch(
                std::ptr::null(),
                9.81,
                1.0,
                1,
                sets.as_ptr(),
                out.as_mut_ptr(),
                msg.as_mut_ptr(),
                200,
            )
        };
        assert_eq!(status, 3);
        std::fs::remove_dir_all(&dir).ok();
    }
}
