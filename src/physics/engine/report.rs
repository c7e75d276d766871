//! What the engine reports: its outputs, counters and errors.

use super::*;
use crate::limits::Num;

/// An error while advancing.
#[derive(Clone, Debug, PartialEq)]
pub enum SimError {
    /// An input was NaN or infinite.
    BadInput {
        /// The input's name (`ag`, `der(ag)`, `Fext`, `der(Fext)`, `t_end`).
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// `t_end` is before the current time.
    BadTime {
        /// The simulator's time.
        now: f64,
        /// The time asked for.
        t_end: f64,
    },
    /// The state left the finite numbers (cannot happen with the step bound;
    /// reported rather than propagated as NaN).
    NonFinite {
        /// When it happened.
        t: f64,
    },
    /// The call's work budget ([`Simulator::set_work_budget`]) is spent.
    WorkLimit {
        /// The simulator's time when it stopped (a substep's end).
        t: f64,
    },
    /// A non-zero `Fext` (or slope) on a prescribed support, which has no
    /// structure for it to act on.
    NoForceOnSupport {
        /// `Fext` or `der(Fext)`.
        name: &'static str,
        /// The value given.
        value: f64,
    },
}

impl std::fmt::Display for SimError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SimError::BadInput { name, value } => {
                write!(
                    f,
                    "{name} = {} is not allowed: it must be finite",
                    Num(*value)
                )
            }
            SimError::BadTime { now, t_end } => write!(
                f,
                "cannot step to t = {} s: the simulation is already at t = {} s",
                Num(*t_end),
                Num(*now)
            ),
            SimError::NonFinite { t } => {
                write!(f, "the state became non-finite at t = {} s", Num(*t))
            }
            SimError::WorkLimit { t } => write!(
                f,
                "stopped at t = {} s: the stick/slip switches spent the work bound of one call \
                 ({:e} internal steps' worth)",
                Num(*t),
                crate::limits::MAX_STEPS_PER_CALL
            ),
            SimError::NoForceOnSupport { name, value } => write!(
                f,
                "{name} = {} is not allowed: it must be 0 on a prescribed support \
                 (there is no structure for an external force to act on)",
                Num(*value)
            ),
        }
    }
}

impl std::error::Error for SimError {}

/// Counters of what the solver did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// Internal substeps taken (a substep's stretches between events count separately).
    pub steps: u64,
    /// Mode switches.
    pub events: u64,
    /// Resolutions where no assignment met the contact law within tolerance.
    pub inconsistent: u64,
    /// Guards muted by the chatter guard (switched at the step end instead).
    pub muted: u64,
    /// Resolutions where several assignments were consistent (possible only
    /// with mus > muk) and the selection rule chose.
    pub ambiguous: u64,
}

/// Everything the product reports at the current time. Block arrays are
/// indexed by block number minus one; entries beyond `n_blocks` are 0.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Outputs {
    /// Time (s).
    pub t: f64,
    /// Structure displacement relative to the support (m).
    pub up: f64,
    /// Structure velocity relative to the support (m/s).
    pub vp: f64,
    /// Structure absolute acceleration (m/s2).
    pub ap_abs: f64,
    /// Force on the support, `k up + c vp` (N).
    pub base_shear: f64,
    /// Block displacements relative to the support (m).
    pub ub: [f64; MAX_BLOCKS],
    /// Block velocities relative to the support (m/s).
    pub vb: [f64; MAX_BLOCKS],
    /// Block displacements relative to the body below (m).
    pub slip: [f64; MAX_BLOCKS],
    /// Block absolute accelerations (m/s2).
    pub ab_abs: [f64; MAX_BLOCKS],
    /// Friction force of interface j on block j (N).
    pub force: [f64; MAX_BLOCKS],
    /// Interface j is stuck.
    pub stuck: [bool; MAX_BLOCKS],
    /// Largest |up| so far, between steps too (m).
    pub peak_up: f64,
    /// Largest |slip| of each interface so far (m).
    pub peak_slip: [f64; MAX_BLOCKS],
    /// Largest |ap_abs| so far (m/s2).
    pub peak_ap_abs: f64,
    /// Input energy in relative coordinates (J).
    pub e_input: f64,
    /// Kinetic energy in relative coordinates (J).
    pub e_kinetic: f64,
    /// Strain energy of the structure's spring (J).
    pub e_strain: f64,
    /// Energy dissipated by the damper (J).
    pub e_viscous: f64,
    /// Energy dissipated by friction, all interfaces (J).
    pub e_friction: f64,
    /// Energy dissipated by friction at each interface (J).
    pub e_friction_of: [f64; MAX_BLOCKS],
    /// Mode switches so far (for the regularized baseline: internal steps
    /// over which a relative velocity changed sign).
    pub n_events: u64,
    /// Mode resolutions decided by the mus > muk selection rule.
    pub n_ambiguous: u64,
    /// The force the stack puts on body 0 along +x, `-F_1` (N): a model
    /// whose floor carries the stack applies it to that floor.
    pub floor_force: f64,
    /// Mass of the blocks stuck to body 0 now (body 0 excluded), kg.
    pub attached_mass: f64,
    /// `floor_force + attached_mass * apAbs` (N): the friction force of the
    /// first slipping interface above the attached blocks on them, or
    /// `floor_force` while interface 1 slips; constant between switches.
    pub sliding_force: f64,
}

impl Outputs {
    /// Input energy minus the stored and dissipated energy.
    pub fn energy_residual(&self) -> f64 {
        self.e_input - (self.e_kinetic + self.e_strain + self.e_viscous + self.e_friction)
    }
}

impl Simulator {
    /// All reported quantities at the current time.
    pub fn outputs(&self) -> Outputs {
        let s = &self.sys;
        let d = &self.dynamics;
        let load0 = self.load0();
        let ap_abs = d.accel(0, load0);
        // The running peaks shown are never below the values shown, which
        // come from other sums (rounding apart) or, for the acceleration,
        // from inputs set since (a jump of Fext, or of a support's `ag`).
        let mut o = Outputs {
            t: self.t,
            up: self.u[0],
            vp: self.v[0],
            ap_abs,
            base_shear: s.k * self.u[0] + s.c * self.v[0],
            peak_up: self.peak_u0.max(self.u[0].abs()),
            peak_ap_abs: self.peak_a0.max(ap_abs.abs()),
            e_input: self.e_input,
            e_strain: 0.5 * s.k * self.u[0] * self.u[0],
            e_viscous: self.e_viscous,
            n_events: self.stats.events,
            n_ambiguous: self.stats.ambiguous,
            ..Outputs::default()
        };
        o.e_kinetic = (0..=s.n)
            .map(|i| 0.5 * s.mass[i] * self.v[i] * self.v[i])
            .sum();
        for j in 1..=s.n {
            let b = j - 1;
            o.ub[b] = self.u[j];
            o.vb[b] = self.v[j];
            o.slip[b] = self.u[j] - self.u[j - 1];
            o.ab_abs[b] = d.accel(d.cluster_of[j], load0);
            o.force[b] = if s.is_free(j) {
                0.0
            } else {
                d.force(j, &self.mode, load0)
            };
            o.stuck[b] = self.mode.is_stuck(j);
            o.peak_slip[b] = self.peak_slip[j].max(o.slip[b].abs());
            o.e_friction_of[b] = self.e_friction[j];
        }
        o.e_friction = o.e_friction_of.iter().sum();
        o.floor_force = d.floor_force(&self.mode, load0);
        o.attached_mass = d.attached_mass(&self.mode);
        o.sliding_force = d.sliding_force(&self.mode);
        o
    }
}
