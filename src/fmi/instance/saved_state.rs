//! Saved states: fmi2GetFMUstate and fmi2SetFMUstate, the explicit,
//! versioned byte format of `fmi2SerializeFMUstate` and
//! `fmi2DeSerializeFMUstate`, and the checks of a deserialized saved state
//! beyond what the engine checks of its own state: a blob changed anywhere
//! must be refused, never lead to a panic, a hang or a non-finite output.

use super::{floor, Dynamic, Instance, ParameterValues, Phase, SavedState, Status};
use crate::fmi::variables::Model;
use crate::physics::params::Params;
use crate::physics::snapshot::{ByteReader, ByteWriter};

const STATE_MAGIC: &[u8; 8] = b"SLLSTATE";
/// 4: the count of steps (the time tolerance), and every field checked.
/// 5: the engine's support (structure or prescribed) and support mobility;
/// the FMU's model (StackedLiveLoad 0, StackOnFloor 1) and `supportMobility`.
/// 6: the reference mode of the support's law (the engine's).
const STATE_VERSION: u32 = 6;
use crate::limits::{self, Num, MAX_PATH_BYTES, MAX_TIME};
use crate::physics::params::{check_scalar, MAX_BLOCKS};
use crate::physics::snapshot::SnapshotError;
use crate::solver::{Solver, SolverKind, Stepper};

/// Every field of a deserialized state, beyond what the engine checks of its
/// own: times, parameters (of every block, present or not) and inputs with
/// their slopes in the ranges `fmi2SetReal` allows, a solver that is the one
/// its parameters build, its clock the FMU's, finite outputs
/// (docs/robustness.md, "Saved states").
pub(super) fn check_saved(d: &Dynamic) -> Result<(), SnapshotError> {
    if d.phase == Phase::Error {
        return Err("a saved state is never in the Error state".into());
    }
    let in_range = |t: f64| t.abs() <= MAX_TIME;
    let stop_ok = d
        .stop_time
        .is_none_or(|stop| in_range(stop) && stop >= d.start_time);
    // (The time may pass MAX_TIME by stepping, as far as the work bound goes.)
    let time_ok = in_range(d.start_time)
        && d.time.is_finite()
        && d.time >= d.start_time
        && d.stop_time
            .is_none_or(|stop| limits::within_stop(d.time, stop));
    let switch_ok = d.t_switch >= d.start_time && d.t_switch <= d.time;
    if !(stop_ok && time_ok && switch_ok) {
        return Err(format!(
            "times of the saved state are not consistent: startTime {}, stopTime {}, time {}, \
             tSwitch {} (start <= tSwitch <= time <= stop, start and stop within {} s)",
            Num(d.start_time),
            d.stop_time.map_or("none".into(), |s| Num(s).to_string()),
            Num(d.time),
            Num(d.t_switch),
            Num(MAX_TIME)
        ));
    }
    let v = &d.values;
    if v.record_file.len() > MAX_PATH_BYTES {
        return Err("the saved recordFile is longer than a path".into());
    }
    if SolverKind::from_code(v.solver).is_none() {
        return Err(format!("solver {} of the saved state is unknown", v.solver));
    }
    let p = &v.params;
    if p.n_blocks > MAX_BLOCKS {
        return Err(format!(
            "nBlocks {} of the saved state is above 8",
            p.n_blocks
        ));
    }
    // The ranges of fmi2SetReal, for every value it could have set.
    let scalars = [
        ("mp", p.mp),
        ("Tp", p.tp),
        ("zeta", p.zeta),
        ("g", p.g),
        ("recordScale", v.record_scale),
        ("maxStep", v.max_step),
        ("frictionEps", v.friction_eps),
        ("ag", d.ag),
        ("Fext", d.fext),
        ("der(ag)", d.der_ag),
        ("der(Fext)", d.der_fext),
        ("supportMobility", d.support_mobility),
    ];
    let blocks =
        (0..MAX_BLOCKS).flat_map(|j| [("alpha", p.alpha[j]), ("mus", p.mus[j]), ("muk", p.muk[j])]);
    for (name, x) in scalars.into_iter().chain(blocks) {
        check_scalar(name, x).map_err(|e| format!("saved value {e}"))?;
    }
    let Some(sim) = &d.sim else {
        if matches!(d.phase, Phase::StepComplete | Phase::EventMode) {
            return Err("a saved state ready to step has no simulator".into());
        }
        // Before initialization the simulator's clock has not started.
        if d.time != d.start_time || d.steps != 0 {
            return Err("a saved state before initialization has moved its time".into());
        }
        // The cross-field rules wait for fmi2ExitInitializationMode.
        return Ok(());
    };
    if (d.model == Model::Floor) != floor::is_prescribed(p) {
        return Err("the saved scene is not one of the saved model".into());
    }
    if d.model == Model::Floor && (d.fext != 0.0 || d.der_fext != 0.0 || v.solver != 1) {
        return Err("a saved StackOnFloor state has an external force or another solver".into());
    }
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
    // The force the engine holds is an input too.
    check_scalar("Fext", sim.fext_now()).map_err(|e| format!("saved simulator's {e}"))?;
    // The FMU's time is the start plus the simulator's own, as every step
    // leaves it.
    if (d.start_time + sim.time()).to_bits() != d.time.to_bits() {
        return Err(format!(
            "the saved simulator's time {} does not match the saved time {} - {}",
            Num(sim.time()),
            Num(d.time),
            Num(d.start_time)
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
        if state.0.model != self.model {
            return self.error(
                F,
                format!(
                    "the state was saved by a {} instance; this one is a {}",
                    state.0.model.identifier(),
                    self.model.identifier()
                ),
            );
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
        w.u8(match d.model {
            Model::Storey => 0,
            Model::Floor => 1,
        });
        w.u8(d.phase as u8);
        w.f64s(&[d.start_time, d.stop_time.unwrap_or(0.0), d.time]);
        w.u8(u8::from(d.stop_time.is_some()));
        w.u64(d.steps);
        w.f64(d.t_switch);
        let v = &d.values;
        w.str(&v.record_file);
        w.f64s(&[v.record_scale, v.max_step, v.friction_eps]);
        w.u32(v.solver as u32);
        w.f64s(&[d.ag, d.fext, d.der_ag, d.der_fext, d.support_mobility]);
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
        let model = match r.u8()? {
            0 => Model::Storey,
            1 => Model::Floor,
            x => return Err(format!("unknown model {x}")),
        };
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
        let stop_time = match r.u8()? {
            0 => None,
            1 => Some(stop),
            x => return Err(format!("unknown stop-time flag {x}")),
        };
        let steps = r.u64()?;
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
        let support_mobility = r.f64()?;
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
            model,
            phase,
            start_time,
            stop_time,
            time,
            steps,
            t_switch,
            values,
            ag,
            fext,
            der_ag,
            der_fext,
            support_mobility,
            sim,
        };
        check_saved(&d)?;
        Ok(SavedState(d))
    }
}
