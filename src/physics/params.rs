//! User-facing parameters of a scene and of the solver, with validation.

use std::fmt;

/// Largest stack height supported (blocks above the structure).
pub const MAX_BLOCKS: usize = 8;
/// Bodies: the structure (index 0) and up to `MAX_BLOCKS` blocks.
pub const MAX_BODIES: usize = MAX_BLOCKS + 1;

/// What block 1 rests on (see `shared/MODEL.md`, "A stack on a support
/// whose motion is prescribed").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Support {
    /// The SDOF structure (body 0: mass `mp`, period `Tp`, damping `zeta`)
    /// on the ground, whose absolute acceleration is the input `ag`.
    #[default]
    Structure,
    /// A support whose absolute acceleration is the input `ag` (the floor of
    /// another model): body 0 is pinned to it (no spring, no damper, no mass
    /// of its own); `Tp` and `zeta` are unused, `Fext` must be 0, and block
    /// j's mass is `alpha[j] * mp`.
    Prescribed,
}

/// Physical description of a scene, in the paper's terms (see `shared/MODEL.md`).
///
/// Arrays are indexed by block / interface number minus one: `alpha[0]` is
/// block 1, `mus[0]` the interface between the structure and block 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    /// Number of blocks in the stack, 0..=`MAX_BLOCKS`.
    pub n_blocks: usize,
    /// Mass of the primary structure (kg).
    pub mp: f64,
    /// Period of the bare structure (s).
    pub tp: f64,
    /// Damping ratio of the bare structure.
    pub zeta: f64,
    /// Gravitational acceleration (m/s^2).
    pub g: f64,
    /// Mass ratio of block j to the structure, `m_j / mp`.
    pub alpha: [f64; MAX_BLOCKS],
    /// Static friction coefficient of interface j (below block j).
    pub mus: [f64; MAX_BLOCKS],
    /// Kinetic friction coefficient of interface j.
    pub muk: [f64; MAX_BLOCKS],
    /// What block 1 rests on.
    pub support: Support,
}

impl Default for Params {
    /// The paper's Fig. 5a scene: Tp 0.5 s, 5 % damping, alpha 0.25 + 0.25,
    /// mu_1 = 0.1, mu_2 = 0.05 (static = kinetic), on a 1000 kg structure.
    fn default() -> Self {
        let mut alpha = [0.25; MAX_BLOCKS];
        let mut mu = [0.1; MAX_BLOCKS];
        alpha[1] = 0.25;
        mu[1] = 0.05;
        Params {
            n_blocks: 2,
            mp: 1000.0,
            tp: 0.5,
            zeta: 0.05,
            g: 9.81,
            alpha,
            mus: mu,
            muk: mu,
            support: Support::Structure,
        }
    }
}

/// A parameter outside its allowed range. `field` is the variable's public
/// name (as in the FMU, e.g. `alpha[2]`).
#[derive(Clone, Debug, PartialEq)]
pub struct ParamError {
    /// The variable's public name.
    pub field: String,
    /// The value given.
    pub value: f64,
    /// The allowed range, in words.
    pub allowed: String,
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} = {} is not allowed: it must be {}",
            self.field,
            crate::limits::Num(self.value),
            self.allowed
        )
    }
}

impl std::error::Error for ParamError {}

fn check(field: &str, value: f64, ok: bool, allowed: &'static str) -> Result<(), ParamError> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(ParamError {
            field: field.to_string(),
            value,
            allowed: allowed.to_string(),
        })
    }
}

/// The allowed range of each scalar field: a physical range wide enough for
/// any real scene that keeps the work of a simulation finite and every
/// derived quantity (stiffness, normal forces, energies) far from overflow.
/// `(name, low, high, in words)`; both ends are included unless the words say
/// otherwise. See `docs/robustness.md`.
pub const RANGES: [(&str, f64, f64, &str); 14] = [
    ("mp", 1e-3, 1e12, "finite, from 1e-3 to 1e12 (kg)"),
    ("Tp", 1e-3, 1e3, "finite, from 1e-3 to 1e3 (s)"),
    ("zeta", 0.0, 1.0, "finite, >= 0 and < 1"),
    ("g", 1e-3, 1e3, "finite, from 1e-3 to 1e3 (m/s2)"),
    ("alpha", 1e-9, 1e9, "finite, from 1e-9 to 1e9"),
    ("mus", 0.0, 1e9, "finite, from 0 to 1e9"),
    ("muk", 0.0, 1e9, "finite, from 0 to 1e9"),
    ("frictionEps", 1e-7, 1e3, "finite, from 1e-7 to 1e3 (m/s)"),
    ("recordScale", -1e3, 1e3, "finite, from -1e3 to 1e3"),
    // Inputs: far beyond any physical value, and low enough that no energy
    // or displacement they cause can overflow within the work bound.
    ("ag", -1e6, 1e6, "finite, from -1e6 to 1e6 (m/s2)"),
    ("Fext", -1e18, 1e18, "finite, from -1e18 to 1e18 (N)"),
    ("der(ag)", -1e9, 1e9, "finite, from -1e9 to 1e9 (m/s3)"),
    ("der(Fext)", -1e21, 1e21, "finite, from -1e21 to 1e21 (N/s)"),
    // d(floor acceleration) / d(floor force) of a prescribed support's
    // partner (1 / its floor mass): 0 is a support that nothing moves.
    ("supportMobility", 0.0, 1e9, "finite, from 0 to 1e9 (1/kg)"),
];

/// Smallest positive `maxStep` (s); 0 selects the automatic step.
pub const MIN_MAX_STEP: f64 = 1e-7;

/// The range of one scalar field, by its public name (`alpha[2]` is checked
/// as `alpha`). Cross-field rules (muk <= mus) are in [`Params::validate`].
#[inline] // (constant names: the lookup folds away)
pub fn check_scalar(field: &str, value: f64) -> Result<(), ParamError> {
    let base = field.split('[').next().unwrap_or(field);
    if base == "maxStep" {
        let ok = value == 0.0 || value >= MIN_MAX_STEP;
        return check(field, value, ok, "0 (automatic) or finite and >= 1e-7 (s)");
    }
    match RANGES.iter().find(|r| r.0 == base) {
        // zeta = 1 is critical damping: excluded.
        Some(&(_, lo, hi, allowed)) => {
            let ok = value >= lo && (value < hi || (value == hi && base != "zeta"));
            check(field, value, ok, allowed)
        }
        None => check(field, value, true, "finite"),
    }
}

impl Params {
    /// Checks every field; the first one out of range is reported.
    pub fn validate(&self) -> Result<(), ParamError> {
        let (n, on_support) = (self.n_blocks, self.support == Support::Prescribed);
        check(
            "nBlocks",
            n as f64,
            n <= MAX_BLOCKS,
            "an integer from 0 to 8",
        )?;
        let allowed = "an integer from 1 to 8 on a prescribed support (a stack of no block has \
                       nothing to compute)";
        check("nBlocks", n as f64, n > 0 || !on_support, allowed)?;
        check_scalar("mp", self.mp)?;
        check_scalar("Tp", self.tp)?;
        check_scalar("zeta", self.zeta)?;
        check_scalar("g", self.g)?;
        for j in 0..self.n_blocks {
            let (mus, muk) = (self.mus[j], self.muk[j]);
            let same = "finite, >= 0 and <= mus of the same interface";
            // The first error in this order; the interface's number added to its field only then.
            (check_scalar("alpha", self.alpha[j]).and(check_scalar("mus", mus)))
                .and(check_scalar("muk", muk).and(check("muk", muk, muk <= mus, same)))
                .map_err(|e| ParamError {
                    field: format!("{}[{}]", e.field, j + 1),
                    ..e
                })?;
        }
        Ok(())
    }
}

/// How mode switches are handled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// The exact default: the exact motion of each mode, every switch
    /// located on it (docs/model-and-numerics.md, "Method").
    EventLocated,
    /// Guards are checked only at internal step ends, as in the paper
    /// (first order at every switch). A baseline for comparisons.
    StepEnd,
}

/// Solver settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// How mode switches are handled.
    pub method: Method,
    /// Largest internal step (s); 0: automatic. The exact default stays
    /// exact at any value (a shorter substep only costs time); for the RK4
    /// baseline it replaces the automatic accuracy bound
    /// ([`crate::baselines::auto_step`]) within the RK4 stability bound
    /// of the bare structure.
    pub max_step: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            method: Method::EventLocated,
            max_step: 0.0,
        }
    }
}

impl Settings {
    /// Checks `max_step`.
    pub fn validate(&self) -> Result<(), ParamError> {
        check_scalar("maxStep", self.max_step)
    }
}
