//! Reading and writing variables by value reference.

use super::*;

/// Reads Real variables (parameters, inputs, outputs).
#[no_mangle]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2GetReal";
    with(c, F, |comp| match (slice(vr, nvr), slice_mut(value, nvr)) {
        (Some(vr), Some(value)) => comp.instance.get_real(vr, value),
        _ => null_argument(&mut comp.instance, F),
    })
}

/// Reads Integer variables (`nBlocks`, `solver`, `nEvents`).
#[no_mangle]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    const F: &str = "fmi2GetInteger";
    with(c, F, |comp| match (slice(vr, nvr), slice_mut(value, nvr)) {
        (Some(vr), Some(value)) => comp.instance.get_integer(vr, value),
        _ => null_argument(&mut comp.instance, F),
    })
}

/// Reads Boolean variables (`stuck[j]`).
#[no_mangle]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    const F: &str = "fmi2GetBoolean";
    with(c, F, |comp| match (slice(vr, nvr), slice_mut(value, nvr)) {
        (Some(vr), Some(value)) => comp.instance.get_boolean(vr, value),
        _ => null_argument(&mut comp.instance, F),
    })
}

/// Sets Real parameters (before initialization ends) and inputs; out-of-range values are refused by name.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2SetReal";
    with(c, F, |comp| match (slice(vr, nvr), slice(value, nvr)) {
        (Some(vr), Some(value)) => comp.instance.set_real(vr, value),
        _ => null_argument(&mut comp.instance, F),
    })
}

/// Sets `nBlocks` (0..8) or `solver` (1 or 2).
#[no_mangle]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    const F: &str = "fmi2SetInteger";
    with(c, F, |comp| match (slice(vr, nvr), slice(value, nvr)) {
        (Some(vr), Some(value)) => comp.instance.set_integer(vr, value),
        _ => null_argument(&mut comp.instance, F),
    })
}

/// No settable Boolean: always an error.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    const F: &str = "fmi2SetBoolean";
    with(c, F, |comp| match (slice(vr, nvr), slice(value, nvr)) {
        (Some(vr), Some(value)) => comp.instance.set_boolean(vr, value),
        _ => null_argument(&mut comp.instance, F),
    })
}

/// Reads String variables (`recordFile`); valid until the next call on the instance.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    const F: &str = "fmi2GetString";
    with(c, F, |comp| match slice(vr, nvr) {
        Some(vr) => get_strings(comp, F, vr, value),
        None => null_argument(&mut comp.instance, F),
    })
}

/// Sets `recordFile`.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    const F: &str = "fmi2SetString";
    with(c, F, |comp| match slice(vr, nvr) {
        Some(vr) => set_strings(comp, F, vr, value),
        None => null_argument(&mut comp.instance, F),
    })
}
