//! Saving, restoring and serializing the FMU state (and the directional
//! derivative, which is not provided).

use super::*;

/// Saves the instance's state (a new one, or into the given one).
#[no_mangle]
pub unsafe extern "C" fn fmi2GetFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    const F: &str = "fmi2GetFMUstate";
    with(c, F, |comp| {
        if FMUstate.is_null() {
            return null_argument(&mut comp.instance, F);
        }
        match comp.instance.save() {
            Ok(state) => {
                let old = *FMUstate as *mut SavedState;
                if old.is_null() {
                    *FMUstate = Box::into_raw(Box::new(state)) as fmi2FMUstate;
                } else {
                    *old = state; // reuse the importer's earlier state
                }
                Status::Ok
            }
            Err(status) => status,
        }
    })
}

/// Restores a saved state; stepping on gives bit-identical outputs.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetFMUstate(c: fmi2Component, FMUstate: fmi2FMUstate) -> fmi2Status {
    const F: &str = "fmi2SetFMUstate";
    with(c, F, |comp| {
        match (FMUstate as *const SavedState).as_ref() {
            Some(state) => comp.instance.restore(state),
            None => null_argument(&mut comp.instance, F),
        }
    })
}

/// Frees a saved state and sets the pointer to NULL.
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    with(c, "fmi2FreeFMUstate", |_| {
        if !FMUstate.is_null() && !(*FMUstate).is_null() {
            drop(Box::from_raw(*FMUstate as *mut SavedState));
            *FMUstate = std::ptr::null_mut();
        }
        Status::Ok
    })
}

/// Size in bytes of a saved state's serialized form.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    const F: &str = "fmi2SerializedFMUstateSize";
    with(c, F, |comp| {
        match ((FMUstate as *const SavedState).as_ref(), size.is_null()) {
            (Some(state), false) => {
                *size = Instance::serialize(state).len();
                Status::Ok
            }
            _ => null_argument(&mut comp.instance, F),
        }
    })
}

/// Writes a saved state in the explicit, versioned byte format.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    serializedState: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    const F: &str = "fmi2SerializeFMUstate";
    with(c, F, |comp| {
        match (
            (FMUstate as *const SavedState).as_ref(),
            slice_mut(serializedState as *mut u8, size),
        ) {
            (Some(state), Some(out)) => {
                let bytes = Instance::serialize(state);
                if bytes.len() != size {
                    return comp.instance.error(
                        F,
                        format!("size = {size}, but the state takes {} bytes", bytes.len()),
                    );
                }
                out.copy_from_slice(&bytes);
                Status::Ok
            }
            _ => null_argument(&mut comp.instance, F),
        }
    })
}

/// Reads a saved state from its byte format.
#[no_mangle]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    serializedState: *const fmi2Byte,
    size: usize,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    const F: &str = "fmi2DeSerializeFMUstate";
    with(c, F, |comp| {
        match (
            slice(serializedState as *const u8, size),
            FMUstate.is_null(),
        ) {
            (Some(bytes), false) => match Instance::deserialize(bytes) {
                Ok(state) if state.model() != comp.instance.model() => comp.instance.error(
                    F,
                    format!(
                        "the state was saved by a {} instance; this one is a {}",
                        state.model().identifier(),
                        comp.instance.model().identifier()
                    ),
                ),
                Ok(state) => {
                    let old = *FMUstate as *mut SavedState;
                    if old.is_null() {
                        *FMUstate = Box::into_raw(Box::new(state)) as fmi2FMUstate;
                    } else {
                        *old = state;
                    }
                    Status::Ok
                }
                Err(e) => comp.instance.error(F, e),
            },
            _ => null_argument(&mut comp.instance, F),
        }
    })
}

/// Directional derivatives of Real outputs with respect to inputs at the
/// current communication point (StackOnFloor; docs/coupling-ports.md):
/// `dvUnknown = J dvKnown`. StackedLiveLoad does not provide them (an error).
#[no_mangle]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    vUnknown_ref: *const fmi2ValueReference,
    nUnknown: usize,
    vKnown_ref: *const fmi2ValueReference,
    nKnown: usize,
    dvKnown: *const fmi2Real,
    dvUnknown: *mut fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2GetDirectionalDerivative";
    with(c, F, |comp| {
        match (
            slice(vUnknown_ref, nUnknown),
            slice(vKnown_ref, nKnown),
            slice(dvKnown, nKnown),
            slice_mut(dvUnknown, nUnknown),
        ) {
            (Some(unknowns), Some(knowns), Some(seed), Some(out)) => comp
                .instance
                .directional_derivative(unknowns, knowns, seed, out),
            _ => null_argument(&mut comp.instance, F),
        }
    })
}
