//! The fmi3 functions this FMU provides, in the order of fmi3Functions.h.

use super::*;
use crate::fmi::instance::StepRequest;

/// "3.0".
#[no_mangle]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

/// Turns diagnostic messages on or off (errors are always logged); categories are ignored.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    instance: fmi3Instance,
    loggingOn: fmi3Boolean,
    nCategories: usize,
    categories: *const fmi3String,
) -> fmi3Status {
    fmi2SetDebugLogging(instance, loggingOn.into(), nCategories, categories)
}

/// Creates a Co-Simulation instance (the token must match); NULL on failure,
/// with a logged reason. `resourcePath` is the resources folder as a native
/// path. With `earlyReturnAllowed`, fmi3DoStep returns at the first
/// stick/slip switch; with `eventModeUsed`, it asks for Event Mode there.
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    resourcePath: fmi3String,
    _visible: fmi3Boolean,
    loggingOn: fmi3Boolean,
    eventModeUsed: fmi3Boolean,
    earlyReturnAllowed: fmi3Boolean,
    _requiredIntermediateVariables: *const fmi3ValueReference,
    _nRequiredIntermediateVariables: usize,
    instanceEnvironment: *mut c_void,
    logMessage: fmi3LogMessageCallback,
    _intermediateUpdate: *const c_void,
) -> fmi3Instance {
    let result = catch_quietly(|| {
        const F: &str = "fmi3InstantiateCoSimulation";
        let name = string_arg(instanceName).unwrap_or_default();
        let sink = Box::new(Fmi3Sink {
            logger: logMessage,
            env: instanceEnvironment,
        });
        // FMI 3.0 gives the resources folder as a native path.
        let dir = string_arg(resourcePath)
            .filter(|p| !p.is_empty())
            .map(std::path::PathBuf::from)
            .ok_or_else(|| format!("{F} was given no resourcePath"));
        let mut instance = Instance::with_resource_dir(&name, dir, sink, loggingOn);
        instance.use_fmi3(earlyReturnAllowed, eventModeUsed);
        if instanceName.is_null() {
            instance.error(F, "instanceName must not be NULL");
            return std::ptr::null_mut();
        }
        if !token_matches(&mut instance, F, instantiationToken) {
            return std::ptr::null_mut();
        }
        Box::into_raw(Box::new(Component {
            instance,
            strings: vec![],
        })) as fmi3Instance
    });
    result.unwrap_or(std::ptr::null_mut())
}

/// Frees an instance (NULL is ignored).
#[no_mangle]
pub unsafe extern "C" fn fmi3FreeInstance(instance: fmi3Instance) {
    fmi2FreeInstance(instance)
}

/// Sets the start time (a record starts there) and the optional stop time,
/// and enters Initialization Mode; parameters stay settable.
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    instance: fmi3Instance,
    _toleranceDefined: fmi3Boolean,
    _tolerance: fmi3Float64,
    startTime: fmi3Float64,
    stopTimeDefined: fmi3Boolean,
    stopTime: fmi3Float64,
) -> fmi3Status {
    with(instance, "fmi3EnterInitializationMode", |comp| {
        let i = &mut comp.instance;
        match i.setup_experiment(startTime, stopTimeDefined.then_some(stopTime)) {
            Status::Ok => i.enter_initialization_mode(),
            status => status,
        }
    })
}

/// Checks the parameters, reads `recordFile`, builds the simulator; then
/// Event Mode if the importer uses it, else Step Mode.
#[no_mangle]
pub unsafe extern "C" fn fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status {
    with(instance, "fmi3ExitInitializationMode", |comp| {
        comp.instance.exit_initialization_mode_fmi3()
    })
}

/// From Step Mode into Event Mode (with `eventModeUsed`).
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterEventMode(instance: fmi3Instance) -> fmi3Status {
    with(instance, "fmi3EnterEventMode", |comp| {
        comp.instance.enter_event_mode()
    })
}

/// Ends the simulation; outputs stay readable.
#[no_mangle]
pub unsafe extern "C" fn fmi3Terminate(instance: fmi3Instance) -> fmi3Status {
    fmi2Terminate(instance)
}

/// Back to the state after instantiation, with default values.
#[no_mangle]
pub unsafe extern "C" fn fmi3Reset(instance: fmi3Instance) -> fmi3Status {
    fmi2Reset(instance)
}

/// Reads Float64 variables; value reference 0 is `time`.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetFloat64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    let (vr, nvr) = (valueReferences, nValueReferences);
    getter(
        instance,
        "fmi3GetFloat64",
        vr,
        nvr,
        values,
        nValues,
        |i, vrs, out| {
            // The state check of the getter, for `time` too.
            match i.get_real(&[], &mut []) {
                Status::Ok => {}
                s => return s,
            }
            for (&vr, slot) in vrs.iter().zip(out.iter_mut()) {
                if vr == TIME_VR {
                    *slot = i.time_now();
                    continue;
                }
                match i.get_real(&[vr], std::slice::from_mut(slot)) {
                    Status::Ok => {}
                    s => return s,
                }
            }
            Status::Ok
        },
    )
}

/// The value reference of `time`, the independent variable (FMI 3.0 only).
pub const TIME_VR: u32 = 0;

/// Every variable is a scalar: one value per value reference.
fn scalars_only(i: &mut Instance, func: &str, nvr: usize, nvalues: usize) -> Result<(), Status> {
    if nvr == nvalues {
        Ok(())
    } else {
        Err(i.error(
            func,
            format!("nValues = {nvalues} with {nvr} value references: every variable of this FMU is a scalar"),
        ))
    }
}

/// A getter's arguments, checked (pointers, one value per reference), to `f`.
unsafe fn getter<T>(
    instance: fmi3Instance,
    func: &str,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut T,
    nvalues: usize,
    f: impl FnOnce(&mut Instance, &[u32], &mut [T]) -> Status,
) -> fmi3Status {
    with(instance, func, |comp| {
        let i = &mut comp.instance;
        match (slice(vr, nvr), slice_mut(values, nvalues)) {
            (Some(vrs), Some(out)) => match scalars_only(i, func, vrs.len(), out.len()) {
                Ok(()) => f(i, vrs, out),
                Err(s) => s,
            },
            _ => null_argument(i, func),
        }
    })
}

/// A setter's arguments, checked (pointers, one value per reference), to `f`.
unsafe fn setter<T>(
    instance: fmi3Instance,
    func: &str,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const T,
    nvalues: usize,
    f: impl FnOnce(&mut Instance, &[u32], &[T]) -> Status,
) -> fmi3Status {
    with(instance, func, |comp| {
        let i = &mut comp.instance;
        match (slice(vr, nvr), slice(values, nvalues)) {
            (Some(vrs), Some(x)) => match scalars_only(i, func, vrs.len(), x.len()) {
                Ok(()) => f(i, vrs, x),
                Err(s) => s,
            },
            _ => null_argument(i, func),
        }
    })
}

/// Reads Int32 variables (`nBlocks`, `solver`, `nEvents`, `nAmbiguous`).
#[no_mangle]
pub unsafe extern "C" fn fmi3GetInt32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Int32,
    nValues: usize,
) -> fmi3Status {
    let (vr, nvr) = (valueReferences, nValueReferences);
    getter(
        instance,
        "fmi3GetInt32",
        vr,
        nvr,
        values,
        nValues,
        |i, vrs, out| i.get_integer(vrs, out),
    )
}

/// Reads Boolean variables (`stuck[j]`).
#[no_mangle]
pub unsafe extern "C" fn fmi3GetBoolean(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Boolean,
    nValues: usize,
) -> fmi3Status {
    let (vr, nvr) = (valueReferences, nValueReferences);
    getter(
        instance,
        "fmi3GetBoolean",
        vr,
        nvr,
        values,
        nValues,
        |i, vrs, out| {
            let mut ints = vec![0; vrs.len()];
            let status = i.get_boolean(vrs, &mut ints);
            for (slot, x) in out.iter_mut().zip(ints) {
                *slot = x != 0;
            }
            status
        },
    )
}

/// Reads String variables (`recordFile`); valid until the next call on the instance.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetString(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3String,
    nValues: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetString";
    with(instance, F, |comp| {
        match slice(valueReferences, nValueReferences) {
            Some(vrs) => match scalars_only(&mut comp.instance, F, vrs.len(), nValues) {
                Ok(()) => get_strings(comp, F, vrs, values),
                Err(s) => s,
            },
            None => null_argument(&mut comp.instance, F),
        }
    })
}

/// Sets Float64 parameters (before initialization ends) and inputs (also in
/// Event Mode); out-of-range values are refused by name.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetFloat64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    let (vr, nvr) = (valueReferences, nValueReferences);
    setter(
        instance,
        "fmi3SetFloat64",
        vr,
        nvr,
        values,
        nValues,
        |i, vrs, x| i.set_real(vrs, x),
    )
}

/// Sets `nBlocks` (0..8) or `solver` (1, 2 or 3).
#[no_mangle]
pub unsafe extern "C" fn fmi3SetInt32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Int32,
    nValues: usize,
) -> fmi3Status {
    let (vr, nvr) = (valueReferences, nValueReferences);
    setter(
        instance,
        "fmi3SetInt32",
        vr,
        nvr,
        values,
        nValues,
        |i, vrs, x| i.set_integer(vrs, x),
    )
}

/// No settable Boolean: always an error (unless no value reference is given).
#[no_mangle]
pub unsafe extern "C" fn fmi3SetBoolean(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Boolean,
    nValues: usize,
) -> fmi3Status {
    let (vr, nvr) = (valueReferences, nValueReferences);
    setter(
        instance,
        "fmi3SetBoolean",
        vr,
        nvr,
        values,
        nValues,
        |i, vrs, x| i.set_boolean(vrs, &x.iter().map(|&b| i32::from(b)).collect::<Vec<_>>()),
    )
}

/// Sets `recordFile`.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetString(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3String,
    nValues: usize,
) -> fmi3Status {
    const F: &str = "fmi3SetString";
    with(instance, F, |comp| {
        match slice(valueReferences, nValueReferences) {
            Some(vrs) => match scalars_only(&mut comp.instance, F, vrs.len(), nValues) {
                Ok(()) => set_strings(comp, F, vrs, values),
                Err(s) => s,
            },
            None => null_argument(&mut comp.instance, F),
        }
    })
}

/// Saves the instance's state (a new one, or into the given one).
#[no_mangle]
pub unsafe extern "C" fn fmi3GetFMUState(
    instance: fmi3Instance,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    fmi2GetFMUstate(instance, FMUState)
}

/// Restores a saved state; stepping on gives bit-identical outputs.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetFMUState(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
) -> fmi3Status {
    fmi2SetFMUstate(instance, FMUState)
}

/// Frees a saved state and sets the pointer to NULL.
#[no_mangle]
pub unsafe extern "C" fn fmi3FreeFMUState(
    instance: fmi3Instance,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    fmi2FreeFMUstate(instance, FMUState)
}

/// Size in bytes of a saved state's serialized form.
#[no_mangle]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
    size: *mut usize,
) -> fmi3Status {
    fmi2SerializedFMUstateSize(instance, FMUState, size)
}

/// Writes a saved state in the explicit, versioned byte format (the FMI 2.0 one).
#[no_mangle]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
    serializedState: *mut fmi3Byte,
    size: usize,
) -> fmi3Status {
    fmi2SerializeFMUstate(instance, FMUState, serializedState as *mut fmi2Byte, size)
}

/// Reads a saved state from its byte format.
#[no_mangle]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    instance: fmi3Instance,
    serializedState: *const fmi3Byte,
    size: usize,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    fmi2DeSerializeFMUstate(instance, serializedState as *const fmi2Byte, size, FMUState)
}

/// Directional derivatives of Float64 outputs with respect to inputs at the
/// current communication point (StackOnFloor; docs/coupling-ports.md):
/// `sensitivity = J seed`, `nSeed = nKnowns`, `nSensitivity = nUnknowns`.
/// StackedLiveLoad does not provide them (an error).
#[no_mangle]
pub unsafe extern "C" fn fmi3GetDirectionalDerivative(
    instance: fmi3Instance,
    unknowns: *const fmi3ValueReference,
    nUnknowns: usize,
    knowns: *const fmi3ValueReference,
    nKnowns: usize,
    seed: *const fmi3Float64,
    nSeed: usize,
    sensitivity: *mut fmi3Float64,
    nSensitivity: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetDirectionalDerivative";
    with(instance, F, |comp| {
        match (
            slice(unknowns, nUnknowns),
            slice(knowns, nKnowns),
            slice(seed, nSeed),
            slice_mut(sensitivity, nSensitivity),
        ) {
            (Some(unknowns), Some(knowns), Some(seed), Some(out)) => comp
                .instance
                .directional_derivative(unknowns, knowns, seed, out),
            _ => null_argument(&mut comp.instance, F),
        }
    })
}

/// Resolves the event in Event Mode, with the inputs set there in force;
/// nothing further is needed or scheduled (every flag false).
#[no_mangle]
pub unsafe extern "C" fn fmi3UpdateDiscreteStates(
    instance: fmi3Instance,
    discreteStatesNeedUpdate: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
    nominalsOfContinuousStatesChanged: *mut fmi3Boolean,
    valuesOfContinuousStatesChanged: *mut fmi3Boolean,
    nextEventTimeDefined: *mut fmi3Boolean,
    nextEventTime: *mut fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3UpdateDiscreteStates";
    with(instance, F, |comp| {
        let flags = [
            discreteStatesNeedUpdate,
            terminateSimulation,
            nominalsOfContinuousStatesChanged,
            valuesOfContinuousStatesChanged,
            nextEventTimeDefined,
        ];
        if flags.iter().any(|p| p.is_null()) || nextEventTime.is_null() {
            return null_argument(&mut comp.instance, F);
        }
        let status = comp.instance.update_discrete_states();
        if status == Status::Ok {
            for p in flags {
                *p = false;
            }
            *nextEventTime = 0.0;
        }
        status
    })
}

/// From Event Mode into Step Mode.
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterStepMode(instance: fmi3Instance) -> fmi3Status {
    with(instance, "fmi3EnterStepMode", |comp| {
        comp.instance.enter_step_mode()
    })
}

/// Derivatives of order 1 and 2 of continuous Float64 outputs (docs/coupling-ports.md).
#[no_mangle]
pub unsafe extern "C" fn fmi3GetOutputDerivatives(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    orders: *const fmi3Int32,
    values: *mut fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    const F: &str = "fmi3GetOutputDerivatives";
    with(instance, F, |comp| {
        let i = &mut comp.instance;
        match (
            slice(valueReferences, nValueReferences),
            slice(orders, nValueReferences),
            slice_mut(values, nValues),
        ) {
            (Some(vrs), Some(orders), Some(out)) => {
                match scalars_only(i, F, vrs.len(), out.len()) {
                    Ok(()) => i.get_output_derivatives(vrs, orders, out),
                    Err(s) => s,
                }
            }
            _ => null_argument(i, F),
        }
    })
}

/// Advances by one communication step; with `earlyReturnAllowed` it returns
/// at the first stick/slip switch inside (`earlyReturn`, `lastSuccessfulTime`
/// the switch time), with `eventModeUsed` asking for Event Mode there.
#[no_mangle]
pub unsafe extern "C" fn fmi3DoStep(
    instance: fmi3Instance,
    currentCommunicationPoint: fmi3Float64,
    communicationStepSize: fmi3Float64,
    _noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
    eventHandlingNeeded: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
    earlyReturn: *mut fmi3Boolean,
    lastSuccessfulTime: *mut fmi3Float64,
) -> fmi3Status {
    const F: &str = "fmi3DoStep";
    with(instance, F, |comp| {
        let flags = [eventHandlingNeeded, terminateSimulation, earlyReturn];
        if flags.iter().any(|p| p.is_null()) || lastSuccessfulTime.is_null() {
            return null_argument(&mut comp.instance, F);
        }
        let outcome = comp.instance.do_step_fmi3(StepRequest {
            t: currentCommunicationPoint,
            h: communicationStepSize,
        });
        *eventHandlingNeeded = outcome.event_handling_needed;
        *terminateSimulation = false;
        *earlyReturn = outcome.early_return;
        *lastSuccessfulTime = outcome.last_successful_time;
        outcome.status
    })
}
