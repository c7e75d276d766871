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

use crate::fmi::resource_location;
use crate::fmi::variables::Model;
use crate::ground::formats;
use crate::ground::record::GroundMotion;
use crate::limits;
use crate::physics::engine::{Excitation, Outputs};
use crate::physics::params::{ParamError, Params};
use crate::solver::{Solver, SolverKind, Stepper, DEFAULT_FRICTION_EPS};
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;

pub mod floor;
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
    /// The defaults of `model`.
    fn of(model: Model) -> ParameterValues {
        match model {
            Model::Storey => ParameterValues::default(),
            Model::Floor => ParameterValues {
                params: floor::default_params(),
                ..ParameterValues::default()
            },
        }
    }

    fn build(&self) -> Result<Solver, ParamError> {
        let kind = SolverKind::from_code(self.solver).unwrap_or(SolverKind::EventLocated);
        Solver::new(&self.params, kind, self.max_step, self.friction_eps)
            .map_err(|e| floor::public_error(&self.params, e))
    }
}

/// Everything that changes while simulating: what a saved state holds.
#[derive(Clone)]
struct Dynamic {
    /// The model (a saved state is restored only into an instance of it).
    model: Model,
    phase: Phase,
    start_time: f64,
    stop_time: Option<f64>,
    /// The FMU's time: `start_time` plus the simulator's own time.
    time: f64,
    /// Steps of positive size since initialization (the rounding two clocks
    /// can differ by grows with it: [`limits::time_tolerance`]).
    steps: u64,
    /// `tSwitch`: the first switch inside the last step, or its end.
    t_switch: f64,
    values: ParameterValues,
    ag: f64,
    fext: f64,
    der_ag: f64,
    der_fext: f64,
    /// StackOnFloor's `supportMobility` (1/kg; 0 for the storey).
    support_mobility: f64,
    sim: Option<Solver>,
}

impl Dynamic {
    fn initial(model: Model) -> Dynamic {
        Dynamic {
            model,
            phase: Phase::Instantiated,
            start_time: 0.0,
            stop_time: None,
            time: 0.0,
            steps: 0,
            t_switch: 0.0,
            values: ParameterValues::of(model),
            ag: 0.0,
            fext: 0.0,
            der_ag: 0.0,
            der_fext: 0.0,
            support_mobility: 0.0,
            sim: None,
        }
    }
}

/// A saved FMU state (`fmi2FMUstate`).
#[derive(Clone)]
pub struct SavedState(Dynamic);

impl SavedState {
    /// The model whose instance saved it.
    pub fn model(&self) -> Model {
        self.0.model
    }
}

/// One FMU instance (see the module docs).
pub struct Instance {
    name: String,
    logger: Box<dyn LogSink>,
    debug_logging: bool,
    /// The resources folder, or why the importer's location names none
    /// (needed only by a relative `recordFile`).
    resource_dir: Result<PathBuf, String>,
    record: Option<(RecordKey, Arc<GroundMotion>)>,
    /// The cached record was read or checked against its file since the
    /// last fmi2Reset (this run reuses it unread).
    record_checked: bool,
    outputs: Option<Outputs>,
    d: Dynamic,
    /// The ABI the importer uses (messages name its functions).
    abi: Abi,
    /// FMI 3.0 `earlyReturnAllowed` and `eventModeUsed` of fmi3InstantiateCoSimulation.
    fmi3_flags: (bool, bool),
    /// The model the importer's GUID / instantiation token named.
    model: Model,
}

impl Instance {
    /// A new instance in state `Instantiated`; `resource_location` is the
    /// importer's `file:` URI of the unzipped FMU's resources folder (see
    /// [`resource_location`]; an unusable one is an error only when a
    /// relative `recordFile` needs it).
    pub fn new(
        name: &str,
        resource_location: Option<&str>,
        logger: Box<dyn LogSink>,
        logging_on: bool,
    ) -> Instance {
        let dir =
            resource_location::resource_dir(resource_location.map(str::as_bytes)).map_err(|why| {
                match resource_location {
                    Some(uri) => format!(
                        "fmuResourceLocation `{}` names no folder: {why}",
                        resource_location::shown(uri.as_bytes())
                    ),
                    None => "fmi2Instantiate was given no fmuResourceLocation (NULL)".into(),
                }
            });
        let inst = Instance::with_resource_dir(name, dir, logger, logging_on);
        if let Err(why) = &inst.resource_dir {
            inst.debug(&format!(
                "fmi2Instantiate: {why}; a relative recordFile will be refused"
            ));
        }
        inst
    }

    /// A new instance whose resources folder is `resource_dir` (or the
    /// reason there is none), for an importer that gives a path.
    pub fn with_resource_dir(
        name: &str,
        resource_dir: Result<PathBuf, String>,
        logger: Box<dyn LogSink>,
        logging_on: bool,
    ) -> Instance {
        Instance {
            name: name.to_string(),
            logger,
            debug_logging: logging_on,
            resource_dir,
            record: None,
            record_checked: false,
            outputs: None,
            d: Dynamic::initial(Model::Storey),
            abi: Abi::Fmi2,
            fmi3_flags: (false, false),
            model: Model::Storey,
        }
    }

    /// Makes this (fresh) instance one of `model` (the storey unless
    /// called): its variables, defaults and equations.
    pub fn use_model(&mut self, model: Model) {
        self.model = model;
        self.d = Dynamic::initial(model);
        self.outputs = None;
    }

    /// The model of this instance.
    pub fn model(&self) -> Model {
        self.model
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
            // (limits::MAX_TIME: at 1e16 s a step of 1 s would round away.)
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

    /// The record file's path: absolute as given, or relative to the FMU's
    /// resources folder (never to the process's working directory).
    fn record_path(&self, file: &str) -> Result<PathBuf, String> {
        let path = Path::new(file);
        if path.is_absolute() {
            return Ok(path.to_path_buf());
        }
        // `\\dir` or `C:dir` on Windows: rooted or prefixed but not absolute,
        // relative to a current drive or folder.
        if path.has_root() || matches!(path.components().next(), Some(Component::Prefix(_))) {
            return Err(format!(
                "`{file}` is neither an absolute path nor one relative to the FMU's resources \
                 folder (it depends on the process's current drive)"
            ));
        }
        match &self.resource_dir {
            Ok(dir) => Ok(dir.join(path)),
            Err(why) => Err(format!(
                "`{file}` is a relative path, read from the FMU's resources folder, but {why}; \
                 give an absolute path"
            )),
        }
    }

    /// Reads the record `recordFile` names, or reuses the one read before:
    /// unread within a run (since the last fmi2Reset), and after it if its
    /// file still holds the same bytes.
    fn load_record(&mut self, func: &str) -> Result<(), Status> {
        let file = self.d.values.record_file.clone();
        if file.is_empty() {
            self.record = None;
            return Ok(());
        }
        let path = match self.record_path(&file) {
            Ok(path) => path,
            Err(e) => return Err(self.error(func, format!("recordFile: {e}"))),
        };
        let g_bits = self.d.values.params.g.to_bits();
        let same_file = |k: &RecordKey| k.path == path && k.g_bits == g_bits;
        if let Some((key, _)) = self.record.as_ref().filter(|(k, _)| same_file(k)) {
            if self.record_checked {
                return Ok(());
            }
            let known = key.fingerprint;
            match formats::fingerprint(&path) {
                Ok(now) if now == known => {
                    self.record_checked = true;
                    return Ok(());
                }
                Ok(_) => {}
                Err(e) => return Err(self.error(func, format!("recordFile: {e}"))),
            }
        }
        match GroundMotion::read_with_fingerprint(&path, self.d.values.params.g) {
            Ok((gm, fingerprint)) => {
                self.debug(&format!(
                    "recordFile: read {} samples from {}",
                    gm.time.len(),
                    path.display()
                ));
                let key = RecordKey {
                    path,
                    g_bits,
                    fingerprint,
                };
                self.record = Some((key, Arc::new(gm)));
                self.record_checked = true;
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
    /// (A record already read stays cached, and is read again unless its
    /// file holds the same bytes.)
    pub fn reset(&mut self) -> Status {
        self.d = Dynamic::initial(self.model);
        self.outputs = None;
        self.record_checked = false;
        Status::Ok
    }
}

/// What a parsed record depends on: the file's path and content (a keyed
/// hash of its bytes, [`formats::fingerprint`]) and `g` (AT2 files are in
/// units of g). A study reuses a parsed record across fmi2Reset; a file
/// rewritten in between (even with the same size and modification time), or
/// another g, is read again.
#[derive(Clone, Debug, PartialEq)]
struct RecordKey {
    path: PathBuf,
    g_bits: u64,
    fingerprint: formats::Fingerprint,
}

/// A sink that drops everything.
pub struct NullSink;

impl LogSink for NullSink {
    fn log(&self, _: Status, _: &str, _: &str) {}
}
