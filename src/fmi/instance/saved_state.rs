//! Saved states: fmi2GetFMUstate and fmi2SetFMUstate, the explicit,
//! versioned byte format of `fmi2SerializeFMUstate` and
//! `fmi2DeSerializeFMUstate`, and the checks of a deserialized saved state
//! beyond what the engine checks of its own state: a blob changed anywhere
//! must be refused, never lead to a panic, a hang or a non-finite output.

use super::{Dynamic, Instance, ParameterValues, Phase, SavedState, Status};
use crate::physics::params::Params;
use crate::physics::snapshot::{ByteReader, ByteWriter};

const STATE_MAGIC: &[u8; 8] = b"SLLSTATE";
const STATE_VERSION: u32 = 3;
use crate::limits::MAX_PATH_BYTES;
use crate::physics::params::{check_scalar, MAX_BLOCKS};
use crate::physics::snapshot::SnapshotError;
use crate::physics::solver::{Solver, SolverKind, Stepper};

/// Every field of a deserialized state, beyond what the engine checks of its
/// own: times, parameters in range, a solver that is the one its parameters
/// build, finite inputs and outputs (docs/robustness.md, "Saved states").
pub(super) fn check_saved(d: &Dynamic) -> Result<(), SnapshotError> {
    if d.phase == Phase::Error {
        return Err("a saved state is never in the Error state".into());
    }
    let stop_ok = d
        .stop_time
        .is_none_or(|stop| stop.is_finite() && stop >= d.start_time);
    let tol = 1e-9 * d.time.abs().max(1.0);
    let time_ok = d.start_time.is_finite()
        && d.time.is_finite()
        && d.time >= d.start_time
        && d.stop_time.is_none_or(|stop| d.time <= stop + tol);
    if !(stop_ok && time_ok) {
        return Err(format!(
            "times of the saved state are not consistent: startTime {}, stopTime {:?}, time {}",
            d.start_time, d.stop_time, d.time
        ));
    }
    let v = &d.values;
    if v.record_file.len() > MAX_PATH_BYTES {
        return Err("the saved recordFile is longer than a path".into());
    }
    if SolverKind::from_code(v.solver).is_none() {
        return Err(format!("solver {} of the saved state is unknown", v.solver));
    }
    for (name, x) in [
        ("recordScale", v.record_scale),
        ("maxStep", v.max_step),
        ("frictionEps", v.friction_eps),
    ] {
        check_scalar(name, x).map_err(|e| format!("saved parameter {e}"))?;
    }
    if ![d.ag, d.fext, d.der_ag, d.der_fext]
        .iter()
        .all(|x| x.is_finite())
    {
        return Err("a saved input is not finite".into());
    }
    let Some(sim) = &d.sim else {
        if matches!(d.phase, Phase::StepComplete | Phase::EventMode) {
            return Err("a saved state ready to step has no simulator".into());
        }
        // Before initialization each value was checked as it was set; the
        // cross-field rules wait for fmi2ExitInitializationMode.
        let p = &v.params;
        if p.n_blocks > MAX_BLOCKS {
            return Err(format!(
                "nBlocks {} of the saved state is above 8",
                p.n_blocks
            ));
        }
        let scalars = [("mp", p.mp), ("Tp", p.tp), ("zeta", p.zeta), ("g", p.g)];
        for (name, x) in scalars.into_iter().chain(
            (0..MAX_BLOCKS)
                .flat_map(|j| [("alpha", p.alpha[j]), ("mus", p.mus[j]), ("muk", p.muk[j])]),
        ) {
            check_scalar(name, x).map_err(|e| format!("saved parameter {e}"))?;
        }
        return Ok(());
    };
    let fresh = v.build().map_err(|e| format!("saved parameter {e}"))?;
    let same_solver = match (sim, &fresh) {
        (Solver::Exact(a), Solver::Exact(b)) => a.settings() == b.settings(),
        (Solver::Regularized(a), Solver::Regularized(b)) => {
            a.eps().to_bits() == b.eps().to_bits() && a.step().to_bits() == b.step().to_bits()
        }
        _ => false,
    };
    if !same_solver {
        return Err("the saved simulator is not the one its saved parameters build".into());
    }
    if (d.start_time + sim.time() - d.time).abs() > tol {
        return Err(format!(
            "the saved simulator's time {} does not match the saved time {}",
            sim.time(),
            d.time - d.start_time
        ));
    }
    if let Some(message) = crate::limits::non_finite_message(&sim.outputs(), d.start_time) {
        return Err(format!("saved state: {message}"));
    }
    Ok(())
}

impl Instance {
    /// fmi2GetFMUstate.
    pub fn save(&mut self) -> Result<SavedState, Status> {
        self.require("fmi2GetFMUstate")?;
        Ok(SavedState(self.d.clone()))
    }

    /// fmi2SetFMUstate (re-reads the record if the state names another).
    pub fn restore(&mut self, state: &SavedState) -> Status {
        const F: &str = "fmi2SetFMUstate";
        if let Err(s) = self.require(F) {
            return s;
        }
        self.d = state.0.clone();
        self.outputs = None;
        if self.d.sim.is_some() {
            if let Err(s) = self.load_record(F) {
                self.d.phase = Phase::Error;
                return s;
            }
        }
        Status::Ok
    }

    /// The explicit, versioned byte format of a saved state.
    pub fn serialize(state: &SavedState) -> Vec<u8> {
        let d = &state.0;
        let mut w = ByteWriter::default();
        w.buf.extend_from_slice(STATE_MAGIC);
        w.u32(STATE_VERSION);
        w.u8(d.phase as u8);
        w.f64s(&[d.start_time, d.stop_time.unwrap_or(f64::NAN), d.time]);
        w.f64(d.t_switch);
        let v = &d.values;
        w.str(&v.record_file);
        w.f64s(&[v.record_scale, v.max_step, v.friction_eps]);
        w.u32(v.solver as u32);
        w.f64s(&[d.ag, d.fext, d.der_ag, d.der_fext]);
        // The parameters travel with the simulator when it exists; before
        // initialization they are written on their own.
        match &d.sim {
            Some(sim) => {
                w.u8(1);
                sim.write_state(&mut w);
            }
            None => {
                w.u8(0);
                v.params.write(&mut w);
            }
        }
        w.buf
    }

    /// Reads the byte format of [`Instance::serialize`].
    pub fn deserialize(bytes: &[u8]) -> Result<SavedState, SnapshotError> {
        let magic = bytes.get(..8).ok_or("the saved state is truncated")?;
        if magic != STATE_MAGIC {
            return Err("not a StackedLiveLoad state".into());
        }
        let mut r = ByteReader::new(&bytes[8..]);
        let version = r.u32()?;
        if version != STATE_VERSION {
            return Err(format!(
                "state format version {version} is not supported (this FMU reads {STATE_VERSION})"
            ));
        }
        let phase = match r.u8()? {
            0 => Phase::Instantiated,
            1 => Phase::InitializationMode,
            2 => Phase::StepComplete,
            3 => Phase::Terminated,
            4 => Phase::Error,
            5 => Phase::EventMode,
            x => return Err(format!("unknown phase {x}")),
        };
        let (start_time, stop, time) = (r.f64()?, r.f64()?, r.f64()?);
        let t_switch = r.f64()?;
        let mut values = ParameterValues {
            record_file: r.str()?,
            record_scale: r.f64()?,
            max_step: r.f64()?,
            friction_eps: r.f64()?,
            solver: r.u32()? as i32,
            ..ParameterValues::default()
        };
        let (ag, fext, der_ag, der_fext) = (r.f64()?, r.f64()?, r.f64()?, r.f64()?);
        let sim = match r.u8()? {
            1 => {
                let sim = Solver::read_state(&mut r)?;
                values.params = sim.params().clone();
                Some(sim)
            }
            _ => {
                values.params = Params::read(&mut r)?;
                None
            }
        };
        if !r.is_empty() {
            return Err("the saved state has trailing bytes".into());
        }
        let d = Dynamic {
            phase,
            start_time,
            stop_time: (!stop.is_nan()).then_some(stop),
            time,
            t_switch,
            values,
            ag,
            fext,
            der_ag,
            der_fext,
            sim,
        };
        check_saved(&d)?;
        Ok(SavedState(d))
    }
}
