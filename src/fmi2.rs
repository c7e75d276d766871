//! The FMI 2.0 Co-Simulation C API. Every export is a thin wrapper: it
//! checks pointers, converts arguments, calls the safe [`Instance`] inside a
//! panic boundary (a panic becomes `fmi2Fatal` and a log message, never an
//! unwind into the importer) and returns the status. No global state.
#![allow(non_snake_case, non_camel_case_types, clippy::missing_safety_doc)]

use crate::instance::{Instance, LogSink, NullSink, SavedState, Status};
use std::ffi::{c_char, c_int, c_uint, c_void, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// An instance, as the importer holds it.
pub type fmi2Component = *mut c_void;
/// The importer's pointer, passed back to its callbacks.
pub type fmi2ComponentEnvironment = *mut c_void;
/// A saved state.
pub type fmi2FMUstate = *mut c_void;
/// A variable's value reference.
pub type fmi2ValueReference = c_uint;
/// FMI Real.
pub type fmi2Real = f64;
/// FMI Integer.
pub type fmi2Integer = c_int;
/// FMI Boolean (0 false, otherwise true).
pub type fmi2Boolean = c_int;
/// FMI String (NUL-terminated UTF-8).
pub type fmi2String = *const c_char;
/// One byte of a serialized state.
pub type fmi2Byte = c_char;
/// fmi2OK = 0, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending.
pub type fmi2Status = c_int;
/// fmi2ModelExchange = 0, fmi2CoSimulation = 1.
pub type fmi2Type = c_int;
/// fmi2DoStepStatus = 0, fmi2PendingStatus, fmi2LastSuccessfulTime, fmi2Terminated.
pub type fmi2StatusKind = c_int;

/// The importer's logger (variadic, printf-like).
pub type fmi2CallbackLogger = Option<
    unsafe extern "C" fn(
        fmi2ComponentEnvironment,
        fmi2String,
        fmi2Status,
        fmi2String,
        fmi2String,
        ...
    ),
>;
/// The importer's allocator (unused: canNotUseMemoryManagementFunctions).
pub type fmi2CallbackAllocateMemory = Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>;
/// The importer's deallocator (unused).
pub type fmi2CallbackFreeMemory = Option<unsafe extern "C" fn(*mut c_void)>;
/// Asynchronous step callback (unused).
pub type fmi2StepFinished = Option<unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2Status)>;

/// The importer's callbacks (FMI 2.0 `fmi2CallbackFunctions`).
#[repr(C)]
pub struct fmi2CallbackFunctions {
    /// Logger (may be NULL).
    pub logger: fmi2CallbackLogger,
    /// Allocator (unused).
    pub allocateMemory: fmi2CallbackAllocateMemory,
    /// Deallocator (unused).
    pub freeMemory: fmi2CallbackFreeMemory,
    /// Step callback (unused).
    pub stepFinished: fmi2StepFinished,
    /// Passed back to the logger.
    pub componentEnvironment: fmi2ComponentEnvironment,
}

/// The GUID of this model description (change it when the interface changes).
pub const GUID: &str = "{6b1f0c9e-3a57-4d2b-9c84-57acced11fe2}";

const OK: fmi2Status = Status::Ok as fmi2Status;
const ERROR: fmi2Status = Status::Error as fmi2Status;

/// Passes messages to the importer's logger, always as the argument of a
/// "%s" format so that a '%' in a message is never interpreted.
struct CallbackSink {
    logger: fmi2CallbackLogger,
    env: fmi2ComponentEnvironment,
    name: CString,
}

fn c_text(s: &str) -> CString {
    CString::new(s.replace('\0', " ")).expect("NULs removed")
}

impl LogSink for CallbackSink {
    fn log(&self, status: Status, category: &str, message: &str) {
        if let Some(logger) = self.logger {
            let (category, message) = (c_text(category), c_text(message));
            unsafe {
                logger(
                    self.env,
                    self.name.as_ptr(),
                    status as fmi2Status,
                    category.as_ptr(),
                    c"%s".as_ptr(),
                    message.as_ptr(),
                )
            };
        }
    }
}

/// What a `fmi2Component` points to.
struct Component {
    instance: Instance,
    /// Backing store of the strings returned by fmi2GetString.
    strings: Vec<CString>,
}

fn panic_text(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}

/// Runs `f` on the component behind `c` inside a panic boundary.
unsafe fn with(
    c: fmi2Component,
    func: &str,
    f: impl FnOnce(&mut Component) -> Status,
) -> fmi2Status {
    if c.is_null() {
        return ERROR;
    }
    let comp = &mut *(c as *mut Component);
    match catch_unwind(AssertUnwindSafe(|| f(&mut *comp))) {
        Ok(status) => status as fmi2Status,
        Err(p) => comp
            .instance
            .fatal(func, &format!("internal error: {}", panic_text(&*p)))
            as fmi2Status,
    }
}

/// Builds a slice from a C array, or None if the pointer is null with n > 0.
unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        Some(&[])
    } else if p.is_null() {
        None
    } else {
        Some(std::slice::from_raw_parts(p, n))
    }
}

unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        Some(&mut [])
    } else if p.is_null() {
        None
    } else {
        Some(std::slice::from_raw_parts_mut(p, n))
    }
}

fn null_argument(inst: &mut Instance, func: &str) -> Status {
    inst.error(func, "a required pointer argument is NULL")
}

unsafe fn string_arg(s: fmi2String) -> Option<String> {
    (!s.is_null()).then(|| CStr::from_ptr(s).to_string_lossy().into_owned())
}

// ---------------------------------------------------------------- common

/// "default": the standard FMI 2.0 types.
#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

/// "2.0".
#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// Turns diagnostic messages on or off (errors are always logged); categories are ignored.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    loggingOn: fmi2Boolean,
    _nCategories: usize,
    _categories: *const fmi2String,
) -> fmi2Status {
    with(c, "fmi2SetDebugLogging", |comp| {
        comp.instance.set_debug_logging(loggingOn != 0)
    })
}

/// Creates an instance (Co-Simulation only; the GUID must match); NULL on failure, with a logged reason.
#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    instanceName: fmi2String,
    fmuType: fmi2Type,
    fmuGUID: fmi2String,
    fmuResourceLocation: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    loggingOn: fmi2Boolean,
) -> fmi2Component {
    let result = catch_unwind(|| {
        let name = string_arg(instanceName).unwrap_or_default();
        let sink: Box<dyn LogSink> = match functions.as_ref() {
            Some(f) => Box::new(CallbackSink {
                logger: f.logger,
                env: f.componentEnvironment,
                name: c_text(&name),
            }),
            None => Box::new(NullSink),
        };
        let resources = string_arg(fmuResourceLocation);
        let mut instance = Instance::new(&name, resources.as_deref(), sink, loggingOn != 0);
        const F: &str = "fmi2Instantiate";
        if instanceName.is_null() || functions.is_null() {
            instance.error(F, "instanceName and functions must not be NULL");
            return std::ptr::null_mut();
        }
        if fmuType != 1 {
            instance.error(
                F,
                format!("fmuType = {fmuType}: this FMU supports Co-Simulation (1) only"),
            );
            return std::ptr::null_mut();
        }
        let guid = string_arg(fmuGUID).unwrap_or_default();
        if guid != GUID {
            instance.error(
                F,
                format!("fmuGUID {guid} does not match this FMU's {GUID}"),
            );
            return std::ptr::null_mut();
        }
        Box::into_raw(Box::new(Component {
            instance,
            strings: vec![],
        })) as fmi2Component
    });
    result.unwrap_or(std::ptr::null_mut())
}

/// Frees an instance (NULL is ignored).
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    if !c.is_null() {
        let _ = catch_unwind(|| drop(Box::from_raw(c as *mut Component)));
    }
}

/// Sets the start time (a record starts there) and the optional stop time.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    _toleranceDefined: fmi2Boolean,
    _tolerance: fmi2Real,
    startTime: fmi2Real,
    stopTimeDefined: fmi2Boolean,
    stopTime: fmi2Real,
) -> fmi2Status {
    with(c, "fmi2SetupExperiment", |comp| {
        comp.instance
            .setup_experiment(startTime, (stopTimeDefined != 0).then_some(stopTime))
    })
}

/// Enters initialization mode; parameters stay settable.
#[no_mangle]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    with(c, "fmi2EnterInitializationMode", |comp| {
        comp.instance.enter_initialization_mode()
    })
}

/// Checks the parameters, reads `recordFile`, builds the simulator.
#[no_mangle]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    with(c, "fmi2ExitInitializationMode", |comp| {
        comp.instance.exit_initialization_mode()
    })
}

/// Ends the simulation; outputs stay readable.
#[no_mangle]
pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    with(c, "fmi2Terminate", |comp| comp.instance.terminate())
}

/// Back to the state after instantiation, with default values.
#[no_mangle]
pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    with(c, "fmi2Reset", |comp| comp.instance.reset())
}

// ---------------------------------------------------------------- get/set

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
    with(c, F, |comp| match (slice(vr, nvr), slice_mut(value, nvr)) {
        (Some(vr), Some(value)) => match comp.instance.get_string(vr) {
            Ok(strings) => {
                // Valid until the next call on this instance, as FMI 2.0 allows.
                comp.strings = strings.iter().map(|s| c_text(s)).collect();
                for (slot, s) in value.iter_mut().zip(&comp.strings) {
                    *slot = s.as_ptr();
                }
                Status::Ok
            }
            Err(status) => status,
        },
        _ => null_argument(&mut comp.instance, F),
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
    with(c, F, |comp| match (slice(vr, nvr), slice(value, nvr)) {
        (Some(vr), Some(value)) => {
            let strings: Option<Vec<String>> = value.iter().map(|&s| string_arg(s)).collect();
            match strings {
                Some(strings) => comp.instance.set_string(vr, &strings),
                None => null_argument(&mut comp.instance, F),
            }
        }
        _ => null_argument(&mut comp.instance, F),
    })
}

// ---------------------------------------------------------------- FMU state

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

/// Not provided: always an error.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    _vUnknown_ref: *const fmi2ValueReference,
    _nUnknown: usize,
    _vKnown_ref: *const fmi2ValueReference,
    _nKnown: usize,
    _dvKnown: *const fmi2Real,
    _dvUnknown: *mut fmi2Real,
) -> fmi2Status {
    const F: &str = "fmi2GetDirectionalDerivative";
    with(c, F, |comp| {
        comp.instance
            .error(F, "directional derivatives are not provided")
    })
}

// ---------------------------------------------------------------- co-simulation

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
        comp.instance
            .error(F, format!("status kind {s} is not provided"))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::instance::Phase;

    #[test]
    fn a_panic_inside_a_call_becomes_fmi2_fatal_not_an_unwind() {
        let callbacks = fmi2CallbackFunctions {
            logger: None,
            allocateMemory: None,
            freeMemory: None,
            stepFinished: None,
            componentEnvironment: std::ptr::null_mut(),
        };
        let guid = CString::new(GUID).unwrap();
        unsafe {
            let c = fmi2Instantiate(
                c"t".as_ptr(),
                1,
                guid.as_ptr(),
                std::ptr::null(),
                &callbacks,
                0,
                0,
            );
            assert!(!c.is_null());
            // The same boundary every export goes through, around a failing body.
            let status = with(c, "fmi2Test", |_| panic!("deliberate"));
            assert_eq!(status, Status::Fatal as fmi2Status);
            assert_eq!((*(c as *mut Component)).instance.phase(), Phase::Error);
            // The instance survives and still answers (with an error: wrong state).
            assert_eq!(fmi2DoStep(c, 0.0, 0.1, 1), ERROR);
            fmi2FreeInstance(c);
            // NULL components are refused, never dereferenced.
            assert_eq!(fmi2DoStep(std::ptr::null_mut(), 0.0, 0.1, 1), ERROR);
            assert!(fmi2Instantiate(
                c"t".as_ptr(),
                0,
                guid.as_ptr(),
                std::ptr::null(),
                &callbacks,
                0,
                0
            )
            .is_null());
        }
    }
}
