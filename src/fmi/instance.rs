//! One FMU instance in safe Rust: the FMI 2.0 Co-Simulation state machine,
//! variables, inputs and their derivatives, the ground-motion record, the
//! simulator, status queries and saved states. The C ABI in [`crate::fmi::c_api`]
//! only checks pointers, converts arguments and calls in here.

use crate::fmi::ports;
use crate::fmi::variables::{Causality, Id};
use crate::ground::record::{self, GroundMotion};
use crate::limits::{self, MAX_PATH_BYTES};
use crate::physics::engine::{Excitation, Outputs};
use crate::physics::params::{check_scalar, ParamError, Params, MAX_BLOCKS};
use crate::physics::snapshot::{ByteReader, ByteWriter, SnapshotError};
use crate::physics::solver::{Solver, SolverKind, Stepper, DEFAULT_FRICTION_EPS};
use std::path::{Path, PathBuf};
use std::sync::Arc;

mod saved_state;
use saved_state::check_saved;

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

/// The states of the FMI 2.0 Co-Simulation state machine.
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

const STATE_MAGIC: &[u8; 8] = b"SLLSTATE";
const STATE_VERSION: u32 = 3;

/// One FMU instance (see the module docs).
pub struct Instance {
    name: String,
    logger: Box<dyn LogSink>,
    debug_logging: bool,
    resource_dir: Option<PathBuf>,
    record: Option<(RecordKey, Arc<GroundMotion>)>,
    outputs: Option<Outputs>,
    d: Dynamic,
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
        }
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

    /// Errors unless the instance is in one of `allowed` phases.
    fn require(&mut self, func: &str, allowed: &[Phase]) -> Result<(), Status> {
        if allowed.contains(&self.d.phase) {
            Ok(())
        } else {
            let phase = self.d.phase;
            Err(self.error(func, format!("not allowed in state {phase:?}")))
        }
    }

    /// fmi2SetupExperiment.
    pub fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> Status {
        const F: &str = "fmi2SetupExperiment";
        if let Err(s) = self.require(F, &[Phase::Instantiated]) {
            return s;
        }
        if !start.is_finite() || stop.is_some_and(|s| !(s.is_finite() && s >= start)) {
            return self.error(F, format!("startTime = {start}, stopTime = {stop:?}: need finite times with stopTime >= startTime"));
        }
        self.d.start_time = start;
        self.d.time = start;
        self.d.t_switch = start;
        self.d.stop_time = stop;
        Status::Ok
    }

    /// fmi2EnterInitializationMode.
    pub fn enter_initialization_mode(&mut self) -> Status {
        if let Err(s) = self.require("fmi2EnterInitializationMode", &[Phase::Instantiated]) {
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
        if let Err(s) = self.require(F, &[Phase::InitializationMode]) {
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
        if let Err(s) = self.require(
            "fmi2Terminate",
            &[Phase::StepComplete, Phase::InitializationMode],
        ) {
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

    // ---- variables ----

    fn lookup(&mut self, func: &str, vr: u32) -> Result<Id, Status> {
        Id::from_vr(vr).ok_or_else(|| self.error(func, format!("unknown value reference {vr}")))
    }

    /// The variable behind `vr`, if it exists and may be set now.
    fn target(&mut self, func: &str, vr: u32) -> Result<Id, Status> {
        let id = self.lookup(func, vr)?;
        self.settable(func, id)?;
        Ok(id)
    }

    /// Checks that variable `id` may be set now.
    fn settable(&mut self, func: &str, id: Id) -> Result<(), Status> {
        let phase = self.d.phase;
        let ok = match id.causality() {
            Causality::Parameter => {
                matches!(phase, Phase::Instantiated | Phase::InitializationMode)
            }
            Causality::Input => matches!(
                phase,
                Phase::Instantiated | Phase::InitializationMode | Phase::StepComplete
            ),
            Causality::Output => {
                return Err(self.error(
                    func,
                    format!("{} is an output and cannot be set", name_of(id)),
                ));
            }
        };
        if ok {
            Ok(())
        } else {
            Err(self.error(
                func,
                format!("{} cannot be set in state {phase:?}", name_of(id)),
            ))
        }
    }

    fn param_error(&mut self, func: &str, e: ParamError) -> Status {
        self.error(func, e.to_string())
    }

    /// fmi2SetReal.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        const F: &str = "fmi2SetReal";
        for (&vr, &x) in vrs.iter().zip(values) {
            let id = match self.target(F, vr) {
                Ok(id) => id,
                Err(s) => return s,
            };
            if let Err(e) = check_scalar(&name_of(id), x) {
                return self.param_error(F, e);
            }
            let v = &mut self.d.values;
            match id {
                Id::Mp => v.params.mp = x,
                Id::Tp => v.params.tp = x,
                Id::Zeta => v.params.zeta = x,
                Id::G => v.params.g = x,
                Id::RecordScale => v.record_scale = x,
                Id::MaxStep => v.max_step = x,
                Id::FrictionEps => v.friction_eps = x,
                Id::Alpha(j) => v.params.alpha[j - 1] = x,
                Id::Mus(j) => v.params.mus[j - 1] = x,
                Id::Muk(j) => v.params.muk[j - 1] = x,
                Id::Ag => self.d.ag = x,
                Id::Fext => self.d.fext = x,
                _ => return self.error(F, format!("{} is not a Real", name_of(id))),
            }
            // Outputs show the inputs set for the next step (a master may iterate).
            self.outputs = None;
            if id.causality() == Causality::Parameter {
                self.d.sim = None;
            }
        }
        Status::Ok
    }

    /// fmi2SetInteger.
    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Status {
        const F: &str = "fmi2SetInteger";
        for (&vr, &x) in vrs.iter().zip(values) {
            let id = match self.target(F, vr) {
                Ok(id) => id,
                Err(s) => return s,
            };
            match id {
                Id::NBlocks if (0..=MAX_BLOCKS as i32).contains(&x) => {
                    self.d.values.params.n_blocks = x as usize
                }
                Id::NBlocks => return self.error(F, format!("nBlocks = {x} is not allowed: it must be an integer from 0 to {MAX_BLOCKS}")),
                Id::Solver if SolverKind::from_code(x).is_some() => self.d.values.solver = x,
                Id::Solver => return self.error(F, format!("solver = {x} is not allowed: it must be 1 (event-located RK4), 2 (step-end switching) or 3 (tanh-regularized friction)")),
                _ => return self.error(F, format!("{} is not an Integer", name_of(id))),
            }
            self.d.sim = None;
        }
        Status::Ok
    }

    /// fmi2SetBoolean (nothing is settable).
    pub fn set_boolean(&mut self, vrs: &[u32], _values: &[i32]) -> Status {
        const F: &str = "fmi2SetBoolean";
        // The first reference decides: it is unknown, not settable now, or
        // a Boolean output.
        match vrs.first().map(|&vr| self.target(F, vr)) {
            None => Status::Ok,
            Some(Err(s)) => s,
            Some(Ok(id)) => self.error(F, format!("{} is not a settable Boolean", name_of(id))),
        }
    }

    /// fmi2SetString.
    pub fn set_string(&mut self, vrs: &[u32], values: &[String]) -> Status {
        const F: &str = "fmi2SetString";
        for (&vr, x) in vrs.iter().zip(values) {
            let id = match self.target(F, vr) {
                Ok(id) => id,
                Err(s) => return s,
            };
            match id {
                Id::RecordFile if x.len() > MAX_PATH_BYTES => {
                    return self.error(
                        F,
                        format!(
                            "recordFile of {} bytes is not allowed: it must be a path of at most {MAX_PATH_BYTES} bytes",
                            x.len()
                        ),
                    )
                }
                Id::RecordFile => self.d.values.record_file = x.clone(),
                _ => return self.error(F, format!("{} is not a String", name_of(id))),
            }
            self.d.sim = None;
        }
        Status::Ok
    }

    /// Outputs of the current state; in initialization mode the simulator
    /// is built on demand from the parameters set so far.
    fn current_outputs(&mut self, func: &str) -> Result<&Outputs, Status> {
        if self.d.sim.is_none() {
            if self.d.phase != Phase::InitializationMode {
                return Err(self.error(func, "outputs are not available before initialization"));
            }
            self.build(func)?;
        }
        if self.outputs.is_none() {
            let exc = self.next_excitation();
            let sim = self.d.sim.as_ref().expect("built above");
            let outputs = match ports::outputs_at_step_start(sim, &exc) {
                Ok(o) => o,
                Err(e) => return Err(self.error(func, e.to_string())),
            };
            // After a failed step the state may hold a NaN: never read as OK.
            if let Some(message) = limits::non_finite_message(&outputs, self.d.start_time) {
                return Err(self.error(func, message));
            }
            self.outputs = Some(outputs);
        }
        Ok(self.outputs.as_ref().expect("set above"))
    }

    /// The excitation the next step starts with: the record's piece at the
    /// current time (the next one if this one ends within rounding of now,
    /// as a step would take it) plus the inputs and their derivatives.
    fn next_excitation(&self) -> Excitation {
        let t = self.d.sim.as_ref().map_or(0.0, |s| s.time());
        let (a, slope) = match &self.record {
            Some((_, gm)) => {
                let (mut a, mut slope, end) = gm.piece_at(t);
                if end.is_finite() && end - t <= 1e-9 * t.abs().max(1.0) {
                    let (a_end, slope_end, _) = gm.piece_at(end);
                    (a, slope) = (a_end, slope_end);
                }
                let scale = self.d.values.record_scale;
                (scale * a, scale * slope)
            }
            None => (0.0, 0.0),
        };
        Excitation {
            ag: a + self.d.ag,
            ag_rate: slope + self.d.der_ag,
            fext: self.d.fext,
            fext_rate: self.d.der_fext,
        }
    }

    /// fmi2GetRealOutputDerivatives: derivatives of order 1 or 2 of continuous
    /// Real outputs at the current communication point, in the mode the next
    /// step starts in, under the inputs and input derivatives set for it.
    pub fn get_output_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        out: &mut [f64],
    ) -> Status {
        const F: &str = "fmi2GetRealOutputDerivatives";
        if let Err(s) = self.require(F, &[Phase::StepComplete, Phase::Terminated]) {
            return s;
        }
        let exc = self.next_excitation();
        let derivatives = match &self.d.sim {
            Some(Solver::Exact(sim)) => match ports::exact_at_step_start(sim, &exc) {
                Ok(next) => ports::derivatives(&next, &exc),
                Err(e) => return self.error(F, e.to_string()),
            },
            _ => {
                return self.error(
                    F,
                    "output derivatives are provided by solvers 1 and 2, not by solver 3 (the regularized baseline)",
                )
            }
        };
        for ((&vr, &order), slot) in vrs.iter().zip(orders).zip(out.iter_mut()) {
            let id = match self.lookup(F, vr) {
                Ok(id) => id,
                Err(s) => return s,
            };
            if id.causality() != Causality::Output || !id.is_continuous() {
                return self.error(
                    F,
                    format!(
                        "{} is not a continuous Real output: it has no derivative",
                        name_of(id)
                    ),
                );
            }
            if !(1..=2).contains(&order) {
                return self.error(F, format!("derivative order {order} of {} is not provided: orders 1 and 2 are (maxOutputDerivativeOrder = 2)", name_of(id)));
            }
            let of_order = &derivatives[order as usize - 1];
            *slot = real_output(of_order, id).expect("every continuous Real output has a field");
        }
        Status::Ok
    }

    fn readable(&mut self, func: &str) -> Result<(), Status> {
        self.require(
            func,
            &[
                Phase::InitializationMode,
                Phase::StepComplete,
                Phase::Terminated,
                Phase::Error,
            ],
        )
    }

    /// fmi2GetReal.
    pub fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Status {
        const F: &str = "fmi2GetReal";
        if let Err(s) = self.readable(F) {
            return s;
        }
        for (&vr, slot) in vrs.iter().zip(out.iter_mut()) {
            let id = match self.lookup(F, vr) {
                Ok(id) => id,
                Err(s) => return s,
            };
            let v = &self.d.values;
            let p = &v.params;
            let block = |j: usize, xs: &[f64; MAX_BLOCKS]| xs[j - 1];
            *slot = match id {
                Id::Mp => p.mp,
                Id::Tp => p.tp,
                Id::Zeta => p.zeta,
                Id::G => p.g,
                Id::RecordScale => v.record_scale,
                Id::MaxStep => v.max_step,
                Id::FrictionEps => v.friction_eps,
                Id::Alpha(j) => block(j, &p.alpha),
                Id::Mus(j) => block(j, &p.mus),
                Id::Muk(j) => block(j, &p.muk),
                Id::Ag => self.d.ag,
                Id::Fext => self.d.fext,
                Id::TSwitch => self.d.t_switch,
                _ => {
                    let o = match self.current_outputs(F) {
                        Ok(o) => o,
                        Err(s) => return s,
                    };
                    match real_output(o, id) {
                        Some(x) => x,
                        None => return self.error(F, format!("{} is not a Real", name_of(id))),
                    }
                }
            };
        }
        Status::Ok
    }

    /// fmi2GetInteger.
    pub fn get_integer(&mut self, vrs: &[u32], out: &mut [i32]) -> Status {
        const F: &str = "fmi2GetInteger";
        if let Err(s) = self.readable(F) {
            return s;
        }
        for (&vr, slot) in vrs.iter().zip(out.iter_mut()) {
            *slot = match self.lookup(F, vr) {
                Ok(Id::NBlocks) => self.d.values.params.n_blocks as i32,
                Ok(Id::Solver) => self.d.values.solver,
                Ok(Id::NEvents) => match self.current_outputs(F) {
                    Ok(o) => o.n_events.min(i32::MAX as u64) as i32,
                    Err(s) => return s,
                },
                Ok(Id::NAmbiguous) => match self.current_outputs(F) {
                    Ok(o) => o.n_ambiguous.min(i32::MAX as u64) as i32,
                    Err(s) => return s,
                },
                Ok(id) => return self.error(F, format!("{} is not an Integer", name_of(id))),
                Err(s) => return s,
            };
        }
        Status::Ok
    }

    /// fmi2GetBoolean.
    pub fn get_boolean(&mut self, vrs: &[u32], out: &mut [i32]) -> Status {
        const F: &str = "fmi2GetBoolean";
        if let Err(s) = self.readable(F) {
            return s;
        }
        for (&vr, slot) in vrs.iter().zip(out.iter_mut()) {
            *slot = match self.lookup(F, vr) {
                Ok(Id::Stuck(j)) => match self.current_outputs(F) {
                    Ok(o) => i32::from(o.stuck[j - 1]),
                    Err(s) => return s,
                },
                Ok(id) => return self.error(F, format!("{} is not a Boolean", name_of(id))),
                Err(s) => return s,
            };
        }
        Status::Ok
    }

    /// fmi2GetString.
    pub fn get_string(&mut self, vrs: &[u32]) -> Result<Vec<String>, Status> {
        const F: &str = "fmi2GetString";
        self.readable(F)?;
        vrs.iter()
            .map(|&vr| match self.lookup(F, vr)? {
                Id::RecordFile => Ok(self.d.values.record_file.clone()),
                id => Err(self.error(F, format!("{} is not a String", name_of(id)))),
            })
            .collect()
    }

    /// `fmi2SetRealInputDerivatives`, order 1: the slope of an input over the
    /// next step (reset to zero after every step: without it the input is held).
    pub fn set_input_derivatives(&mut self, vrs: &[u32], orders: &[i32], values: &[f64]) -> Status {
        const F: &str = "fmi2SetRealInputDerivatives";
        if let Err(s) = self.require(
            F,
            &[
                Phase::Instantiated,
                Phase::InitializationMode,
                Phase::StepComplete,
            ],
        ) {
            return s;
        }
        for ((&vr, &order), &x) in vrs.iter().zip(orders).zip(values) {
            let id = match self.lookup(F, vr) {
                Ok(id) => id,
                Err(s) => return s,
            };
            if order != 1 {
                return self.error(
                    F,
                    format!(
                        "derivative order {order} of {} is not supported: only order 1",
                        name_of(id)
                    ),
                );
            }
            if let Err(e) = check_scalar(&format!("der({})", name_of(id)), x) {
                return self.param_error(F, e);
            }
            match id {
                Id::Ag => self.d.der_ag = x,
                Id::Fext => self.d.der_fext = x,
                _ => return self.error(F, format!("{} is not a Real input", name_of(id))),
            }
        }
        Status::Ok
    }

    /// fmi2DoStep.
    pub fn do_step(&mut self, t: f64, h: f64) -> Status {
        const F: &str = "fmi2DoStep";
        if let Err(s) = self.require(F, &[Phase::StepComplete]) {
            return s;
        }
        let now = self.d.time;
        if !t.is_finite() || (t - now).abs() > 1e-9 * now.abs().max(1.0) {
            return self.error(
                F,
                format!("currentCommunicationPoint = {t} does not match the FMU's time {now}"),
            );
        }
        if !(h >= 0.0 && h.is_finite()) {
            return self.error(
                F,
                format!("communicationStepSize = {h} is not allowed: it must be finite and >= 0"),
            );
        }
        if let Some(stop) = self.d.stop_time {
            if t + h > stop + 1e-9 * stop.abs().max(1.0) {
                return self.error(
                    F,
                    format!("stepping to {} would pass stopTime = {stop}", t + h),
                );
            }
        }
        let extra = Excitation {
            ag: self.d.ag,
            ag_rate: self.d.der_ag,
            fext: self.d.fext,
            fext_rate: self.d.der_fext,
        };
        let at_start = self.next_excitation();
        let sim = self.d.sim.as_mut().expect("built at initialization");
        let t_end = (t + h - self.d.start_time).max(sim.time());
        // Bounded work: refuse up front what would run for minutes or more.
        let samples = self
            .record
            .as_ref()
            .map_or(0, |(_, gm)| gm.samples_in(sim.time(), t_end));
        if let Some(message) = limits::work_error(
            t_end - sim.time(),
            sim.max_internal_step(),
            samples,
            sim.step_weight(),
        ) {
            return self.error(F, message);
        }
        // A jump of an input acts at the communication point, where the
        // outputs already showed it: tSwitch watches for switches after it.
        let jump = if at_start.fext != sim.fext_now() {
            sim.advance(sim.time(), &at_start)
        } else {
            Ok(())
        };
        let result = jump.and_then(|()| {
            sim.watch_switches();
            match &self.record {
                Some((_, gm)) => {
                    record::advance_with_record(sim, t_end, gm, self.d.values.record_scale, &extra)
                }
                None => sim.advance(t_end, &extra),
            }
        });
        self.outputs = None;
        let first_switch = sim.first_switch();
        let fext_end = sim.fext_now();
        // Never fmi2OK with a NaN or an infinity in an output.
        let bad = limits::non_finite_message(&sim.outputs(), self.d.start_time);
        match (result, bad) {
            (Ok(()), None) => {
                // The inputs stand where their slopes took them: the outputs
                // at t + h see them there, and an input left alone is held at
                // that value (Fext exactly as the engine ended the step, so
                // the next step sees no jump).
                self.d.ag += self.d.der_ag * h;
                self.d.fext = fext_end;
                self.d.der_ag = 0.0;
                self.d.der_fext = 0.0;
                self.d.time = t + h;
                self.d.t_switch = if first_switch.is_nan() {
                    t + h
                } else {
                    (first_switch + self.d.start_time).min(t + h)
                };
                Status::Ok
            }
            (result, bad) => {
                self.d.phase = Phase::Error;
                let message =
                    bad.unwrap_or_else(|| result.err().map(|e| e.to_string()).unwrap_or_default());
                self.error(F, message)
            }
        }
    }

    /// `fmi2LastSuccessfulTime`.
    pub fn last_successful_time(&self) -> f64 {
        self.d.time
    }

    // ---- saved states ----

    /// fmi2GetFMUstate.
    pub fn save(&mut self) -> Result<SavedState, Status> {
        self.require(
            "fmi2GetFMUstate",
            &[
                Phase::Instantiated,
                Phase::InitializationMode,
                Phase::StepComplete,
                Phase::Terminated,
            ],
        )?;
        Ok(SavedState(self.d.clone()))
    }

    /// fmi2SetFMUstate (re-reads the record if the state names another).
    pub fn restore(&mut self, state: &SavedState) -> Status {
        const F: &str = "fmi2SetFMUstate";
        if let Err(s) = self.require(
            F,
            &[
                Phase::Instantiated,
                Phase::InitializationMode,
                Phase::StepComplete,
                Phase::Terminated,
                Phase::Error,
            ],
        ) {
            return s;
        }
        self.d = state.0.clone();
        self.outputs = None;
        if self.d.sim.is_some() {
            if let Err(s) = self.load_record(F) {
                self.d.phase = Phase::Error;
                return s;
            }
        }
        Status::Ok
    }

    /// The explicit, versioned byte format of a saved state.
    pub fn serialize(state: &SavedState) -> Vec<u8> {
        let d = &state.0;
        let mut w = ByteWriter::default();
        w.buf.extend_from_slice(STATE_MAGIC);
        w.u32(STATE_VERSION);
        w.u8(d.phase as u8);
        w.f64s(&[d.start_time, d.stop_time.unwrap_or(f64::NAN), d.time]);
        w.f64(d.t_switch);
        let v = &d.values;
        w.str(&v.record_file);
        w.f64s(&[v.record_scale, v.max_step, v.friction_eps]);
        w.u32(v.solver as u32);
        w.f64s(&[d.ag, d.fext, d.der_ag, d.der_fext]);
        // The parameters travel with the simulator when it exists; before
        // initialization they are written on their own.
        match &d.sim {
            Some(sim) => {
                w.u8(1);
                sim.write_state(&mut w);
            }
            None => {
                w.u8(0);
                v.params.write(&mut w);
            }
        }
        w.buf
    }

    /// Reads the byte format of [`Instance::serialize`].
    pub fn deserialize(bytes: &[u8]) -> Result<SavedState, SnapshotError> {
        let magic = bytes.get(..8).ok_or("the saved state is truncated")?;
        if magic != STATE_MAGIC {
            return Err("not a StackedLiveLoad state".into());
        }
        let mut r = ByteReader::new(&bytes[8..]);
        let version = r.u32()?;
        if version != STATE_VERSION {
            return Err(format!(
                "state format version {version} is not supported (this FMU reads {STATE_VERSION})"
            ));
        }
        let phase = match r.u8()? {
            0 => Phase::Instantiated,
            1 => Phase::InitializationMode,
            2 => Phase::StepComplete,
            3 => Phase::Terminated,
            4 => Phase::Error,
            x => return Err(format!("unknown phase {x}")),
        };
        let (start_time, stop, time) = (r.f64()?, r.f64()?, r.f64()?);
        let t_switch = r.f64()?;
        let mut values = ParameterValues {
            record_file: r.str()?,
            record_scale: r.f64()?,
            max_step: r.f64()?,
            friction_eps: r.f64()?,
            solver: r.u32()? as i32,
            ..ParameterValues::default()
        };
        let (ag, fext, der_ag, der_fext) = (r.f64()?, r.f64()?, r.f64()?, r.f64()?);
        let sim = match r.u8()? {
            1 => {
                let sim = Solver::read_state(&mut r)?;
                values.params = sim.params().clone();
                Some(sim)
            }
            _ => {
                values.params = Params::read(&mut r)?;
                None
            }
        };
        if !r.is_empty() {
            return Err("the saved state has trailing bytes".into());
        }
        let d = Dynamic {
            phase,
            start_time,
            stop_time: (!stop.is_nan()).then_some(stop),
            time,
            t_switch,
            values,
            ag,
            fext,
            der_ag,
            der_fext,
            sim,
        };
        check_saved(&d)?;
        Ok(SavedState(d))
    }
}

fn name_of(id: Id) -> String {
    id.name()
}

/// The field of `o` behind a Real output computed by the simulator.
fn real_output(o: &Outputs, id: Id) -> Option<f64> {
    let block = |j: usize, xs: &[f64; MAX_BLOCKS]| xs[j - 1];
    Some(match id {
        Id::Up => o.up,
        Id::Vp => o.vp,
        Id::ApAbs => o.ap_abs,
        Id::BaseShear => o.base_shear,
        Id::PeakUp => o.peak_up,
        Id::PeakApAbs => o.peak_ap_abs,
        Id::Einput => o.e_input,
        Id::Ekinetic => o.e_kinetic,
        Id::Estrain => o.e_strain,
        Id::Eviscous => o.e_viscous,
        Id::Efriction => o.e_friction,
        Id::Ub(j) => block(j, &o.ub),
        Id::Vb(j) => block(j, &o.vb),
        Id::Slip(j) => block(j, &o.slip),
        Id::AbAbs(j) => block(j, &o.ab_abs),
        Id::F(j) => block(j, &o.force),
        Id::PeakSlip(j) => block(j, &o.peak_slip),
        _ => return None,
    })
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
