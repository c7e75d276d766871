//! Stepping: fmi2DoStep, the outputs and the excitation at the current
//! communication point, input derivatives (fmi2SetRealInputDerivatives),
//! output derivatives (fmi2GetRealOutputDerivatives) and
//! fmi2GetRealStatus (`fmi2LastSuccessfulTime`).

use super::values::{name_of, real_output};
use super::{Instance, Phase, Status};
use crate::fmi::ports;
use crate::fmi::variables::{Causality, Id, Model};
use crate::ground::record;
use crate::limits::{self, Num};
use crate::physics::engine::{Excitation, Outputs, SimError};
use crate::physics::params::check_scalar;
use crate::solver::{Solver, Stepper};

impl Instance {
    /// Outputs of the current state; in initialization mode the simulator
    /// is built on demand from the parameters set so far.
    pub(super) fn current_outputs(&mut self, func: &str) -> Result<&Outputs, Status> {
        if self.d.sim.is_none() {
            if self.d.phase != Phase::InitializationMode {
                return Err(self.error(func, "outputs are not available before initialization"));
            }
            self.build(func)?;
        }
        if self.outputs.is_none() {
            let exc = self.next_excitation();
            let sim = self.d.sim.as_ref().expect("built above");
            let at_start = ports::outputs_at_step_start(sim, &exc, self.d.support_mobility);
            let outputs = match at_start {
                Ok(o) => o,
                Err(e) => return Err(self.error(func, e.to_string())),
            };
            // After a failed step the state may hold a NaN: never read as OK.
            if let Some(message) = limits::non_finite_message(&outputs, self.d.start_time) {
                return Err(self.error(func, message));
            }
            self.outputs = Some(outputs);
        }
        Ok(self.outputs.as_ref().expect("set above"))
    }

    /// The excitation the next step starts with: the record's piece at the
    /// current time (the next one if this one ends within rounding of now,
    /// as a step would take it) plus the inputs and their derivatives.
    pub(super) fn next_excitation(&self) -> Excitation {
        let t = self.d.sim.as_ref().map_or(0.0, |s| s.time());
        let (a, slope) = match &self.record {
            Some((_, gm)) => {
                let (mut a, mut slope, end) = gm.piece_at(t);
                if end.is_finite() && end - t <= 1e-9 * t.abs().max(1.0) {
                    let (a_end, slope_end, _) = gm.piece_at(end);
                    (a, slope) = (a_end, slope_end);
                }
                let scale = self.d.values.record_scale;
                (scale * a, scale * slope)
            }
            None => (0.0, 0.0),
        };
        Excitation {
            ag: a + self.d.ag,
            ag_rate: slope + self.d.der_ag,
            fext: self.d.fext,
            fext_rate: self.d.der_fext,
        }
    }

    /// fmi2GetRealOutputDerivatives: derivatives of order 1 or 2 of continuous
    /// Real outputs at the current communication point, in the mode the next
    /// step starts in, under the inputs and input derivatives set for it.
    pub fn get_output_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        out: &mut [f64],
    ) -> Status {
        const F: &str = "fmi2GetRealOutputDerivatives";
        if let Err(s) = self.require(F) {
            return s;
        }
        let exc = self.next_excitation();
        let derivatives = match &self.d.sim {
            Some(Solver::Exact(sim)) => match ports::exact_at_step_start(
                sim,
                &exc,
                self.d.support_mobility,
            ) {
                Ok(next) => ports::derivatives(&next, &exc),
                Err(e) => return self.error(F, e.to_string()),
            },
            _ => {
                return self.error(
                    F,
                    "output derivatives are provided by solvers 1 and 2, not by solver 3 (the regularized baseline)",
                )
            }
        };
        for ((&vr, &order), slot) in vrs.iter().zip(orders).zip(out.iter_mut()) {
            let id = match self.lookup(F, vr) {
                Ok(id) => id,
                Err(s) => return s,
            };
            if id.causality() != Causality::Output || !id.is_continuous() {
                return self.error(
                    F,
                    format!(
                        "{} is not a continuous Real output: it has no derivative",
                        name_of(id)
                    ),
                );
            }
            if !(1..=2).contains(&order) {
                return self.error(F, format!("derivative order {order} of {} is not provided: orders 1 and 2 are (maxOutputDerivativeOrder = 2)", name_of(id)));
            }
            let of_order = &derivatives[order as usize - 1];
            *slot = real_output(of_order, id).expect("every continuous Real output has a field");
        }
        self.all_finite(F, vrs, out, "derivative of ")
    }

    /// `fmi2SetRealInputDerivatives`, order 1: the slope of an input over the
    /// next step (reset to zero after every step: without it the input is held).
    pub fn set_input_derivatives(&mut self, vrs: &[u32], orders: &[i32], values: &[f64]) -> Status {
        const F: &str = "fmi2SetRealInputDerivatives";
        if let Err(s) = self.require(F) {
            return s;
        }
        // Every entry checked before any is set (all or nothing).
        for ((&vr, &order), &x) in vrs.iter().zip(orders).zip(values) {
            let id = match self.lookup(F, vr) {
                Ok(id) => id,
                Err(s) => return s,
            };
            if !matches!(id, Id::Ag | Id::Fext) {
                return self.error(
                    F,
                    format!(
                        "{} is not a continuous Real input: only ag{} take derivatives",
                        name_of(id),
                        if self.model == Model::Storey {
                            " and Fext"
                        } else {
                            ""
                        }
                    ),
                );
            }
            if order != 1 {
                return self.error(
                    F,
                    format!(
                        "derivative order {order} of {} is not supported: only order 1",
                        name_of(id)
                    ),
                );
            }
            if let Err(e) = check_scalar(&format!("der({})", name_of(id)), x) {
                return self.param_error(F, e);
            }
        }
        for (&vr, &x) in vrs.iter().zip(values) {
            match Id::from_vr(vr) {
                Some(Id::Ag) => self.d.der_ag = x,
                _ => self.d.der_fext = x,
            }
        }
        Status::Ok
    }

    /// fmi2DoStep. The FMU's time is its own: the step goes from it by
    /// exactly `h` (the master's `t` must match it up to rounding, see
    /// [`limits::time_tolerance`]), so the results depend on the step sizes
    /// only, a step of size 0 never moves time, and a master's rounding
    /// never accumulates in the FMU's clock.
    pub fn do_step(&mut self, t: f64, h: f64) -> Status {
        const F: &str = "fmi2DoStep";
        if let Err(s) = self.require(F) {
            return s;
        }
        let (now, start) = (self.d.time, self.d.start_time);
        let tol = limits::time_tolerance(now, start, self.d.steps);
        if !(t.is_finite() && (t - now).abs() <= tol) {
            return self.error(
                F,
                format!(
                    "currentCommunicationPoint = {} does not match the FMU's time {} \
                     (they may differ by rounding only: at most {} s here); step from the \
                     time the last step ended (fmi2LastSuccessfulTime)",
                    Num(t),
                    Num(now),
                    Num(tol)
                ),
            );
        }
        if !(h >= 0.0 && h.is_finite()) {
            return self.error(
                F,
                format!(
                    "communicationStepSize = {} is not allowed: it must be finite and >= 0",
                    Num(h)
                ),
            );
        }
        let sim_time = self.d.sim.as_ref().expect("built at initialization").time();
        let sim_end = sim_time + h;
        let end = if h == 0.0 { now } else { start + sim_end };
        if h > 0.0 && end <= now {
            return self.error(
                F,
                format!(
                    "communicationStepSize = {} is below the resolution of time at t = {} s: \
                     it would not advance",
                    Num(h),
                    Num(now)
                ),
            );
        }
        if let Some(stop) = self.d.stop_time {
            if !limits::within_stop(end, stop) {
                return self.error(
                    F,
                    format!(
                        "stepping to {} would pass stopTime = {}",
                        Num(end),
                        Num(stop)
                    ),
                );
            }
        }
        // The inputs' slopes keep them in their ranges over the step.
        let ag_end = self.d.ag + self.d.der_ag * h;
        let fext_end = self.d.fext + self.d.der_fext * h;
        for (name, x0, slope, x1) in [
            ("ag", self.d.ag, self.d.der_ag, ag_end),
            ("Fext", self.d.fext, self.d.der_fext, fext_end),
        ] {
            if let Err(e) = check_scalar(name, x1) {
                return self.error(
                    F,
                    format!(
                        "der({name}) = {} takes {name} from {} to {} over communicationStepSize \
                         = {} s, outside its range: {name} must stay {}; shorten the step or \
                         lower the slope",
                        Num(slope),
                        Num(x0),
                        Num(x1),
                        Num(h),
                        e.allowed
                    ),
                );
            }
        }
        let extra = Excitation {
            ag: self.d.ag,
            ag_rate: self.d.der_ag,
            fext: self.d.fext,
            fext_rate: self.d.der_fext,
        };
        let at_start = self.next_excitation();
        let sim = self.d.sim.as_mut().expect("built at initialization");
        // Bounded work: refuse up front what would run for minutes or more.
        let samples = self
            .record
            .as_ref()
            .map_or(0, |(_, gm)| gm.samples_in(sim_time, sim_end));
        let weight = sim.step_weight();
        if let Some(message) = limits::work_error(h, sim.max_internal_step(), samples, weight) {
            return self.error(F, message);
        }
        // What switches spend, counted as they happen: a call that spends
        // the budget is stopped and undone (the state before it is kept).
        let before = sim.clone();
        if let Solver::Exact(s) = sim {
            s.set_work_budget((limits::MAX_STEPS_PER_CALL / weight) as u64);
        }
        // A jump of an input acts at the communication point, where the
        // outputs already showed it: tSwitch watches for switches after it.
        let jump = ports::take_inputs(sim, &at_start, self.d.support_mobility);
        let result = jump.and_then(|()| {
            sim.watch_switches();
            match &self.record {
                Some((_, gm)) => record::advance_with_record(
                    sim,
                    sim_end,
                    gm,
                    self.d.values.record_scale,
                    &extra,
                ),
                None => sim.advance(sim_end, &extra),
            }
        });
        self.outputs = None;
        if let Err(SimError::WorkLimit { t: stopped }) = result {
            *sim = before;
            return self.error(
                F,
                format!(
                    "the stick/slip switches spent the work bound of one call ({:e} internal \
                     steps' worth, a few seconds) at t = {} s, before the step's end at {} s: \
                     the step was not taken (the FMU stays at t = {} s, as before the call); \
                     split it into shorter communication steps",
                    limits::MAX_STEPS_PER_CALL,
                    Num(start + stopped),
                    Num(end),
                    Num(now)
                ),
            );
        }
        let first_switch = sim.first_switch();
        // The inputs stand where their slopes took them: the outputs at the
        // step's end see them there, and an input left alone is held at that
        // value: `ag` as the engine took its input part to the step's end (a
        // support's outputs see it), `Fext` as the engine ended the step (the
        // next step sees no jump). Both differ from the values checked above
        // by rounding only, which can take a ramp to a range's end an ulp past
        // it: the checked value then, which the engine is given to hold (its
        // saved state is checked as an input).
        let held = |name, engine: f64, checked| match check_scalar(name, engine) {
            Ok(()) => engine,
            Err(_) => checked,
        };
        let ag_held = held(
            "ag",
            self.d.ag + self.d.der_ag * (sim_end - sim_time),
            ag_end,
        );
        let fext_held = held("Fext", sim.fext_now(), fext_end);
        let result = result.and_then(|()| {
            if fext_held == sim.fext_now() {
                return Ok(());
            }
            sim.hold_fext(fext_held)
        });
        // Never fmi2OK with a NaN or an infinity in an output.
        let bad = limits::non_finite_message(&sim.outputs(), start);
        match (result, bad) {
            (Ok(()), None) => {
                (self.d.ag, self.d.fext) = (ag_held, fext_held);
                self.d.der_ag = 0.0;
                self.d.der_fext = 0.0;
                self.d.time = end;
                if h > 0.0 {
                    self.d.steps += 1;
                }
                self.d.t_switch = if first_switch.is_nan() {
                    end
                } else {
                    (first_switch + start).clamp(now, end)
                };
                Status::Ok
            }
            (result, bad) => {
                self.d.phase = Phase::Error;
                let message =
                    bad.unwrap_or_else(|| result.err().map(|e| e.to_string()).unwrap_or_default());
                self.error(F, message)
            }
        }
    }

    /// fmi2GetDirectionalDerivative (and fmi3GetDirectionalDerivative):
    /// `out[i] = sum_k d unknowns[i] / d knowns[k] * seed[k]` at the current
    /// communication point, in the mode the next step starts in, for Real
    /// outputs with respect to inputs ([`ports::directional`]). `seed` has one entry per known, `out` one
    /// per unknown.
    pub fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        out: &mut [f64],
    ) -> Status {
        const F: &str = "fmi2GetDirectionalDerivative";
        if let Err(s) = self.require(F) {
            return s;
        }
        if seed.len() != knowns.len() || out.len() != unknowns.len() {
            return self.error(
                F,
                format!(
                    "{} seed values for {} knowns and {} sensitivities for {} unknowns: one \
                     seed per known and one sensitivity per unknown",
                    seed.len(),
                    knowns.len(),
                    out.len(),
                    unknowns.len()
                ),
            );
        }
        let mut known_ids = Vec::with_capacity(knowns.len());
        for &vr in knowns {
            let id = match self.lookup(F, vr) {
                Ok(id) => id,
                Err(s) => return s,
            };
            if id.causality() != Causality::Input {
                return self.error(
                    F,
                    format!(
                        "{} is not an input: the knowns of a directional derivative are inputs \
                         ({})",
                        name_of(id),
                        match self.model {
                            Model::Floor => "ag, supportMobility",
                            Model::Storey => "ag, Fext",
                        }
                    ),
                );
            }
            known_ids.push(id);
        }
        let mut unknown_ids = Vec::with_capacity(unknowns.len());
        for &vr in unknowns {
            let id = match self.lookup(F, vr) {
                Ok(id) => id,
                Err(s) => return s,
            };
            if id.causality() != Causality::Output || id.kind() != crate::fmi::variables::Kind::Real
            {
                return self.error(
                    F,
                    format!(
                        "{} is not a Real output: it has no directional derivative",
                        name_of(id)
                    ),
                );
            }
            unknown_ids.push(id);
        }
        if let Some((k, x)) = seed.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return self.error(
                F,
                format!(
                    "the seed of {} is {}: it must be finite",
                    name_of(known_ids[k]),
                    Num(*x)
                ),
            );
        }
        let o = match self.current_outputs(F) {
            Ok(o) => o.clone(),
            Err(s) => return s,
        };
        // In the mode the next step starts in, as the outputs.
        let next = match &self.d.sim {
            Some(Solver::Exact(sim)) => {
                let exc = self.next_excitation();
                match ports::exact_at_step_start(sim, &exc, self.d.support_mobility) {
                    Ok(next) => next,
                    Err(e) => return self.error(F, e.to_string()),
                }
            }
            _ => {
                return self.error(
                    F,
                    "directional derivatives are provided by solvers 1 and 2, not by solver 3 \
                     (the regularized baseline)",
                )
            }
        };
        for (slot, &unknown) in out.iter_mut().zip(&unknown_ids) {
            // -0.0: the identity of IEEE addition (a single term comes out unchanged).
            let mut sum = -0.0;
            for (&known, &dv) in known_ids.iter().zip(seed) {
                match ports::directional(&next, &o, unknown, known) {
                    Some(d) => sum += d * dv,
                    None => {
                        return self.error(
                            F,
                            format!(
                                "d {} / d {} is not provided",
                                name_of(unknown),
                                name_of(known)
                            ),
                        )
                    }
                }
            }
            *slot = sum;
        }
        self.all_finite(F, unknowns, out, "directional derivative of ")
    }

    /// `fmi2LastSuccessfulTime`.
    pub fn last_successful_time(&self) -> f64 {
        self.d.time
    }
}
