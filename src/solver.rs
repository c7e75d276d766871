//! The FMU's `solver` parameter: which of the three methods computes the
//! scene. 1 and 2 are the exact stick/slip engine with located or step-end
//! switching; 3 is the tanh-regularized baseline (not a recommended mode).

use crate::baselines::regularized::RegularizedSimulator;
use crate::physics::engine::{Excitation, Outputs, PieceSource, SimError, Simulator};
use crate::physics::params::{check_scalar, Method, ParamError, Params, Settings};
use crate::physics::snapshot::{ByteReader, ByteWriter, SnapshotError};

/// Anything that advances in time under a linear excitation piece.
pub trait Stepper {
    /// Current time (s).
    fn time(&self) -> f64;
    /// Advances to `t_end` under an excitation linear over `[now, t_end]`.
    fn advance(&mut self, t_end: f64, exc: &Excitation) -> Result<(), SimError>;

    /// Advances through the consecutive linear pieces of a [`PieceSource`]
    /// (end time, excitation at the piece start), as `advance` on each in turn.
    fn advance_source(&mut self, mut pieces: impl PieceSource) -> Result<(), SimError> {
        while let Some((t_end, exc)) = pieces.next_piece() {
            self.advance(t_end, &exc)?;
        }
        Ok(())
    }
}

impl Stepper for Simulator {
    fn time(&self) -> f64 {
        Simulator::time(self)
    }
    fn advance(&mut self, t_end: f64, exc: &Excitation) -> Result<(), SimError> {
        Simulator::advance(self, t_end, exc)
    }
    fn advance_source(&mut self, pieces: impl PieceSource) -> Result<(), SimError> {
        Simulator::advance_source(self, pieces)
    }
}

impl Stepper for RegularizedSimulator {
    fn time(&self) -> f64 {
        RegularizedSimulator::time(self)
    }
    fn advance(&mut self, t_end: f64, exc: &Excitation) -> Result<(), SimError> {
        RegularizedSimulator::advance(self, t_end, exc)
    }
}

/// The `solver` choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolverKind {
    /// 1: the exact engine, switches located on the exact motion (the default).
    EventLocated = 1,
    /// 2: RK4 switching modes at step ends only (the paper's approach; a baseline).
    StepEnd = 2,
    /// 3: friction regularized as `tanh(v / frictionEps)`, plain RK4.
    Regularized = 3,
}

impl SolverKind {
    /// The FMU's integer code.
    pub fn code(self) -> i32 {
        self as i32
    }

    /// The kind with FMU code `code`, if any.
    pub fn from_code(code: i32) -> Option<SolverKind> {
        match code {
            1 => Some(SolverKind::EventLocated),
            2 => Some(SolverKind::StepEnd),
            3 => Some(SolverKind::Regularized),
            _ => None,
        }
    }
}

/// Default regularization velocity of solver 3 (m/s).
pub const DEFAULT_FRICTION_EPS: f64 = 1e-3;

/// A built solver of any kind. (Not boxed: one per instance, and the
/// exact engine, the large variant, is the common one.)
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum Solver {
    /// Solvers 1 and 2.
    Exact(Simulator),
    /// Solver 3.
    Regularized(RegularizedSimulator),
}

impl Solver {
    /// Builds the scene with the chosen method. `max_step` (s) bounds the
    /// internal step (0 = automatic); for the regularized method see
    /// [`RegularizedSimulator::for_solver`].
    pub fn new(
        params: &Params,
        kind: SolverKind,
        max_step: f64,
        friction_eps: f64,
    ) -> Result<Solver, ParamError> {
        let method = match kind {
            SolverKind::StepEnd => Method::StepEnd,
            _ => Method::EventLocated,
        };
        let settings = Settings { method, max_step };
        settings.validate()?;
        if kind != SolverKind::Regularized {
            return Ok(Solver::Exact(Simulator::new(params, &settings)?));
        }
        Ok(Solver::Regularized(RegularizedSimulator::for_solver(
            params,
            max_step,
            friction_eps,
        )?))
    }

    /// The scene.
    pub fn params(&self) -> &Params {
        match self {
            Solver::Exact(s) => s.params(),
            Solver::Regularized(s) => s.params(),
        }
    }

    /// Largest internal step in use (s).
    pub fn max_internal_step(&self) -> f64 {
        match self {
            Solver::Exact(s) => s.max_internal_step(),
            Solver::Regularized(s) => s.step(),
        }
    }

    /// The cost of one internal step in steps of the exact engine (the
    /// work bound of [`crate::limits`]).
    pub fn step_weight(&self) -> f64 {
        match self {
            // Step-end switching has no fast path: measured 3 times slower
            // than the former RK4 default for the same steps (1.45 ms
            // against 0.47 ms, Criterion, 2-block scene).
            Solver::Exact(s) if s.settings().method == Method::StepEnd => 3.0,
            Solver::Exact(_) => 1.0,
            Solver::Regularized(s) => crate::limits::regularized_step_weight(s.params().n_blocks),
        }
    }

    /// All reported quantities at the current time.
    pub fn outputs(&self) -> Outputs {
        match self {
            Solver::Exact(s) => s.outputs(),
            Solver::Regularized(s) => s.outputs(),
        }
    }

    /// Sets the support's mobility ([`Simulator::set_support_mobility`]):
    /// checked for every solver, used by the exact ones (the regularized
    /// baseline has no prescribed support).
    pub fn set_support_mobility(&mut self, mobility: f64) -> Result<(), ParamError> {
        match self {
            Solver::Exact(s) => s.set_support_mobility(mobility),
            Solver::Regularized(_) => check_scalar("supportMobility", mobility),
        }
    }

    /// The external force now, as the last call left it (N).
    pub fn fext_now(&self) -> f64 {
        match self {
            Solver::Exact(s) => s.fext_now(),
            Solver::Regularized(s) => s.fext_now(),
        }
    }

    /// Holds `fext` from now on in place of the force the last step ended
    /// with, which differs from it by rounding only (no jump: nothing
    /// switches): a step of length 0 under it.
    pub fn hold_fext(&mut self, fext: f64) -> Result<(), SimError> {
        let now = self.time();
        match self {
            Solver::Exact(s) => {
                let ag = s.ag_now();
                s.advance(
                    now,
                    &Excitation {
                        ag,
                        fext,
                        ..Default::default()
                    },
                )
            }
            Solver::Regularized(s) => s.advance(
                now,
                &Excitation {
                    fext,
                    ..Default::default()
                },
            ),
        }
    }

    /// Starts watching for the first stick/slip switch after the current time.
    pub fn watch_switches(&mut self) {
        if let Solver::Exact(s) = self {
            s.watch_switches();
        }
    }

    /// Time of the first switch since [`Solver::watch_switches`], NaN if
    /// none (always NaN for the regularized method, which has no switches).
    pub fn first_switch(&self) -> f64 {
        match self {
            Solver::Exact(s) => s.first_switch(),
            Solver::Regularized(_) => f64::NAN,
        }
    }

    /// Writes the state with a tag for its kind.
    pub fn write_state(&self, w: &mut ByteWriter) {
        match self {
            Solver::Exact(s) => {
                w.u8(1);
                s.write_state(w);
            }
            Solver::Regularized(s) => {
                w.u8(3);
                s.write_state(w);
            }
        }
    }

    /// Reads a state written by [`Solver::write_state`].
    pub fn read_state(r: &mut ByteReader) -> Result<Solver, SnapshotError> {
        match r.u8()? {
            1 => Ok(Solver::Exact(Simulator::read_state(r)?)),
            3 => Ok(Solver::Regularized(RegularizedSimulator::read_state(r)?)),
            x => Err(format!("unknown solver tag {x} in the saved state")),
        }
    }
}

impl Stepper for Solver {
    fn time(&self) -> f64 {
        match self {
            Solver::Exact(s) => s.time(),
            Solver::Regularized(s) => s.time(),
        }
    }
    fn advance(&mut self, t_end: f64, exc: &Excitation) -> Result<(), SimError> {
        match self {
            Solver::Exact(s) => s.advance(t_end, exc),
            Solver::Regularized(s) => s.advance(t_end, exc),
        }
    }
    fn advance_source(&mut self, pieces: impl PieceSource) -> Result<(), SimError> {
        match self {
            Solver::Exact(s) => s.advance_source(pieces),
            Solver::Regularized(s) => Stepper::advance_source(s, pieces),
        }
    }
}
