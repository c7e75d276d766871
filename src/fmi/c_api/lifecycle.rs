//! Instances and their life: create, set up, initialize, terminate, reset, free.

use super::*;

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
    let result = catch_quietly(|| {
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
        if !token_matches(&mut instance, F, fmuGUID) {
            return std::ptr::null_mut();
        }
        Box::into_raw(Box::new(Component {
            instance,
            strings: vec![],
        })) as fmi2Component
    });
    result.unwrap_or_else(|text| {
        // Through the importer's logger, never on its stderr.
        let _ = catch_quietly(|| {
            if let Some(f) = functions.as_ref() {
                let sink = CallbackSink {
                    logger: f.logger,
                    env: f.componentEnvironment,
                    name: c_text(&string_arg(instanceName).unwrap_or_default()),
                };
                let message = format!("fmi2Instantiate: internal error: {text}");
                sink.log(Status::Fatal, "logStatusFatal", &message);
            }
        });
        std::ptr::null_mut()
    })
}

/// Frees an instance (NULL is ignored).
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    if !c.is_null() {
        let _ = catch_quietly(|| drop(Box::from_raw(c as *mut Component)));
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
