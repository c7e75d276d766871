//! The fmi3Functions.h functions this FMU does not provide: each is exported
//! (FMI 3.0.1 requires every one) and fails with a message naming why.
#![allow(clippy::too_many_arguments)]

use super::*;

// Interface types other than Co-Simulation
/// This FMU provides Co-Simulation only: returns NULL, with a logged reason.
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    instanceName: fmi3String,
    _instantiationToken: fmi3String,
    _resourcePath: fmi3String,
    _visible: fmi3Boolean,
    _loggingOn: fmi3Boolean,
    instanceEnvironment: *mut c_void,
    logMessage: fmi3LogMessageCallback,
) -> fmi3Instance {
    refuse_instantiation(
        instanceName,
        instanceEnvironment,
        logMessage,
        "fmi3InstantiateModelExchange",
        "this FMU provides Co-Simulation only",
    )
}

/// This FMU provides Co-Simulation only: returns NULL, with a logged reason.
#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    instanceName: fmi3String,
    _instantiationToken: fmi3String,
    _resourcePath: fmi3String,
    _visible: fmi3Boolean,
    _loggingOn: fmi3Boolean,
    instanceEnvironment: *mut c_void,
    logMessage: fmi3LogMessageCallback,
    _clockUpdate: *const c_void,
    _lockPreemption: *const c_void,
    _unlockPreemption: *const c_void,
) -> fmi3Instance {
    refuse_instantiation(
        instanceName,
        instanceEnvironment,
        logMessage,
        "fmi3InstantiateScheduledExecution",
        "this FMU provides Co-Simulation only",
    )
}

// Value types this FMU has no variable of
/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetFloat32(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *mut f32,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3GetFloat32", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetInt8(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *mut i8,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3GetInt8", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetUInt8(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *mut u8,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3GetUInt8", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetInt16(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *mut i16,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3GetInt16", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetUInt16(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *mut u16,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3GetUInt16", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetUInt32(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *mut u32,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3GetUInt32", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetInt64(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *mut i64,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3GetInt64", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetUInt64(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *mut u64,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3GetUInt64", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetBinary(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _valueSizes: *mut usize,
    _values: *mut *const u8,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3GetBinary", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetFloat32(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *const f32,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3SetFloat32", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetInt8(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *const i8,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3SetInt8", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetUInt8(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *const u8,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3SetUInt8", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetInt16(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *const i16,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3SetInt16", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetUInt16(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *const u16,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3SetUInt16", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetUInt32(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *const u32,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3SetUInt32", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetInt64(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *const i64,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3SetInt64", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetUInt64(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *const u64,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3SetUInt64", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

/// This FMU has no variable of this type (its variables are Float64, Int32, Boolean and String): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetBinary(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _valueSizes: *const usize,
    _values: *const *const u8,
    _nValues: usize,
) -> fmi3Status {
    not_provided(instance, "fmi3SetBinary", "this FMU has no variable of this type (its variables are Float64, Int32, Boolean and String)")
}

// Clocks
/// This FMU has no clocks: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetClock(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *mut fmi3Boolean,
) -> fmi3Status {
    not_provided(instance, "fmi3GetClock", "this FMU has no clocks")
}

/// This FMU has no clocks: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetClock(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _values: *const fmi3Boolean,
) -> fmi3Status {
    not_provided(instance, "fmi3SetClock", "this FMU has no clocks")
}

/// This FMU has no clocks: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetIntervalDecimal(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _intervals: *mut fmi3Float64,
    _qualifiers: *mut c_int,
) -> fmi3Status {
    not_provided(instance, "fmi3GetIntervalDecimal", "this FMU has no clocks")
}

/// This FMU has no clocks: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetIntervalFraction(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _counters: *mut u64,
    _resolutions: *mut u64,
    _qualifiers: *mut c_int,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3GetIntervalFraction",
        "this FMU has no clocks",
    )
}

/// This FMU has no clocks: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetShiftDecimal(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _shifts: *mut fmi3Float64,
) -> fmi3Status {
    not_provided(instance, "fmi3GetShiftDecimal", "this FMU has no clocks")
}

/// This FMU has no clocks: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetShiftFraction(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _counters: *mut u64,
    _resolutions: *mut u64,
) -> fmi3Status {
    not_provided(instance, "fmi3GetShiftFraction", "this FMU has no clocks")
}

/// This FMU has no clocks: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetIntervalDecimal(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _intervals: *const fmi3Float64,
) -> fmi3Status {
    not_provided(instance, "fmi3SetIntervalDecimal", "this FMU has no clocks")
}

/// This FMU has no clocks: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetIntervalFraction(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _counters: *const u64,
    _resolutions: *const u64,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3SetIntervalFraction",
        "this FMU has no clocks",
    )
}

/// This FMU has no clocks: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetShiftDecimal(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _shifts: *const fmi3Float64,
) -> fmi3Status {
    not_provided(instance, "fmi3SetShiftDecimal", "this FMU has no clocks")
}

/// This FMU has no clocks: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetShiftFraction(
    instance: fmi3Instance,
    _valueReferences: *const fmi3ValueReference,
    _nValueReferences: usize,
    _counters: *const u64,
    _resolutions: *const u64,
) -> fmi3Status {
    not_provided(instance, "fmi3SetShiftFraction", "this FMU has no clocks")
}

/// This FMU has no clocks: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3ActivateModelPartition(
    instance: fmi3Instance,
    _clockReference: fmi3ValueReference,
    _activationTime: fmi3Float64,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3ActivateModelPartition",
        "this FMU has no clocks",
    )
}

// Dependencies and partial derivatives (the model description declares the dependencies)
/// Not provided (the outputs' dependencies are in the model description; providesAdjointDerivatives is false): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetNumberOfVariableDependencies(
    instance: fmi3Instance,
    _valueReference: fmi3ValueReference,
    _nDependencies: *mut usize,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3GetNumberOfVariableDependencies",
        "not provided (the outputs' dependencies are in the model description)",
    )
}

/// Not provided (the outputs' dependencies are in the model description; providesAdjointDerivatives is false): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetVariableDependencies(
    instance: fmi3Instance,
    _dependent: fmi3ValueReference,
    _elementIndicesOfDependent: *mut usize,
    _independents: *mut fmi3ValueReference,
    _elementIndicesOfIndependents: *mut usize,
    _dependencyKinds: *mut c_int,
    _nDependencies: usize,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3GetVariableDependencies",
        "not provided (the outputs' dependencies are in the model description)",
    )
}

/// Not provided (the outputs' dependencies are in the model description; providesAdjointDerivatives is false): always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetAdjointDerivative(
    instance: fmi3Instance,
    _unknowns: *const fmi3ValueReference,
    _nUnknowns: usize,
    _knowns: *const fmi3ValueReference,
    _nKnowns: usize,
    _seed: *const fmi3Float64,
    _nSeed: usize,
    _sensitivity: *mut fmi3Float64,
    _nSensitivity: usize,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3GetAdjointDerivative",
        "not provided (the outputs' dependencies are in the model description)",
    )
}

// Configuration Mode and discrete-state evaluation
/// Not provided: this FMU has no structural parameters and no clocks: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    not_provided(
        instance,
        "fmi3EnterConfigurationMode",
        "not provided: this FMU has no structural parameters and no clocks",
    )
}

/// Not provided: this FMU has no structural parameters and no clocks: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3ExitConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    not_provided(
        instance,
        "fmi3ExitConfigurationMode",
        "not provided: this FMU has no structural parameters and no clocks",
    )
}

/// Not provided: this FMU has no structural parameters and no clocks: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3EvaluateDiscreteStates(instance: fmi3Instance) -> fmi3Status {
    not_provided(
        instance,
        "fmi3EvaluateDiscreteStates",
        "not provided: this FMU has no structural parameters and no clocks",
    )
}

// Model Exchange
/// A Model Exchange function: this FMU provides Co-Simulation only: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3EnterContinuousTimeMode(instance: fmi3Instance) -> fmi3Status {
    not_provided(
        instance,
        "fmi3EnterContinuousTimeMode",
        "a Model Exchange function: this FMU provides Co-Simulation only",
    )
}

/// A Model Exchange function: this FMU provides Co-Simulation only: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3CompletedIntegratorStep(
    instance: fmi3Instance,
    _noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
    _enterEventMode: *mut fmi3Boolean,
    _terminateSimulation: *mut fmi3Boolean,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3CompletedIntegratorStep",
        "a Model Exchange function: this FMU provides Co-Simulation only",
    )
}

/// A Model Exchange function: this FMU provides Co-Simulation only: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetTime(instance: fmi3Instance, _time: fmi3Float64) -> fmi3Status {
    not_provided(
        instance,
        "fmi3SetTime",
        "a Model Exchange function: this FMU provides Co-Simulation only",
    )
}

/// A Model Exchange function: this FMU provides Co-Simulation only: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3SetContinuousStates(
    instance: fmi3Instance,
    _continuousStates: *const fmi3Float64,
    _nContinuousStates: usize,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3SetContinuousStates",
        "a Model Exchange function: this FMU provides Co-Simulation only",
    )
}

/// A Model Exchange function: this FMU provides Co-Simulation only: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetContinuousStateDerivatives(
    instance: fmi3Instance,
    _derivatives: *mut fmi3Float64,
    _nContinuousStates: usize,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3GetContinuousStateDerivatives",
        "a Model Exchange function: this FMU provides Co-Simulation only",
    )
}

/// A Model Exchange function: this FMU provides Co-Simulation only: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetEventIndicators(
    instance: fmi3Instance,
    _eventIndicators: *mut fmi3Float64,
    _nEventIndicators: usize,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3GetEventIndicators",
        "a Model Exchange function: this FMU provides Co-Simulation only",
    )
}

/// A Model Exchange function: this FMU provides Co-Simulation only: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetContinuousStates(
    instance: fmi3Instance,
    _continuousStates: *mut fmi3Float64,
    _nContinuousStates: usize,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3GetContinuousStates",
        "a Model Exchange function: this FMU provides Co-Simulation only",
    )
}

/// A Model Exchange function: this FMU provides Co-Simulation only: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetNominalsOfContinuousStates(
    instance: fmi3Instance,
    _nominals: *mut fmi3Float64,
    _nContinuousStates: usize,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3GetNominalsOfContinuousStates",
        "a Model Exchange function: this FMU provides Co-Simulation only",
    )
}

/// A Model Exchange function: this FMU provides Co-Simulation only: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetNumberOfEventIndicators(
    instance: fmi3Instance,
    _nEventIndicators: *mut usize,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3GetNumberOfEventIndicators",
        "a Model Exchange function: this FMU provides Co-Simulation only",
    )
}

/// A Model Exchange function: this FMU provides Co-Simulation only: always fmi3Error, with a logged message.
#[no_mangle]
pub unsafe extern "C" fn fmi3GetNumberOfContinuousStates(
    instance: fmi3Instance,
    _nContinuousStates: *mut usize,
) -> fmi3Status {
    not_provided(
        instance,
        "fmi3GetNumberOfContinuousStates",
        "a Model Exchange function: this FMU provides Co-Simulation only",
    )
}
