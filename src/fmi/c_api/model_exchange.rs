//! The FMI 2.0 Model Exchange functions of fmi2Functions.h: exported, so that
//! an importer that resolves every symbol loads the library, and failing with
//! a message (this FMU is Co-Simulation only: fmi2Instantiate refuses
//! fmi2ModelExchange, so no instance is ever in a Model Exchange state).

use super::*;

const WHY: &str = "a Model Exchange function: this FMU provides Co-Simulation only";

unsafe fn not_provided(c: fmi2Component, func: &str) -> fmi2Status {
    with(c, func, |comp| comp.instance.error(func, WHY))
}

/// Model Exchange only: always fmi2Error.
#[no_mangle]
pub unsafe extern "C" fn fmi2EnterEventMode(c: fmi2Component) -> fmi2Status {
    not_provided(c, "fmi2EnterEventMode")
}

/// The event information of `fmi2NewDiscreteStates` (FMI 2.0 `fmi2EventInfo`).
#[repr(C)]
pub struct fmi2EventInfo {
    /// newDiscreteStatesNeeded.
    pub newDiscreteStatesNeeded: fmi2Boolean,
    /// terminateSimulation.
    pub terminateSimulation: fmi2Boolean,
    /// nominalsOfContinuousStatesChanged.
    pub nominalsOfContinuousStatesChanged: fmi2Boolean,
    /// valuesOfContinuousStatesChanged.
    pub valuesOfContinuousStatesChanged: fmi2Boolean,
    /// nextEventTimeDefined.
    pub nextEventTimeDefined: fmi2Boolean,
    /// nextEventTime.
    pub nextEventTime: fmi2Real,
}

/// Model Exchange only: always fmi2Error.
#[no_mangle]
pub unsafe extern "C" fn fmi2NewDiscreteStates(
    c: fmi2Component,
    _eventInfo: *mut fmi2EventInfo,
) -> fmi2Status {
    not_provided(c, "fmi2NewDiscreteStates")
}

/// Model Exchange only: always fmi2Error.
#[no_mangle]
pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(c: fmi2Component) -> fmi2Status {
    not_provided(c, "fmi2EnterContinuousTimeMode")
}

/// Model Exchange only: always fmi2Error.
#[no_mangle]
pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
    c: fmi2Component,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
    _enterEventMode: *mut fmi2Boolean,
    _terminateSimulation: *mut fmi2Boolean,
) -> fmi2Status {
    not_provided(c, "fmi2CompletedIntegratorStep")
}

/// Model Exchange only: always fmi2Error.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetTime(c: fmi2Component, _time: fmi2Real) -> fmi2Status {
    not_provided(c, "fmi2SetTime")
}

/// Model Exchange only: always fmi2Error.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetContinuousStates(
    c: fmi2Component,
    _x: *const fmi2Real,
    _nx: usize,
) -> fmi2Status {
    not_provided(c, "fmi2SetContinuousStates")
}

/// Model Exchange only: always fmi2Error.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetDerivatives(
    c: fmi2Component,
    _derivatives: *mut fmi2Real,
    _nx: usize,
) -> fmi2Status {
    not_provided(c, "fmi2GetDerivatives")
}

/// Model Exchange only: always fmi2Error.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetEventIndicators(
    c: fmi2Component,
    _eventIndicators: *mut fmi2Real,
    _ni: usize,
) -> fmi2Status {
    not_provided(c, "fmi2GetEventIndicators")
}

/// Model Exchange only: always fmi2Error.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetContinuousStates(
    c: fmi2Component,
    _x: *mut fmi2Real,
    _nx: usize,
) -> fmi2Status {
    not_provided(c, "fmi2GetContinuousStates")
}

/// Model Exchange only: always fmi2Error.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
    c: fmi2Component,
    _x_nominal: *mut fmi2Real,
    _nx: usize,
) -> fmi2Status {
    not_provided(c, "fmi2GetNominalsOfContinuousStates")
}
