//! The FMI 2.0 Co-Simulation C API: its C types, and the panic boundary and
//! argument checks every export goes through. Every export is a thin wrapper: it
//! checks pointers, converts arguments, calls the safe [`Instance`] inside a
//! panic boundary (a panic becomes `fmi2Fatal` and a log message, never an
//! unwind into the importer) and returns the status. No global state.
#![allow(non_snake_case, non_camel_case_types, clippy::missing_safety_doc)]

use crate::fmi::instance::{Instance, LogSink, NullSink, SavedState, Status};
use crate::fmi::variables::Model;
use std::cell::{Cell, RefCell};
use std::ffi::{c_char, c_int, c_uint, c_void, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Once;

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

/// The GUID of the storey's (StackedLiveLoad's) model description; each
/// model has its own ([`Model::guid`]).
pub const GUID: &str = "{6b1f0c9e-3a57-4d2b-9c84-57acced11fe2}";
/// The GUID of StackOnFloor's model description (change it when its interface changes).
pub const FLOOR_GUID: &str = "{2f8d4b1a-7c3e-4e59-a1d6-0b9e5f3c8a47}";

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

thread_local! {
    /// Inside [`catch_quietly`] on this thread.
    static QUIET: Cell<bool> = const { Cell::new(false) };
    /// The message of the last panic caught quietly on this thread.
    static CAUGHT: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Runs `f`, turning a panic into its message (with where it happened)
/// without printing anything: the default panic hook writes to the host's
/// stderr, so a hook installed once passes a panic inside this boundary to
/// the caller (for the logger) and any other to the previous hook.
pub fn catch_quietly<R>(f: impl FnOnce() -> R) -> Result<R, String> {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if QUIET.with(Cell::get) {
                let place = info
                    .location()
                    .map_or(String::new(), |l| format!(" at {}:{}", l.file(), l.line()));
                let text = format!("{}{place}", panic_text(info.payload()));
                CAUGHT.with(|c| *c.borrow_mut() = Some(text));
            } else {
                previous(info)
            }
        }));
    });
    let outer = QUIET.with(|q| q.replace(true));
    let result = catch_unwind(AssertUnwindSafe(f));
    QUIET.with(|q| q.set(outer));
    result.map_err(|p| {
        CAUGHT
            .with(|c| c.borrow_mut().take())
            .unwrap_or_else(|| panic_text(&*p))
    })
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
    match catch_quietly(|| f(&mut *comp)) {
        Ok(status) => status as fmi2Status,
        Err(text) => catch_quietly(|| {
            comp.instance
                .fatal(func, &format!("internal error: {text}"))
        })
        .unwrap_or(Status::Fatal) as fmi2Status,
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

/// Picks the model of the instance from the importer's GUID (FMI 2.0) or
/// instantiation token (FMI 3.0): each model of the binary has its own. An
/// unknown one is logged and refused (false).
unsafe fn token_matches(instance: &mut Instance, func: &str, token: *const c_char) -> bool {
    let token = string_arg(token).unwrap_or_default();
    match Model::from_token(&token) {
        Some(model) => {
            instance.use_model(model);
            true
        }
        None => {
            let known: Vec<String> = Model::ALL
                .iter()
                .map(|m| format!("{} {}", m.identifier(), m.guid()))
                .collect();
            instance.error(
                func,
                format!(
                    "the GUID / instantiation token {} does not match any of this binary's models ({}): \
                     use the one in the FMU's modelDescription.xml",
                    crate::limits::quote(&token),
                    known.join(", ")
                ),
            );
            false
        }
    }
}

/// fmi2GetString and fmi3GetString: the strings stay valid until the next
/// call on the instance, as FMI allows.
unsafe fn get_strings(
    comp: &mut Component,
    func: &str,
    vr: &[u32],
    value: *mut *const c_char,
) -> Status {
    let Some(value) = slice_mut(value, vr.len()) else {
        return null_argument(&mut comp.instance, func);
    };
    match comp.instance.get_string(vr) {
        Ok(strings) => {
            comp.strings = strings.iter().map(|s| c_text(s)).collect();
            for (slot, s) in value.iter_mut().zip(&comp.strings) {
                *slot = s.as_ptr();
            }
            Status::Ok
        }
        Err(status) => status,
    }
}

/// fmi2SetString and fmi3SetString.
unsafe fn set_strings(
    comp: &mut Component,
    func: &str,
    vr: &[u32],
    value: *const *const c_char,
) -> Status {
    let strings: Option<Vec<String>> =
        slice(value, vr.len()).and_then(|v| v.iter().map(|&s| string_arg(s)).collect());
    match strings {
        Some(strings) => comp.instance.set_string(vr, &strings),
        None => null_argument(&mut comp.instance, func),
    }
}

// The FMI 2.0 exports in four files, declared in the standard's order (the
// header keeps it), and the Model Exchange ones, which are not provided.
mod lifecycle;

mod values;

mod fmu_state;

mod co_simulation;

mod model_exchange;

pub mod fmi3;

pub use co_simulation::*;
pub use fmu_state::*;
pub use lifecycle::*;
pub use model_exchange::*;
pub use values::*;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fmi::instance::Phase;

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
