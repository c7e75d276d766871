//! Which call is legal in which state: one row per function, with its FMI 2.0
//! and FMI 3.0 names and the mask of the states where it may be called (as the
//! FMI standards' state machines, and the Reference FMUs, write them). Both
//! ABIs go through the one instance layer, which checks every call here
//! ([`Instance::require`](super::Instance)); messages name the function as the
//! importer called it ([`name_for`]).
//!
//! Functions of one ABI only have an empty name in the other. Functions that
//! are exported but not provided (Model Exchange, clocks, other value types)
//! have no row: they fail in every state, with a message.

use super::{Instance, Phase, Status};

/// The ABI an instance was created through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Abi {
    /// FMI 2.0 Co-Simulation (`fmi2*`).
    Fmi2,
    /// FMI 3.0 Co-Simulation (`fmi3*`).
    Fmi3,
}

/// A set of states (one bit per [`Phase`]).
pub type Mask = u8;

/// The bit of a state.
pub const fn bit(phase: Phase) -> Mask {
    match phase {
        Phase::Instantiated => 1,
        Phase::InitializationMode => 2,
        Phase::EventMode => 4,
        Phase::StepComplete => 8,
        Phase::Terminated => 16,
        Phase::Error => 32,
    }
}

const INST: Mask = bit(Phase::Instantiated);
const INIT: Mask = bit(Phase::InitializationMode);
const EVENT: Mask = bit(Phase::EventMode);
const STEP: Mask = bit(Phase::StepComplete);
const TERM: Mask = bit(Phase::Terminated);
const ERR: Mask = bit(Phase::Error);
/// Every state.
pub const ANY: Mask = INST | INIT | EVENT | STEP | TERM | ERR;

/// One function of the table.
#[derive(Clone, Copy, Debug)]
pub struct Row {
    /// Its FMI 2.0 name ("" if FMI 3.0 only).
    pub fmi2: &'static str,
    /// Its FMI 3.0 name ("" if FMI 2.0 only).
    pub fmi3: &'static str,
    /// The states where it is legal.
    pub legal: Mask,
}

const fn row(fmi2: &'static str, fmi3: &'static str, legal: Mask) -> Row {
    Row { fmi2, fmi3, legal }
}

/// Outputs are readable once initialization has begun, after a failed step too.
const READ: Mask = INIT | EVENT | STEP | TERM | ERR;

/// The table. A variable's own rule (parameters only before initialization
/// ends, outputs never) is checked beside it, in `values`.
pub const TABLE: &[Row] = &[
    row("fmi2SetDebugLogging", "fmi3SetDebugLogging", ANY),
    row("fmi2SetupExperiment", "fmi3EnterInitializationMode", INST),
    row(
        "fmi2EnterInitializationMode",
        "fmi3EnterInitializationMode",
        INST,
    ),
    row(
        "fmi2ExitInitializationMode",
        "fmi3ExitInitializationMode",
        INIT,
    ),
    row("", "fmi3EnterEventMode", STEP),
    row("", "fmi3UpdateDiscreteStates", EVENT),
    row("", "fmi3EnterStepMode", EVENT),
    row("fmi2Terminate", "fmi3Terminate", INIT | EVENT | STEP),
    row("fmi2Reset", "fmi3Reset", ANY),
    row("fmi2GetReal", "fmi3GetFloat64", READ),
    row("fmi2GetInteger", "fmi3GetInt32", READ),
    row("fmi2GetBoolean", "fmi3GetBoolean", READ),
    row("fmi2GetString", "fmi3GetString", READ),
    row("fmi2SetReal", "fmi3SetFloat64", INST | INIT | EVENT | STEP),
    row("fmi2SetInteger", "fmi3SetInt32", INST | INIT),
    row(
        "fmi2SetBoolean",
        "fmi3SetBoolean",
        INST | INIT | EVENT | STEP,
    ),
    row("fmi2SetString", "fmi3SetString", INST | INIT),
    row(
        "fmi2GetFMUstate",
        "fmi3GetFMUState",
        INST | INIT | EVENT | STEP | TERM,
    ),
    row("fmi2SetFMUstate", "fmi3SetFMUState", ANY),
    row("fmi2FreeFMUstate", "fmi3FreeFMUState", ANY),
    row(
        "fmi2SerializedFMUstateSize",
        "fmi3SerializedFMUStateSize",
        ANY,
    ),
    row("fmi2SerializeFMUstate", "fmi3SerializeFMUState", ANY),
    row("fmi2DeSerializeFMUstate", "fmi3DeserializeFMUState", ANY),
    row("fmi2SetRealInputDerivatives", "", INST | INIT | STEP),
    row(
        "fmi2GetRealOutputDerivatives",
        "fmi3GetOutputDerivatives",
        EVENT | STEP | TERM,
    ),
    row(
        "fmi2GetDirectionalDerivative",
        "fmi3GetDirectionalDerivative",
        READ,
    ),
    row("fmi2DoStep", "fmi3DoStep", STEP),
    row("fmi2GetStatus", "", STEP | TERM | ERR),
    row("fmi2GetRealStatus", "", STEP | TERM | ERR),
    row("fmi2GetIntegerStatus", "", STEP | TERM | ERR),
    row("fmi2GetBooleanStatus", "", STEP | TERM | ERR),
    row("fmi2GetStringStatus", "", STEP | TERM | ERR),
];

/// The row of a function, by either of its names.
pub fn row_of(name: &str) -> Option<&'static Row> {
    TABLE.iter().find(|r| r.fmi2 == name || r.fmi3 == name)
}

/// Whether `name` may be called in `phase` (a function with no row: never).
pub fn legal(name: &str, phase: Phase) -> bool {
    row_of(name).is_some_and(|r| r.legal & bit(phase) != 0)
}

/// The name of function `name` in `abi` (itself if it has no row or no
/// name there).
pub fn name_for(name: &str, abi: Abi) -> &str {
    match (row_of(name), abi) {
        (Some(r), Abi::Fmi2) if !r.fmi2.is_empty() => r.fmi2,
        (Some(r), Abi::Fmi3) if !r.fmi3.is_empty() => r.fmi3,
        _ => name,
    }
}

impl Instance {
    /// Errors (logged) unless `func` is legal now: for calls that the C API
    /// answers without another instance method (the FMI 2.0 status queries).
    pub fn check_call(&mut self, func: &str) -> Result<(), Status> {
        self.require(func)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_has_one_row_and_names_map_both_ways() {
        for r in TABLE {
            for name in [r.fmi2, r.fmi3] {
                if !name.is_empty() && name != "fmi3EnterInitializationMode" {
                    let rows = TABLE
                        .iter()
                        .filter(|x| x.fmi2 == name || x.fmi3 == name)
                        .count();
                    assert_eq!(rows, 1, "{name}");
                }
            }
        }
        assert_eq!(name_for("fmi2DoStep", Abi::Fmi3), "fmi3DoStep");
        assert_eq!(name_for("fmi3GetFloat64", Abi::Fmi2), "fmi2GetReal");
        assert_eq!(
            name_for("fmi2SetRealInputDerivatives", Abi::Fmi3),
            "fmi2SetRealInputDerivatives"
        );
        assert!(legal("fmi2DoStep", Phase::StepComplete));
        assert!(!legal("fmi3DoStep", Phase::EventMode));
        assert!(legal("fmi3UpdateDiscreteStates", Phase::EventMode));
        assert!(!legal("fmi3GetClock", Phase::StepComplete));
    }
}
