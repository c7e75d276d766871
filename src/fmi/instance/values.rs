//! fmi2Get/fmi2Set of Real, Integer, Boolean and String variables: which
//! value reference names which variable, whether it may be set in the
//! current state, the checks of each value set, and where each value read
//! comes from.

use super::{Instance, Phase, Status};
use crate::fmi::variables::{Causality, Id};
use crate::limits::{Num, MAX_PATH_BYTES};
use crate::physics::engine::Outputs;
use crate::physics::params::{ParamError, MAX_BLOCKS};
use crate::solver::SolverKind;

impl Instance {
    pub(super) fn lookup(&mut self, func: &str, vr: u32) -> Result<Id, Status> {
        let model = self.model;
        model.lookup(vr).ok_or_else(|| {
            self.error(
                func,
                format!(
                    "unknown value reference {vr} (of no variable of {})",
                    model.identifier()
                ),
            )
        })
    }

    /// The variable behind `vr`, if it exists and may be set now.
    fn target(&mut self, func: &str, vr: u32) -> Result<Id, Status> {
        let id = self.lookup(func, vr)?;
        self.settable(func, id)?;
        Ok(id)
    }

    /// Checks that variable `id` may be set now.
    fn settable(&mut self, func: &str, id: Id) -> Result<(), Status> {
        let phase = self.d.phase;
        let ok = match id.causality() {
            Causality::Parameter => {
                matches!(phase, Phase::Instantiated | Phase::InitializationMode)
            }
            Causality::Input => super::state_table::legal(func, phase),
            Causality::Output => {
                return Err(self.error(
                    func,
                    format!("{} is an output and cannot be set", name_of(id)),
                ));
            }
        };
        if ok {
            Ok(())
        } else {
            Err(self.error(
                func,
                format!("{} cannot be set in state {phase:?}", name_of(id)),
            ))
        }
    }

    pub(super) fn param_error(&mut self, func: &str, e: ParamError) -> Status {
        self.error(func, e.to_string())
    }

    /// The slot of a settable Real variable.
    fn real_slot(&mut self, id: Id) -> Option<&mut f64> {
        let v = &mut self.d.values;
        Some(match id {
            Id::Mp => &mut v.params.mp,
            Id::Tp => &mut v.params.tp,
            Id::Zeta => &mut v.params.zeta,
            Id::G => &mut v.params.g,
            Id::RecordScale => &mut v.record_scale,
            Id::MaxStep => &mut v.max_step,
            Id::FrictionEps => &mut v.friction_eps,
            Id::Alpha(j) => &mut v.params.alpha[j - 1],
            Id::Mus(j) => &mut v.params.mus[j - 1],
            Id::Muk(j) => &mut v.params.muk[j - 1],
            // StackOnFloor: mp = 1 kg, so m[j] is alpha[j].
            Id::M(j) => &mut v.params.alpha[j - 1],
            Id::Ag => &mut self.d.ag,
            Id::Fext => &mut self.d.fext,
            Id::SupportMobility => &mut self.d.support_mobility,
            _ => return None,
        })
    }

    /// After variable `id` was set: outputs show the inputs set for the
    /// next step (a master may iterate); a parameter rebuilds the simulator.
    fn changed(&mut self, id: Id) {
        self.outputs = None;
        if id.causality() == Causality::Parameter {
            self.d.sim = None;
        }
    }

    /// fmi2SetReal: every value checked before any is set (a call with one
    /// bad entry changes nothing).
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        const F: &str = "fmi2SetReal";
        for (&vr, &x) in vrs.iter().zip(values) {
            let id = match self.target(F, vr) {
                Ok(id) => id,
                Err(s) => return s,
            };
            if self.real_slot(id).is_none() {
                return self.error(F, format!("{} is not a Real", name_of(id)));
            }
            if let Err(e) = id.check(x) {
                return self.param_error(F, e);
            }
        }
        for (&vr, &x) in vrs.iter().zip(values) {
            let id = Id::from_vr(vr).expect("checked above");
            *self.real_slot(id).expect("checked above") = x;
            self.changed(id);
        }
        Status::Ok
    }

    /// fmi2SetInteger: all values checked first, as fmi2SetReal.
    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Status {
        const F: &str = "fmi2SetInteger";
        for (&vr, &x) in vrs.iter().zip(values) {
            let id = match self.target(F, vr) {
                Ok(id) => id,
                Err(s) => return s,
            };
            let lowest = self.model.range(Id::NBlocks).map_or(0, |r| r.0 as i32);
            let problem = match id {
                Id::NBlocks if (lowest..=MAX_BLOCKS as i32).contains(&x) => None,
                Id::NBlocks => Some(format!("nBlocks = {x} is not allowed: it must be an integer from {lowest} to {MAX_BLOCKS}")),
                Id::Solver if SolverKind::from_code(x).is_some() => None,
                Id::Solver => Some(format!("solver = {x} is not allowed: it must be 1 (exact, the default), 2 (RK4 switching at step ends) or 3 (tanh-regularized friction)")),
                _ => Some(format!("{} is not an Integer", name_of(id))),
            };
            if let Some(message) = problem {
                return self.error(F, message);
            }
        }
        for (&vr, &x) in vrs.iter().zip(values) {
            let id = Id::from_vr(vr).expect("checked above");
            match id {
                Id::NBlocks => self.d.values.params.n_blocks = x as usize,
                _ => self.d.values.solver = x,
            }
            self.changed(id);
        }
        Status::Ok
    }

    /// fmi2SetBoolean (nothing is settable: any reference is an error).
    pub fn set_boolean(&mut self, vrs: &[u32], _values: &[i32]) -> Status {
        const F: &str = "fmi2SetBoolean";
        // The first reference decides: it is unknown, not settable now, or
        // a Boolean output.
        match vrs.first().map(|&vr| self.target(F, vr)) {
            None => Status::Ok,
            Some(Err(s)) => s,
            Some(Ok(id)) => self.error(F, format!("{} is not a settable Boolean", name_of(id))),
        }
    }

    /// fmi2SetString: all values checked first, as fmi2SetReal.
    pub fn set_string(&mut self, vrs: &[u32], values: &[String]) -> Status {
        const F: &str = "fmi2SetString";
        for (&vr, x) in vrs.iter().zip(values) {
            let id = match self.target(F, vr) {
                Ok(id) => id,
                Err(s) => return s,
            };
            let problem = match id {
                Id::RecordFile if x.len() > MAX_PATH_BYTES => Some(format!(
                    "recordFile of {} bytes is not allowed: it must be a path of at most {MAX_PATH_BYTES} bytes",
                    x.len()
                )),
                Id::RecordFile => None,
                _ => Some(format!("{} is not a String", name_of(id))),
            };
            if let Some(message) = problem {
                return self.error(F, message);
            }
        }
        for (&vr, x) in vrs.iter().zip(values) {
            let id = Id::from_vr(vr).expect("checked above");
            self.d.values.record_file = x.clone();
            self.changed(id);
        }
        Status::Ok
    }

    fn readable(&mut self, func: &str) -> Result<(), Status> {
        self.require(func)
    }

    /// fmi2GetReal.
    pub fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Status {
        const F: &str = "fmi2GetReal";
        if let Err(s) = self.readable(F) {
            return s;
        }
        for (&vr, slot) in vrs.iter().zip(out.iter_mut()) {
            let id = match self.lookup(F, vr) {
                Ok(id) => id,
                Err(s) => return s,
            };
            let v = &self.d.values;
            let p = &v.params;
            let block = |j: usize, xs: &[f64; MAX_BLOCKS]| xs[j - 1];
            *slot = match id {
                Id::Mp => p.mp,
                Id::Tp => p.tp,
                Id::Zeta => p.zeta,
                Id::G => p.g,
                Id::RecordScale => v.record_scale,
                Id::MaxStep => v.max_step,
                Id::FrictionEps => v.friction_eps,
                Id::Alpha(j) => block(j, &p.alpha),
                Id::Mus(j) => block(j, &p.mus),
                Id::Muk(j) => block(j, &p.muk),
                Id::M(j) => block(j, &p.alpha),
                Id::Ag => self.d.ag,
                Id::Fext => self.d.fext,
                Id::SupportMobility => self.d.support_mobility,
                Id::TSwitch => self.d.t_switch,
                _ => {
                    let o = match self.current_outputs(F) {
                        Ok(o) => o,
                        Err(s) => return s,
                    };
                    match real_output(o, id) {
                        Some(x) => x,
                        None => return self.error(F, format!("{} is not a Real", name_of(id))),
                    }
                }
            };
        }
        self.all_finite(F, vrs, out, "")
    }

    /// The one check every Real getter ends with: fmi2OK only if every value
    /// it wrote is finite; otherwise fmi2Error naming the first other one.
    /// (`what`: "" for values, "derivative of " for derivatives.)
    pub(super) fn all_finite(
        &mut self,
        func: &str,
        vrs: &[u32],
        out: &[f64],
        what: &str,
    ) -> Status {
        match vrs.iter().zip(out).find(|(_, x)| !x.is_finite()) {
            None => Status::Ok,
            Some((&vr, &x)) => {
                let name = Id::from_vr(vr).map_or(vr.to_string(), name_of);
                let time = self.d.time;
                self.error(
                    func,
                    format!(
                        "the {what}{name} = {} at t = {} s is not finite (the state left the \
                         finite numbers: inputs or parameters too large for this scene)",
                        Num(x),
                        Num(time)
                    ),
                )
            }
        }
    }

    /// fmi2GetInteger.
    pub fn get_integer(&mut self, vrs: &[u32], out: &mut [i32]) -> Status {
        const F: &str = "fmi2GetInteger";
        if let Err(s) = self.readable(F) {
            return s;
        }
        for (&vr, slot) in vrs.iter().zip(out.iter_mut()) {
            *slot = match self.lookup(F, vr) {
                Ok(Id::NBlocks) => self.d.values.params.n_blocks as i32,
                Ok(Id::Solver) => self.d.values.solver,
                Ok(Id::NEvents) => match self.current_outputs(F) {
                    Ok(o) => o.n_events.min(i32::MAX as u64) as i32,
                    Err(s) => return s,
                },
                Ok(Id::NAmbiguous) => match self.current_outputs(F) {
                    Ok(o) => o.n_ambiguous.min(i32::MAX as u64) as i32,
                    Err(s) => return s,
                },
                Ok(id) => return self.error(F, format!("{} is not an Integer", name_of(id))),
                Err(s) => return s,
            };
        }
        Status::Ok
    }

    /// fmi2GetBoolean.
    pub fn get_boolean(&mut self, vrs: &[u32], out: &mut [i32]) -> Status {
        const F: &str = "fmi2GetBoolean";
        if let Err(s) = self.readable(F) {
            return s;
        }
        for (&vr, slot) in vrs.iter().zip(out.iter_mut()) {
            *slot = match self.lookup(F, vr) {
                Ok(Id::Stuck(j)) => match self.current_outputs(F) {
                    Ok(o) => i32::from(o.stuck[j - 1]),
                    Err(s) => return s,
                },
                Ok(id) => return self.error(F, format!("{} is not a Boolean", name_of(id))),
                Err(s) => return s,
            };
        }
        Status::Ok
    }

    /// fmi2GetString.
    pub fn get_string(&mut self, vrs: &[u32]) -> Result<Vec<String>, Status> {
        const F: &str = "fmi2GetString";
        self.readable(F)?;
        vrs.iter()
            .map(|&vr| match self.lookup(F, vr)? {
                Id::RecordFile => Ok(self.d.values.record_file.clone()),
                id => Err(self.error(F, format!("{} is not a String", name_of(id)))),
            })
            .collect()
    }
}

pub(super) fn name_of(id: Id) -> String {
    id.name()
}

/// The field of `o` behind a Real output computed by the simulator.
pub(super) fn real_output(o: &Outputs, id: Id) -> Option<f64> {
    let block = |j: usize, xs: &[f64; MAX_BLOCKS]| xs[j - 1];
    Some(match id {
        Id::Up => o.up,
        Id::Vp => o.vp,
        Id::ApAbs => o.ap_abs,
        Id::BaseShear => o.base_shear,
        Id::PeakUp => o.peak_up,
        Id::PeakApAbs => o.peak_ap_abs,
        Id::Einput => o.e_input,
        Id::Ekinetic => o.e_kinetic,
        Id::Estrain => o.e_strain,
        Id::Eviscous => o.e_viscous,
        Id::Efriction => o.e_friction,
        Id::Ub(j) => block(j, &o.ub),
        Id::Vb(j) => block(j, &o.vb),
        Id::Slip(j) => block(j, &o.slip),
        Id::AbAbs(j) => block(j, &o.ab_abs),
        Id::F(j) => block(j, &o.force),
        Id::PeakSlip(j) => block(j, &o.peak_slip),
        Id::FloorForce => o.floor_force,
        Id::AttachedMass => o.attached_mass,
        Id::SlidingForce => o.sliding_force,
        _ => return None,
    })
}
