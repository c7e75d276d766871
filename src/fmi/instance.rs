//! One FMU instance in safe Rust: the FMI 2.0 Co-Simulation state machine,
//! variables, inputs and their derivatives, the ground-motion record, the
//! simulator, status queries and saved states. The C ABI in [`crate::fmi::c_api`]
//! only checks pointers, converts arguments and calls in here.
//!
//! This file holds the instance itself: its status codes, log sink, phases
//! and state, instantiation, logging, the state-machine transitions
//! (setup, initialization, terminate, reset) and the ground-motion record.
//! The rest of the instance's methods live in the child modules:
//! - `values`: fmi2Get/fmi2Set of Real, Integer, Boolean and String;
//! - `stepping`: fmi2DoStep, input and output derivatives, status queries;
//! - `saved_state`: fmi2Get/SetFMUstate, their byte format and its checks.

use crate::ground::record::GroundMotion;
use crate::limits;
use crate::physics::engine::{Excitation, Outputs};
use crate::physics::params::{ParamError, Params};
use crate::physics::solver::{Solver, SolverKind, Stepper, DEFAULT_FRICTION_EPS};
use std::path::{Path, PathBuf};
use std::sync::Arc;

mod fmi3_cs;
mod saved_state;
pub mod state_table;
mod stepping;
mod values;

pub use fmi3_cs::{StepOutcome, StepRequest};
use state_table::Abi;

/// FMI 2.0 status codes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[repr(i32)]
pub enum Status {
    /// fmi2OK.
    Ok = 0,
    /// fmi2Warning.
    Warning = 1,
    /// fmi2Discard.
    Discard = 2,
    /// fmi2Error.
    Error = 3,
    /// fmi2Fatal.
    Fatal = 4,
    /// fmi2Pending.
    Pending = 5,
}

/// Where log messages go (the importer's logger, or a test's buffer).
pub trait LogSink {
    /// Passes one message (already formatted).
    fn log(&self, status: Status, category: &str, message: &str);
}

/// The states of the FMI 2.0 and FMI 3.0 Co-Simulation state machines
/// (`StepComplete` is FMI 3.0's Step Mode).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// After fmi2Instantiate or fmi2Reset.
    Instantiated,
    /// Between fmi2EnterInitializationMode and fmi2ExitInitializationMode.
    InitializationMode,
    /// Ready for fmi2DoStep.
    StepComplete,
    /// After fmi2Terminate.
    Terminated,
    /// After a failed step or a caught panic.
    Error,
    /// FMI 3.0 Event Mode (Co-Simulation with `eventModeUsed`).
    EventMode,
}

/// Values of every parameter, exactly as the importer set them.
#[derive(Clone, Debug, PartialEq)]
struct ParameterValues {
    params: Params,
    record_file: String,
    record_scale: f64,
    solver: i32,
    max_step: f64,
    friction_eps: f64,
}

impl Default for ParameterValues {
    fn default() -> Self {
        ParameterValues {
            params: Params::default(),
            record_file: String::new(),
            record_scale: 1.0,
            solver: 1,
            max_step: 0.0,
            friction_eps: DEFAULT_FRICTION_EPS,
        }
    }
}

impl ParameterValues {
    fn build(&self) -> Result<Solver, ParamError> {
        let kind = SolverKind::from_code(self.solver).unwrap_or(SolverKind::EventLocated);
        Solver::new(&self.params, kind, self.max_step, self.friction_eps)
    }
}

/// Everything that changes while simulating: what a saved state holds.
#[derive(Clone)]
struct Dynamic {
    phase: Phase,
    start_time: f64,
    stop_time: Option<f64>,
    time: f64,
    /// `tSwitch`: the first switch inside the last step, or its end.
    t_switch: f64,
    values: ParameterValues,
    ag: f64,
    fext: f64,
    der_ag: f64,
    der_fext: f64,
    sim: Option<Solver>,
}

impl Dynamic {
    fn initial() -> Dynamic {
        Dynamic {
            phase: Phase::Instantiated,
            start_time: 0.0,
            stop_time: None,
            time: 0.0,
            t_switch: 0.0,
            values: ParameterValues::default(),
            ag: 0.0,
            fext: 0.0,
            der_ag: 0.0,
            der_fext: 0.0,
            sim: None,
        }
    }
}

/// A saved FMU state (`fmi2FMUstate`).
#[derive(Clone)]
pub struct SavedState(Dynamic);

/// One FMU instance (see the module docs).
pub struct Instance {
    name: String,
    logger: Box<dyn LogSink>,
    debug_logging: bool,
    resource_dir: Option<PathBuf>,
    record: Option<(RecordKey, Arc<GroundMotion>)>,
    outputs: Option<Outputs>,
    d: Dynamic,
    /// The ABI the importer uses (messages name its functions).
    abi: Abi,
    /// FMI 3.0 `earlyReturnAllowed` and `eventModeUsed` of fmi3InstantiateCoSimulation.
    fmi3_flags: (bool, bool),
}

/// Parses `file:///a/b`, `file:/a/b` or `file://localhost/a/b` (percent-decoded).
pub fn resource_dir_from_uri(uri: &str) -> Option<PathBuf> {
    let rest = uri.strip_prefix("file:")?;
    let path = if let Some(r) = rest.strip_prefix("//") {
        &r[r.find('/')?..]
    } else {
        rest
    };
    let bytes = path.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let Ok(b) = u8::from_str_radix(&path[i + 1..i + 3], 16) {
                out.push(b);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    Some(PathBuf::from(String::from_utf8(out).ok()?))
}

impl Instance {
    /// A new instance in state `Instantiated`; `resource_location` is the
    /// importer's `file:` URI of the unzipped FMU's resources folder.
    pub fn new(
        name: &str,
        resource_location: Option<&str>,
        logger: Box<dyn LogSink>,
        logging_on: bool,
    ) -> Instance {
        Instance {
            name: name.to_string(),
            logger,
            debug_logging: logging_on,
            resource_dir: resource_location.and_then(resource_dir_from_uri),
            record: None,
            outputs: None,
            d: Dynamic::initial(),
            abi: Abi::Fmi2,
            fmi3_flags: (false, false),
        }
    }

    /// Marks the instance as created through the FMI 3.0 ABI, with its
    /// `earlyReturnAllowed` and `eventModeUsed` (messages then name fmi3 functions).
    pub fn use_fmi3(&mut self, early_return_allowed: bool, event_mode_used: bool) {
        self.abi = Abi::Fmi3;
        self.fmi3_flags = (early_return_allowed, event_mode_used);
    }

    /// The instance name given by the importer.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The current state of the FMI state machine.
    pub fn phase(&self) -> Phase {
        self.d.phase
    }

    /// Logs an error of function `func` and returns `Status::Error`.
    pub fn error(&mut self, func: &str, message: impl AsRef<str>) -> Status {
        let func = state_table::name_for(func, self.abi);
        self.logger.log(
            Status::Error,
            "logStatusError",
            &format!("{func}: {}", message.as_ref()),
        );
        Status::Error
    }

    /// Logs a fatal error (a panic caught at the ABI) and marks the instance unusable.
    pub fn fatal(&mut self, func: &str, message: &str) -> Status {
        self.d.phase = Phase::Error;
        let func = state_table::name_for(func, self.abi);
        self.logger.log(
            Status::Fatal,
            "logStatusFatal",
            &format!("{func}: {message}"),
        );
        Status::Fatal
    }

    fn debug(&self, message: &str) {
        if self.debug_logging {
            self.logger.log(Status::Ok, "logAll", message);
        }
    }

    /// fmi2SetDebugLogging.
    pub fn set_debug_logging(&mut self, on: bool) -> Status {
        self.debug_logging = on;
        Status::Ok
    }

    /// Errors unless function `func` is legal in the current state
    /// ([`state_table`]).
    fn require(&mut self, func: &str) -> Result<(), Status> {
        if state_table::legal(func, self.d.phase) {
            Ok(())
        } else {
            let phase = self.d.phase;
            Err(self.error(func, format!("not allowed in state {phase:?}")))
        }
    }

    /// fmi2SetupExperiment.
    pub fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> Status {
        const F: &str = "fmi2SetupExperiment";
        if let Err(s) = self.require(F) {
            return s;
        }
        let in_range = |t: f64| t.abs() <= limits::MAX_TIME;
        if !in_range(start) || stop.is_some_and(|s| !(in_range(s) && s >= start)) {
            let stop = stop.map_or("none".to_string(), |s| limits::Num(s).to_string());
            return self.error(
                F,
                format!(
                    "startTime = {}, stopTime = {stop}: times must be finite, within \
                     -{max} .. {max} s, with stopTime >= startTime",
                    limits::Num(start),
                    max = limits::Num(limits::MAX_TIME),
                ),
            );
        }
        self.d.start_time = start;
        self.d.time = start;
        self.d.t_switch = start;
        self.d.stop_time = stop;
        Status::Ok
    }

    /// fmi2EnterInitializationMode.
    pub fn enter_initialization_mode(&mut self) -> Status {
        if let Err(s) = self.require("fmi2EnterInitializationMode") {
            return s;
        }
        self.d.phase = Phase::InitializationMode;
        self.d.sim = None;
        Status::Ok
    }

    /// Builds the simulator from the parameters (and reads the record).
    fn build(&mut self, func: &str) -> Result<(), Status> {
        let values = self.d.values.clone();
        let mut sim = match values.build() {
            Ok(sim) => sim,
            Err(e) => return Err(self.error(func, e.to_string())),
        };
        sim.advance(
            0.0,
            &Excitation {
                fext: self.d.fext,
                ..Default::default()
            },
        )
        .map_err(|e| self.error(func, e.to_string()))?;
        self.load_record(func)?;
        if let Some(message) = limits::non_finite_message(&sim.outputs(), self.d.start_time) {
            return Err(self.error(func, message));
        }
        self.d.sim = Some(sim);
        self.outputs = None;
        Ok(())
    }

    fn load_record(&mut self, func: &str) -> Result<(), Status> {
        let file = self.d.values.record_file.clone();
        if file.is_empty() {
            self.record = None;
            return Ok(());
        }
        let path = Path::new(&file);
        let path = match (&self.resource_dir, path.is_absolute()) {
            (Some(dir), false) => dir.join(path),
            _ => path.to_path_buf(),
        };
        let key = RecordKey::of(&path, self.d.values.params.g);
        if self.record.as_ref().is_some_and(|(k, _)| *k == key) {
            return Ok(());
        }
        match GroundMotion::read(&path, self.d.values.params.g) {
            Ok(gm) => {
                self.debug(&format!(
                    "recordFile: read {} samples from {}",
                    gm.time.len(),
                    path.display()
                ));
                self.record = Some((key, Arc::new(gm)));
                Ok(())
            }
            Err(e) => Err(self.error(func, format!("recordFile: {e}"))),
        }
    }

    /// fmi2ExitInitializationMode: builds the simulator, reads the record.
    pub fn exit_initialization_mode(&mut self) -> Status {
        const F: &str = "fmi2ExitInitializationMode";
        if let Err(s) = self.require(F) {
            return s;
        }
        if let Err(s) = self.build(F) {
            return s;
        }
        self.d.phase = Phase::StepComplete;
        Status::Ok
    }

    /// fmi2Terminate.
    pub fn terminate(&mut self) -> Status {
        if let Err(s) = self.require("fmi2Terminate") {
            return s;
        }
        self.d.phase = Phase::Terminated;
        Status::Ok
    }

    /// Back to the state after instantiation: default values everywhere.
    /// (A record already read stays cached under its file name.)
    pub fn reset(&mut self) -> Status {
        self.d = Dynamic::initial();
        self.outputs = None;
        Status::Ok
    }
}

/// What a parsed record depends on: the file (path, size, modification time)
/// and `g` (AT2 files are in units of g). A study reuses a parsed record across
/// fmi2Reset; a file rewritten in between, or another g, is read again.
#[derive(Clone, Debug, PartialEq)]
struct RecordKey {
    path: std::path::PathBuf,
    stamp: Option<(u64, std::time::SystemTime)>,
    g_bits: u64,
}

impl RecordKey {
    fn of(path: &Path, g: f64) -> RecordKey {
        let stamp = std::fs::metadata(path)
            .ok()
            .and_then(|m| Some((m.len(), m.modified().ok()?)));
        RecordKey {
            path: path.to_path_buf(),
            stamp,
            g_bits: g.to_bits(),
        }
    }
}

/// A sink that drops everything.
pub struct NullSink;

impl LogSink for NullSink {
    fn log(&self, _: Status, _: &str, _: &str) {}
}
