//! The FMI 3.0 Co-Simulation C API over the same instance layer as FMI 2.0:
//! its C types, its logger, and the exports (`provided`: instances, modes,
//! values, saved states, stepping; `not_provided`: every other function of
//! fmi3Functions.h, failing with a message). Functions whose FMI 2.0
//! counterpart has the same arguments call it: the instance names them as
//! the importer called them (see [`crate::fmi::instance::state_table`]).
#![allow(non_snake_case, non_camel_case_types, clippy::missing_safety_doc)]

use super::*;

/// An instance, as the importer holds it.
pub type fmi3Instance = *mut c_void;
/// A saved state.
pub type fmi3FMUState = *mut c_void;
/// A variable's value reference.
pub type fmi3ValueReference = u32;
/// FMI 3.0 Float64.
pub type fmi3Float64 = f64;
/// FMI 3.0 Int32.
pub type fmi3Int32 = i32;
/// FMI 3.0 Boolean (C `bool`).
pub type fmi3Boolean = bool;
/// FMI 3.0 String (NUL-terminated UTF-8).
pub type fmi3String = *const c_char;
/// One byte of a serialized state.
pub type fmi3Byte = u8;
/// fmi3OK = 0, fmi3Warning, fmi3Discard, fmi3Error, fmi3Fatal.
pub type fmi3Status = c_int;

/// The importer's logger (not variadic in FMI 3.0).
pub type fmi3LogMessageCallback = Option<
    unsafe extern "C" fn(
        instanceEnvironment: *mut c_void,
        status: fmi3Status,
        category: fmi3String,
        message: fmi3String,
    ),
>;

/// Passes messages to the importer's FMI 3.0 logger.
struct Fmi3Sink {
    logger: fmi3LogMessageCallback,
    env: *mut c_void,
}

impl LogSink for Fmi3Sink {
    fn log(&self, status: Status, category: &str, message: &str) {
        if let Some(logger) = self.logger {
            let (category, message) = (c_text(category), c_text(message));
            unsafe {
                logger(
                    self.env,
                    status as fmi3Status,
                    category.as_ptr(),
                    message.as_ptr(),
                )
            };
        }
    }
}

/// Runs an export that this FMU does not provide: an error naming why.
unsafe fn not_provided(c: fmi3Instance, func: &str, why: &str) -> fmi3Status {
    with(c, func, |comp| comp.instance.error(func, why))
}

/// Refuses to create an instance of an interface type not provided: NULL,
/// with the reason logged through the importer's logger.
unsafe fn refuse_instantiation(
    instanceName: fmi3String,
    env: *mut c_void,
    logger: fmi3LogMessageCallback,
    func: &str,
    why: &str,
) -> fmi3Instance {
    let _ = catch_quietly(|| {
        let name = string_arg(instanceName).unwrap_or_default();
        let sink = Box::new(Fmi3Sink { logger, env });
        let no_dir = Err(String::new());
        let mut instance = Instance::with_resource_dir(&name, no_dir, sink, false);
        instance.use_fmi3(false, false);
        instance.error(func, why);
    });
    std::ptr::null_mut()
}

mod not_provided;
mod provided;

pub use not_provided::*;
pub use provided::*;
