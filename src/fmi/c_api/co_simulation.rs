//! Co-simulation: input and output derivatives, stepping, status queries.

use super::*;

/// First derivatives of `ag` and `Fext` over the next step (order 1 only).
#[no_mangle]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *const fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2SetRealInputDerivatives";
    with(c, F, |comp| {
        match (slice(vr, nvr), slice(order, nvr), slice(value, nvr)) {
            (Some(vr), Some(order), Some(value)) => {
                comp.instance.set_input_derivatives(vr, order, value)
            }
            _ => null_argument(&mut comp.instance, F),
        }
    })
}

/// Derivatives of order 1 and 2 of continuous Real outputs (docs/coupling-ports.md).
#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *mut fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2GetRealOutputDerivatives";
    with(c, F, |comp| {
        match (slice(vr, nvr), slice(order, nvr), slice_mut(value, nvr)) {
            (Some(vr), Some(order), Some(value)) => {
                comp.instance.get_output_derivatives(vr, order, value)
            }
            _ => null_argument(&mut comp.instance, F),
        }
    })
}

/// Advances by one communication step (any length; events located inside).
#[no_mangle]
pub unsafe extern "C" fn fmi2DoStep(
    c: fmi2Component,
    currentCommunicationPoint: fmi2Real,
    communicationStepSize: fmi2Real,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
) -> fmi2Status {
    with(c, "fmi2DoStep", |comp| {
        comp.instance
            .do_step(currentCommunicationPoint, communicationStepSize)
    })
}

/// Nothing to cancel (steps are synchronous): always an error.
#[no_mangle]
pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    const F: &str = "fmi2CancelStep";
    with(c, F, |comp| {
        comp.instance.error(
            F,
            "fmi2DoStep never returns fmi2Pending, so there is nothing to cancel",
        )
    })
}

/// fmi2DoStepStatus: always fmi2OK.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Status,
) -> fmi2Status {
    const F: &str = "fmi2GetStatus";
    with(c, F, |comp| match (s, value.is_null()) {
        _ if comp.instance.check_call(F).is_err() => Status::Error,
        (0, false) => {
            *value = OK; // fmi2DoStepStatus: every step finishes synchronously
            Status::Ok
        }
        _ => comp
            .instance
            .error(F, format!("status kind {s} is not provided")),
    })
}

/// fmi2LastSuccessfulTime.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2GetRealStatus";
    with(c, F, |comp| match (s, value.is_null()) {
        _ if comp.instance.check_call(F).is_err() => Status::Error,
        (2, false) => {
            *value = comp.instance.last_successful_time();
            Status::Ok
        }
        _ => comp
            .instance
            .error(F, format!("status kind {s} is not provided")),
    })
}

/// No Integer status: always an error.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    _value: *mut fmi2Integer,
) -> fmi2Status {
    const F: &str = "fmi2GetIntegerStatus";
    with(c, F, |comp| {
        if let Err(status) = comp.instance.check_call(F) {
            return status;
        }
        comp.instance
            .error(F, format!("status kind {s} is not provided"))
    })
}

/// fmi2Terminated: always false.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    const F: &str = "fmi2GetBooleanStatus";
    with(c, F, |comp| match (s, value.is_null()) {
        _ if comp.instance.check_call(F).is_err() => Status::Error,
        (3, false) => {
            *value = 0; // fmi2Terminated: the FMU never asks to stop
            Status::Ok
        }
        _ => comp
            .instance
            .error(F, format!("status kind {s} is not provided")),
    })
}

/// No String status: always an error.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    _value: *mut fmi2String,
) -> fmi2Status {
    const F: &str = "fmi2GetStringStatus";
    with(c, F, |comp| {
        if let Err(status) = comp.instance.check_call(F) {
            return status;
        }
        comp.instance
            .error(F, format!("status kind {s} is not provided"))
    })
}
