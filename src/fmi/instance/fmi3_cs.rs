//! FMI 3.0 Co-Simulation over the same stepping: `fmi3DoStep` with early
//! return at the first stick/slip switch inside the step, and Event Mode
//! (`fmi3EnterEventMode`, `fmi3UpdateDiscreteStates`, `fmi3EnterStepMode`).
//!
//! A step is first taken whole, as FMI 2.0 takes it (a long one in windows
//! of [`PROBE`] doubling); if the engine located a switch inside it
//! (`tSwitch`), the step is taken again from its start up to that switch, and the FMU returns there (`earlyReturn`, `lastSuccessfulTime`
//! the switch time). The state at an early return has the switch taken, as at
//! any communication point (the outputs show the new mode); with Event Mode
//! the outputs show the mode before the switch until `fmi3UpdateDiscreteStates`
//! resolves it (the left limit, taken [`EDGE`] before the switch).

use super::{Instance, Phase, Status};
use crate::fmi::ports::SWITCH_LOOKAHEAD;

/// A switch within this many seconds of a step's end stays in that step
/// (no early return for it); a switch within it of the step's start is the
/// one the step starts with (taken by the previous step, or left to this one
/// by rounding). The engine locates a switch again along other internal steps
/// within 8e-12 s (docs/coupling-ports.md), so this is [`SWITCH_LOOKAHEAD`].
pub const EDGE: f64 = SWITCH_LOOKAHEAD;

/// The first window of a long step probed for a switch (s); windows double
/// while they have none. Steps up to this long are taken whole first.
pub const PROBE: f64 = 0.1;

/// What `fmi3DoStep` reports besides its status.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepOutcome {
    /// The status of the step.
    pub status: Status,
    /// An event (a stick/slip switch) is to be handled in Event Mode at
    /// `last_successful_time` (only with `eventModeUsed` and early return).
    pub event_handling_needed: bool,
    /// The step ended before its end, at a switch.
    pub early_return: bool,
    /// The time the FMU has reached.
    pub last_successful_time: f64,
}

/// The arguments of `fmi3DoStep` that the FMU uses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepRequest {
    /// `currentCommunicationPoint`.
    pub t: f64,
    /// `communicationStepSize`.
    pub h: f64,
}

impl Instance {
    /// The FMU's current time (the `time` variable of FMI 3.0).
    pub fn time_now(&self) -> f64 {
        self.d.time
    }

    /// fmi3ExitInitializationMode: as FMI 2.0's, then into Event Mode if the
    /// importer uses it (FMI 3.0 Co-Simulation starts there), else Step Mode.
    pub fn exit_initialization_mode_fmi3(&mut self) -> Status {
        let status = self.exit_initialization_mode();
        if status == Status::Ok && self.fmi3_flags.1 {
            self.d.phase = Phase::EventMode;
        }
        status
    }

    /// fmi3EnterEventMode (legal only with `eventModeUsed`).
    pub fn enter_event_mode(&mut self) -> Status {
        const F: &str = "fmi3EnterEventMode";
        if let Err(s) = self.require(F) {
            return s;
        }
        if !self.fmi3_flags.1 {
            return self.error(
                F,
                "Event Mode is used only if the importer instantiated with eventModeUsed = true",
            );
        }
        self.d.phase = Phase::EventMode;
        Status::Ok
    }

    /// fmi3UpdateDiscreteStates: resolves the mode at the event, with the
    /// inputs set in Event Mode in force (outputs read from now on show it).
    /// Nothing further is scheduled: the returned flags are all false.
    pub fn update_discrete_states(&mut self) -> Status {
        if let Err(s) = self.require("fmi3UpdateDiscreteStates") {
            return s;
        }
        self.outputs = None;
        Status::Ok
    }

    /// fmi3EnterStepMode.
    pub fn enter_step_mode(&mut self) -> Status {
        if let Err(s) = self.require("fmi3EnterStepMode") {
            return s;
        }
        self.outputs = None;
        self.d.phase = Phase::StepComplete;
        Status::Ok
    }

    /// fmi3DoStep: with `earlyReturnAllowed`, returns at the first
    /// stick/slip switch inside the step (see the module docs); without it,
    /// as fmi2DoStep.
    pub fn do_step_fmi3(&mut self, req: StepRequest) -> StepOutcome {
        let (early_allowed, event_mode) = self.fmi3_flags;
        let outcome = |inst: &Instance, status: Status, early: bool| StepOutcome {
            status,
            event_handling_needed: early && event_mode && status == Status::Ok,
            early_return: early && status == Status::Ok,
            last_successful_time: inst.d.time,
        };
        if !early_allowed {
            let status = self.do_step(req.t, req.h);
            return outcome(self, status, false);
        }
        let (status, early) = self.step_to_first_switch(req.t, req.h, event_mode);
        outcome(self, status, early)
    }

    /// The step from `t` over `h`, stopped at its first switch; whether it was.
    /// A long step is probed in windows ([`PROBE`], doubling while none has a
    /// switch), so that finding a switch early in it does not cost the
    /// whole step.
    fn step_to_first_switch(&mut self, t: f64, h: f64, event_mode: bool) -> (Status, bool) {
        let end = t + h;
        let (mut from, mut window) = (t, PROBE);
        loop {
            let to = if from + window >= end - EDGE {
                end
            } else {
                from + window
            };
            let (status, early) = self.window_to_first_switch(from, to - from, end, event_mode);
            if status != Status::Ok || early {
                return (status, early);
            }
            if to == end || self.d.time >= end {
                self.d.time = end;
                return (status, false);
            }
            from = self.d.time;
            window *= 2.0;
        }
    }

    /// One window from `t` over `h` of the step that ends at `end`.
    fn window_to_first_switch(
        &mut self,
        t: f64,
        h: f64,
        end: f64,
        event_mode: bool,
    ) -> (Status, bool) {
        let before = (self.d.clone(), self.outputs.clone());
        let status = self.do_step(t, h);
        let ts = self.d.t_switch;
        if status != Status::Ok || ts >= t + h || ts >= end - EDGE {
            return (status, false);
        }
        // A sliver past a switch: EDGE, or a few units of the last place at
        // times where EDGE would not move time.
        let edge = EDGE.max(8.0 * f64::EPSILON * t.abs());
        if ts <= t + EDGE {
            // The step starts on a switch: take it over a sliver, then look
            // for the next one in the rest (the engine reports the first).
            (self.d, self.outputs) = before;
            let status = self.do_step(t, edge);
            if status != Status::Ok || end - t <= 2.0 * edge {
                return (status, false);
            }
            let (status, early) =
                self.step_to_first_switch(self.d.time, end - self.d.time, event_mode);
            if !early && status == Status::Ok {
                self.d.t_switch = ts;
            }
            return (status, early);
        }
        let left = event_mode.then(|| before.clone());
        (self.d, self.outputs) = before;
        let status = self.do_step(t, ts - t);
        if status != Status::Ok {
            return (status, false);
        }
        if self.d.t_switch >= self.d.time {
            // Located again a little past where the whole step located it:
            // take it over a sliver.
            let status = self.do_step(self.d.time, edge);
            if status != Status::Ok {
                return (status, false);
            }
        }
        if let Some((d, outputs)) = left {
            // The left limit: the outputs just before the switch, shown until
            // fmi3UpdateDiscreteStates (or an input set) resolves the event.
            let after = (self.d.clone(), self.outputs.clone());
            (self.d, self.outputs) = (d, outputs);
            let shown = match self.do_step(t, (ts - edge - t).max(0.0)) {
                // Raw: the outputs at a communication point look past a switch
                // this close.
                Status::Ok => self.d.sim.as_ref().map(|s| s.outputs()),
                _ => None,
            };
            (self.d, self.outputs) = after;
            if shown.is_some() {
                self.outputs = shown;
            }
        }
        (Status::Ok, true)
    }
}
