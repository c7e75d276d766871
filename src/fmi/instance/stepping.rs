//! Stepping: fmi2DoStep, the outputs and the excitation at the current
//! communication point, input derivatives (fmi2SetRealInputDerivatives),
//! output derivatives (fmi2GetRealOutputDerivatives) and
//! fmi2GetRealStatus (`fmi2LastSuccessfulTime`).

use super::values::{name_of, real_output};
use super::{Instance, Phase, Status};
use crate::fmi::ports;
use crate::fmi::variables::{Causality, Id};
use crate::ground::record;
use crate::limits::{self, Num};
use crate::physics::engine::{Excitation, Outputs};
use crate::physics::params::check_scalar;
use crate::physics::solver::{Solver, Stepper};

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
            let outputs = match ports::outputs_at_step_start(sim, &exc) {
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
    fn next_excitation(&self) -> Excitation {
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
            Some(Solver::Exact(sim)) => match ports::exact_at_step_start(sim, &exc) {
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
        Status::Ok
    }

    /// `fmi2SetRealInputDerivatives`, order 1: the slope of an input over the
    /// next step (reset to zero after every step: without it the input is held).
    pub fn set_input_derivatives(&mut self, vrs: &[u32], orders: &[i32], values: &[f64]) -> Status {
        const F: &str = "fmi2SetRealInputDerivatives";
        if let Err(s) = self.require(F) {
            return s;
        }
        for ((&vr, &order), &x) in vrs.iter().zip(orders).zip(values) {
            let id = match self.lookup(F, vr) {
                Ok(id) => id,
                Err(s) => return s,
            };
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
            match id {
                Id::Ag => self.d.der_ag = x,
                Id::Fext => self.d.der_fext = x,
                _ => return self.error(F, format!("{} is not a Real input", name_of(id))),
            }
        }
        Status::Ok
    }

    /// fmi2DoStep.
    pub fn do_step(&mut self, t: f64, h: f64) -> Status {
        const F: &str = "fmi2DoStep";
        if let Err(s) = self.require(F) {
            return s;
        }
        let now = self.d.time;
        if !t.is_finite() || (t - now).abs() > 1e-9 * now.abs().max(1.0) {
            return self.error(
                F,
                format!(
                    "currentCommunicationPoint = {} does not match the FMU's time {}",
                    Num(t),
                    Num(now)
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
        if h > 0.0 && t + h == t {
            return self.error(
                F,
                format!(
                    "communicationStepSize = {} is below the resolution of time at t = {} s: \
                     it would not advance",
                    Num(h),
                    Num(t)
                ),
            );
        }
        if let Some(stop) = self.d.stop_time {
            if t + h > stop + 1e-9 * stop.abs().max(1.0) {
                return self.error(
                    F,
                    format!(
                        "stepping to {} would pass stopTime = {}",
                        Num(t + h),
                        Num(stop)
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
        let t_end = (t + h - self.d.start_time).max(sim.time());
        // Bounded work: refuse up front what would run for minutes or more.
        let samples = self
            .record
            .as_ref()
            .map_or(0, |(_, gm)| gm.samples_in(sim.time(), t_end));
        if let Some(message) = limits::work_error(
            t_end - sim.time(),
            sim.max_internal_step(),
            samples,
            sim.step_weight(),
        ) {
            return self.error(F, message);
        }
        // A jump of an input acts at the communication point, where the
        // outputs already showed it: tSwitch watches for switches after it.
        let jump = if at_start.fext != sim.fext_now() {
            sim.advance(sim.time(), &at_start)
        } else {
            Ok(())
        };
        let result = jump.and_then(|()| {
            sim.watch_switches();
            match &self.record {
                Some((_, gm)) => {
                    record::advance_with_record(sim, t_end, gm, self.d.values.record_scale, &extra)
                }
                None => sim.advance(t_end, &extra),
            }
        });
        self.outputs = None;
        let first_switch = sim.first_switch();
        let fext_end = sim.fext_now();
        // Never fmi2OK with a NaN or an infinity in an output.
        let bad = limits::non_finite_message(&sim.outputs(), self.d.start_time);
        match (result, bad) {
            (Ok(()), None) => {
                // The inputs stand where their slopes took them: the outputs
                // at t + h see them there, and an input left alone is held at
                // that value (Fext exactly as the engine ended the step, so
                // the next step sees no jump).
                self.d.ag += self.d.der_ag * h;
                self.d.fext = fext_end;
                self.d.der_ag = 0.0;
                self.d.der_fext = 0.0;
                self.d.time = t + h;
                self.d.t_switch = if first_switch.is_nan() {
                    t + h
                } else {
                    (first_switch + self.d.start_time).min(t + h)
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

    /// `fmi2LastSuccessfulTime`.
    pub fn last_successful_time(&self) -> f64 {
        self.d.time
    }
}
