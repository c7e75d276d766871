//! Time integration: RK4 on the reduced system of the current mode, with
//! stick/slip events located inside the step (or, as a baseline, checked at
//! step ends only), running peaks and the energy balance.
//!
//! The state is kept per body (`u`, `v` relative to the support); a step
//! packs one displacement and one velocity per cluster plus the energy
//! quadratures into a short vector, integrates it, and moves every body of a
//! cluster by its cluster's increment.

use crate::physics::hermite;
use crate::physics::mode::{self, Contact, Dynamics, Mode, ResolveRequest};
use crate::physics::params::{Method, ParamError, Params, Settings, MAX_BLOCKS, MAX_BODIES};
use crate::physics::snapshot::{ByteReader, ByteWriter, SnapshotError};
use crate::physics::system::System;

mod exact_map;
mod folded;
mod lean;
mod rk4_map;
mod state_check;

/// Excitation over one interval, linear in time from the interval start:
/// `ag(t) = ag + ag_rate (t - t_start)`, and likewise the external force.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Excitation {
    /// Ground (support) acceleration at the interval start (m/s^2).
    pub ag: f64,
    /// Its slope over the interval (m/s^3); 0 holds it constant.
    pub ag_rate: f64,
    /// External force on the structure at the interval start (N).
    pub fext: f64,
    /// Its slope (N/s).
    pub fext_rate: f64,
}

impl Excitation {
    /// Checks that a step from `now` to `t_end` under this piece is possible:
    /// every value finite and time not going back.
    #[inline]
    pub fn check(&self, now: f64, t_end: f64) -> Result<(), SimError> {
        // A finite sum means every value is finite. A sum that is not (a
        // bad value, or finite ones overflowing) goes to the detailed check.
        let sum = self.ag + self.ag_rate + self.fext + self.fext_rate + t_end;
        if sum.is_finite() && t_end >= now {
            return Ok(());
        }
        self.check_each(now, t_end)
    }

    #[cold]
    fn check_each(&self, now: f64, t_end: f64) -> Result<(), SimError> {
        for (name, value) in [
            ("ag", self.ag),
            ("der(ag)", self.ag_rate),
            ("Fext", self.fext),
            ("der(Fext)", self.fext_rate),
            ("t_end", t_end),
        ] {
            if !value.is_finite() {
                return Err(SimError::BadInput { name, value });
            }
        }
        if t_end < now {
            return Err(SimError::BadTime { now, t_end });
        }
        Ok(())
    }
}

/// One linear piece of excitation from `t_ref` to `t_end`, cut into `n`
/// equal substeps of `h`; `i` is the next substep to take (1-based).
#[derive(Clone, Copy, Debug)]
struct Piece {
    exc: Excitation,
    t_ref: f64,
    t_end: f64,
    n: usize,
    h: f64,
    i: usize,
}

impl Piece {
    fn new(t_ref: f64, t_end: f64, exc: &Excitation, h_max: f64) -> Piece {
        let length = t_end - t_ref;
        let (n, h) = if length > 0.0 && length <= h_max {
            (1, length)
        } else if length > 0.0 {
            let n = substeps(length, h_max);
            (n as usize, length / n)
        } else {
            (0, 0.0)
        };
        Piece {
            exc: *exc,
            t_ref,
            t_end,
            n,
            h,
            i: 1,
        }
    }

    /// End time of substep `i` (the last one ends exactly at `t_end`).
    #[inline]
    fn end_of(&self, i: usize) -> f64 {
        if i == self.n {
            self.t_end
        } else {
            self.t_ref + i as f64 * self.h
        }
    }
}

/// RK4 step limit for the bare structure: stability needs `h ω_p < 2.83`
/// (undamped); we keep a margin.
pub const STABLE_H_OMEGA: f64 = 2.5;
/// Default accuracy bounds: `h ω_p <= 0.02` and `h <= 1.25 ms`. Measured
/// over periods 0.1–10 s on real, synthetic and spectrum-matched records, they
/// keep peaks within 1e-6 relative of the exact solution and the energy
/// residual below 1e-8 of the input (README, "Accuracy"). The absolute bound
/// matters at long periods and for records rich in short periods (matched
/// records): the structure's free response absorbs every change of slope of
/// the forcing, and the per-step error then no longer falls with ω.
pub const ACCURATE_H_OMEGA: f64 = 0.02;
/// See [`ACCURATE_H_OMEGA`].
pub const ACCURATE_MAX_STEP: f64 = 0.00125;
/// The default method's RK4 step inside the substeps the exact map cannot
/// take (those holding an event or a new interior peak): `h ω_p <= 0.005`
/// and `h <= 0.3125 ms`, a quarter of the former automatic step, so that
/// these few substeps stay below 1e-9 of the peaks (README, "Accuracy").
pub const FINE_H_OMEGA: f64 = 0.01;
/// See [`FINE_H_OMEGA`].
pub const FINE_MAX_STEP: f64 = 0.000625;
/// Event tolerance on time (s).
pub const EVENT_TIME_TOL: f64 = 1e-12;
/// Chatter guard: at most this many located events in one internal step;
/// past it the rest of the step switches at its end only.
pub const MAX_EVENTS_PER_STEP: u32 = 64;

/// Number of equal substeps of at most `h_max` in an interval of `length`.
/// A ratio within 1e-9 of an integer is that integer: the interval is a
/// difference of times carrying rounding, and must not cost an extra step.
pub fn substeps(length: f64, h_max: f64) -> f64 {
    let x = length / h_max * (1.0 - 1e-9);
    // `ceil` without a libm call on the baseline x86-64 target.
    if x < 1.0 {
        return 1.0;
    }
    if x >= 4.5e15 {
        return x.ceil();
    }
    let floor = x as i64 as f64;
    if floor < x {
        floor + 1.0
    } else {
        floor
    }
}

/// Largest internal step for the given settings and structure.
pub fn auto_step(settings: &Settings, omega_p: f64) -> f64 {
    let stable = STABLE_H_OMEGA / omega_p;
    if settings.max_step > 0.0 {
        settings.max_step.min(stable)
    } else {
        (ACCURATE_H_OMEGA / omega_p).min(ACCURATE_MAX_STEP)
    }
}

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
}

impl std::fmt::Display for SimError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SimError::BadInput { name, value } => {
                write!(f, "{name} = {value} is not allowed: it must be finite")
            }
            SimError::BadTime { now, t_end } => write!(
                f,
                "cannot step to t = {t_end} s: the simulation is already at t = {now} s"
            ),
            SimError::NonFinite { t } => write!(f, "the state became non-finite at t = {t} s"),
        }
    }
}

impl std::error::Error for SimError {}

/// Counters of what the solver did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// Internal RK4 steps accepted (segments between events count separately).
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
}

impl Outputs {
    /// Input energy minus the stored and dissipated energy.
    pub fn energy_residual(&self) -> f64 {
        self.e_input - (self.e_kinetic + self.e_strain + self.e_viscous + self.e_friction)
    }
}

/// The structure's cluster during a step: displacement, velocity, and the
/// input and viscous work done on it since the step start.
type Structure = [f64; 4];

/// RK4 of the structure's cluster in one mode under one excitation piece:
/// (u0, v0) plus the input and viscous work, as one short vector.
#[derive(Clone, Copy, Debug)]
struct StructureRk4 {
    k: f64,
    c: f64,
    mass0: f64,
    inv_mass0: f64,
    slip_load0: f64,
    exc: Excitation,
    t_ref: f64,
}

impl StructureRk4 {
    fn new(sys: &System, d: &Dynamics, exc: &Excitation, t_ref: f64) -> StructureRk4 {
        StructureRk4 {
            k: sys.k,
            c: sys.c,
            mass0: d.mass[0],
            inv_mass0: d.inv_mass0,
            slip_load0: d.slip_load[0],
            exc: *exc,
            t_ref,
        }
    }

    /// (ag, fext) at `t`.
    #[inline]
    fn inputs(&self, t: f64) -> (f64, f64) {
        let dt = t - self.t_ref;
        (
            self.exc.ag + self.exc.ag_rate * dt,
            self.exc.fext + self.exc.fext_rate * dt,
        )
    }

    /// Absolute acceleration of the structure's cluster at a state.
    #[inline]
    fn accel(&self, fext: f64, u0: f64, v0: f64) -> f64 {
        (self.slip_load0 + fext - self.k * u0 - self.c * v0) * self.inv_mass0
    }

    /// Absolute acceleration of the structure and its time derivative at `t`.
    #[inline]
    fn accel_and_jerk(&self, t: f64, u0: f64, v0: f64) -> (f64, f64) {
        let (ag, fext) = self.inputs(t);
        let a = self.accel(fext, u0, v0);
        let jerk = (self.exc.fext_rate - self.k * v0 - self.c * (a - ag)) * self.inv_mass0;
        (a, jerk)
    }

    /// Rates of (u0, v0, input work, viscous work).
    #[inline]
    fn rates(&self, t: f64, u0: f64, v0: f64) -> Structure {
        let (ag, fext) = self.inputs(t);
        let a = self.accel(fext, u0, v0) - ag;
        [v0, a, (fext - ag * self.mass0) * v0, self.c * v0 * v0]
    }

    /// One RK4 step of length `tau` from (u, v) at `t0`; the work terms are
    /// the increments over the step.
    #[inline]
    fn step(&self, t0: f64, u: f64, v: f64, tau: f64) -> Structure {
        let k1 = self.rates(t0, u, v);
        let k2 = self.rates(t0 + 0.5 * tau, u + 0.5 * tau * k1[0], v + 0.5 * tau * k1[1]);
        let k3 = self.rates(t0 + 0.5 * tau, u + 0.5 * tau * k2[0], v + 0.5 * tau * k2[1]);
        let k4 = self.rates(t0 + tau, u + tau * k3[0], v + tau * k3[1]);
        let w = tau / 6.0;
        let sum = |i: usize| w * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
        [u + sum(0), v + sum(1), sum(2), sum(3)]
    }
}

/// A cluster above the structure's over a step of length `h`: its absolute
/// acceleration is constant in the mode, so RK4 gives it exactly its Taylor
/// polynomial, and Simpson's rule, exact for it, its input work. Returns
/// (displacement increment, end velocity, input work) from velocity `v`.
#[inline]
fn upper_cluster_step(v: f64, accel: f64, mass: f64, ag0: f64, ag_rate: f64, h: f64) -> [f64; 3] {
    let rel = accel - ag0;
    let vm = v + 0.5 * h * rel - 0.125 * h * h * ag_rate;
    let v_end = v + h * rel - 0.5 * h * h * ag_rate;
    const SIXTH: f64 = 1.0 / 6.0;
    let du = h * (v + h * (0.5 * rel - h * ag_rate * SIXTH));
    let (agm, ag1) = (ag0 + 0.5 * h * ag_rate, ag0 + h * ag_rate);
    let work = -mass * h * SIXTH * (ag0 * v + 4.0 * agm * vm + ag1 * v_end);
    [du, v_end, work]
}

/// Moves every body with its cluster: the structure to `u0`, the other
/// bodies of its cluster by keeping their offset from it (so a body stuck
/// at zero slip stays at exactly zero slip), those of the other clusters by
/// their cluster's displacement increment `du[c]`; velocities to `v[c]`.
fn move_bodies(
    u: &mut [f64; MAX_BODIES],
    v: &mut [f64; MAX_BODIES],
    d: &Dynamics,
    n: usize,
    u0: f64,
    du: &[f64; MAX_BODIES],
    v_cluster: &[f64; MAX_BODIES],
) {
    let u0_before = u[0];
    u[0] = u0;
    v[0] = v_cluster[0];
    for i in 1..=n {
        let c = d.cluster_of[i];
        u[i] = if c == 0 {
            u0 + (u[i] - u0_before)
        } else {
            u[i] + du[c]
        };
        v[i] = v_cluster[c];
    }
}

/// One step's frozen ingredients: the mode, the excitation, and every
/// body's state at the step start `t0`.
///
/// Only the structure's cluster is integrated by RK4 stages. Every other
/// cluster has a constant absolute acceleration in the mode, so RK4 on it
/// reduces exactly to its Taylor polynomial (u cubic, v quadratic in time)
/// and RK4's quadrature of its input power `ag v` to Simpson's rule, exact for
/// that cubic: they are evaluated in closed form at any instant of the step.
struct Segment<'a> {
    sys: &'a System,
    mode: &'a Mode,
    dynamics: &'a Dynamics,
    exc: Excitation,
    rk: StructureRk4,
    t0: f64,
    ag0: f64,
    u: &'a [f64; MAX_BODIES],
    v: &'a [f64; MAX_BODIES],
}

impl Segment<'_> {
    fn start(&self) -> Structure {
        [self.u[0], self.v[0], 0.0, 0.0]
    }

    /// The structure's cluster after one RK4 step of length `tau` from `t0`.
    fn structure_after(&self, tau: f64) -> Structure {
        self.rk.step(self.t0, self.u[0], self.v[0], tau)
    }

    /// Velocity of cluster `c` at `t0 + tau`; `x` is the structure's cluster then.
    #[inline]
    fn velocity(&self, c: usize, x: &Structure, tau: f64) -> f64 {
        if c == 0 {
            x[1]
        } else {
            let d = self.dynamics;
            self.v[d.bottom[c]] + tau * (d.accel_const[c] - self.ag0)
                - 0.5 * tau * tau * self.exc.ag_rate
        }
    }

    /// Guard of interface j at `t0 + tau`: positive while its contact state holds.
    fn guard(&self, j: usize, x: &Structure, tau: f64) -> f64 {
        let d = self.dynamics;
        match self.mode.contact[j] {
            Contact::Stuck => {
                // Same slack as the resolver's consistency check, so that a
                // stick it accepted starts with a guard >= 0. In a stack with
                // equal friction coefficients the stick force of a block riding
                // on a sliding one is exactly mus N; without the slack rounding
                // alone would make it chatter.
                let (_, fext) = self.rk.inputs(self.t0 + tau);
                let load0 = Dynamics::structure_load(self.sys, x[0], x[1], fext);
                let f = d.force(j, self.mode, load0);
                mode::stick_capacity(self.sys, j) - f.abs()
            }
            Contact::SlipForward | Contact::SlipBackward => {
                let v_rel = self.velocity(d.cluster_of[j], x, tau)
                    - self.velocity(d.cluster_of[j - 1], x, tau);
                self.mode.contact[j].slip_sign() * v_rel
            }
            Contact::Free => f64::INFINITY,
        }
    }

    /// Guard j after `theta h`, re-stepping RK4 from the step start.
    fn guard_at(&self, j: usize, theta: f64, h: f64) -> f64 {
        self.guard(j, &self.structure_after(theta * h), theta * h)
    }

    /// Instant (as a fraction of `h`) where guard j crosses zero, bracketed
    /// between `a` (guard > 0) and `b` (guard <= 0); returns the right end of
    /// the final bracket, where the guard has already changed sign. Illinois
    /// iteration on RK4 re-steps from the step start.
    fn locate(&self, j: usize, h: f64, bracket: [(f64, f64); 2]) -> f64 {
        let [(mut a, mut ga), (mut b, mut gb)] = bracket;
        let tol = EVENT_TIME_TOL / h;
        let mut side = 0i8;
        for iter in 0..200 {
            if b - a <= tol {
                break;
            }
            let mut c = (a * gb - b * ga) / (gb - ga);
            // Fall back to bisection when the secant stalls or leaves the bracket.
            if !(c > a && c < b) || iter >= 60 {
                c = 0.5 * (a + b);
            }
            let gc = self.guard_at(j, c, h);
            if gc > 0.0 {
                a = c;
                ga = gc;
                if side == 1 {
                    gb *= 0.5;
                }
                side = 1;
            } else {
                b = c;
                gb = gc;
                if side == -1 {
                    ga *= 0.5;
                }
                side = -1;
            }
        }
        b
    }
}

/// The simulator: one scene, its state, peaks and energy terms.
#[derive(Clone, Debug)]
pub struct Simulator {
    params: Params,
    sys: System,
    settings: Settings,
    h_max: f64,
    /// The default method (automatic step, located events): substeps on the
    /// exact map, fine RK4 steps where it cannot prove a substep event-free.
    exact: bool,
    h_fine: f64,
    /// Exact maps in use (derived data only: rebuilt identically on demand).
    maps: exact_map::MapCache,
    t: f64,
    u: [f64; MAX_BODIES],
    v: [f64; MAX_BODIES],
    e_input: f64,
    e_viscous: f64,
    e_friction: [f64; MAX_BODIES],
    mode: Mode,
    dynamics: Dynamics,
    peak_u0: f64,
    peak_slip: [f64; MAX_BODIES],
    peak_a0: f64,
    ag_now: f64,
    fext_now: f64,
    last_event: f64,
    /// Switches are watched from this time on (`watch_switches`).
    watch_from: f64,
    /// The first switch at or after `watch_from` (NaN: none yet).
    first_switch: f64,
    stats: Stats,
}

impl Simulator {
    /// A scene at rest at t = 0. Fails with the first parameter out of range.
    pub fn new(params: &Params, settings: &Settings) -> Result<Simulator, ParamError> {
        settings.validate()?;
        let sys = System::new(params)?;
        let mode = Mode::all_stuck(&sys);
        let dynamics = Dynamics::new(&sys, &mode);
        let mut sim = Simulator {
            params: params.clone(),
            h_max: auto_step(settings, sys.omega_p),
            exact: settings.method == Method::EventLocated && settings.max_step == 0.0,
            h_fine: (FINE_H_OMEGA / sys.omega_p).min(FINE_MAX_STEP),
            maps: exact_map::MapCache::default(),
            sys,
            settings: *settings,
            t: 0.0,
            u: [0.0; MAX_BODIES],
            v: [0.0; MAX_BODIES],
            e_input: 0.0,
            e_viscous: 0.0,
            e_friction: [0.0; MAX_BODIES],
            mode,
            dynamics,
            peak_u0: 0.0,
            peak_slip: [0.0; MAX_BODIES],
            peak_a0: 0.0,
            ag_now: 0.0,
            fext_now: 0.0,
            last_event: f64::NAN,
            watch_from: f64::INFINITY,
            first_switch: f64::NAN,
            stats: Stats::default(),
        };
        sim.resolve_mode(0);
        sim.stats.events = 0;
        sim.last_event = f64::NAN;
        Ok(sim)
    }

    /// Back to rest at t = 0 with the same scene.
    pub fn reset(&mut self) {
        *self = Simulator::new(&self.params, &self.settings).expect("validated before");
    }

    /// Sets the displacement and velocity of every body (relative to the
    /// support, index 0 = structure) and resolves the mode. Peaks restart
    /// from this state; energies are zeroed.
    pub fn set_state(&mut self, u: &[f64], v: &[f64]) {
        let n = self.sys.n;
        self.u = [0.0; MAX_BODIES];
        self.v = [0.0; MAX_BODIES];
        self.u[..=n].copy_from_slice(&u[..=n]);
        self.v[..=n].copy_from_slice(&v[..=n]);
        self.e_input = 0.0;
        self.e_viscous = 0.0;
        self.e_friction = [0.0; MAX_BODIES];
        self.mode = Mode::all_stuck(&self.sys);
        for j in 1..=n {
            let dv = self.v[j] - self.v[j - 1];
            if !self.sys.is_free(j) && dv != 0.0 {
                self.mode.contact[j] = if dv > 0.0 {
                    Contact::SlipForward
                } else {
                    Contact::SlipBackward
                };
            }
        }
        self.resolve_mode(0);
        self.peak_u0 = self.u[0].abs();
        self.peak_slip = [0.0; MAX_BODIES];
        for j in 1..=n {
            self.peak_slip[j] = (self.u[j] - self.u[j - 1]).abs();
        }
        self.peak_a0 = self.structure_accel().abs();
    }

    /// Current time (s).
    pub fn time(&self) -> f64 {
        self.t
    }

    /// The external force now, as the last call left it (N).
    pub fn fext_now(&self) -> f64 {
        self.fext_now
    }

    /// Time of the latest mode switch (NaN before the first).
    pub fn last_event_time(&self) -> f64 {
        self.last_event
    }

    /// Starts watching for the first mode switch from the current time on
    /// (a switch that an input jump causes is taken before, by a call that
    /// advances by zero time).
    pub fn watch_switches(&mut self) {
        self.watch_from = self.t;
        self.first_switch = f64::NAN;
    }

    /// Time of the first mode switch since [`Simulator::watch_switches`]
    /// (NaN if none).
    pub fn first_switch(&self) -> f64 {
        self.first_switch
    }

    /// What the solver has done so far.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Current stick/slip mode.
    pub fn mode(&self) -> &Mode {
        &self.mode
    }

    /// The derived physical constants.
    pub fn system(&self) -> &System {
        &self.sys
    }

    /// The solver settings.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Largest internal step in use (s).
    pub fn max_internal_step(&self) -> f64 {
        self.h_max
    }

    /// The parameters this simulator was built from.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Whether the current mode satisfies the contact law (within tolerance).
    pub fn mode_is_consistent(&self) -> bool {
        mode::violation(&self.sys, &self.mode, self.zero_mask(), self.load0())
            <= mode::CONSISTENCY_TOL
    }

    /// Advances to `t_end` under an excitation that is linear over
    /// `[now, t_end]` (values given at the current time).
    pub fn advance(&mut self, t_end: f64, exc: &Excitation) -> Result<(), SimError> {
        self.advance_pieces(std::iter::once((t_end, *exc)))
    }

    /// Advances through consecutive linear pieces, each given by its end
    /// time and its excitation (values at its start), exactly as `advance`
    /// on each in turn; runs of switch-free steps go on across the pieces'
    /// ends on the fast path.
    pub fn advance_pieces(
        &mut self,
        pieces: impl IntoIterator<Item = (f64, Excitation)>,
    ) -> Result<(), SimError> {
        let mut pieces = pieces.into_iter();
        let mut pending = pieces.next();
        while let Some((t_end, exc)) = pending.take() {
            let mut piece = self.begin_piece(t_end, &exc)?;
            match self.settings.method {
                Method::EventLocated if self.exact => loop {
                    // Substeps proved event-free on the exact map; the one
                    // it cannot prove at fine RK4 steps with located events.
                    pending = self.folded_steps(&mut piece, &mut pieces);
                    if piece.i > piece.n {
                        break;
                    }
                    self.fine_steps(piece.end_of(piece.i), &piece);
                    piece.i += 1;
                },
                Method::EventLocated => loop {
                    // Runs of switch-free steps on the fast path; the step
                    // where a guard fires with event location.
                    pending = self.lean_steps(&mut piece, &mut pieces);
                    if piece.i > piece.n {
                        break;
                    }
                    self.step_located(piece.end_of(piece.i), &piece.exc, piece.t_ref);
                    piece.i += 1;
                },
                Method::StepEnd => {
                    for i in 1..=piece.n {
                        self.step_switch_at_end(piece.end_of(i), &exc, piece.t_ref);
                    }
                    pending = pieces.next();
                }
            }
            self.end_piece(&piece);
        }
        let n = self.sys.n;
        if !(self.u[..=n]
            .iter()
            .chain(&self.v[..=n])
            .all(|x| x.is_finite()))
        {
            return Err(SimError::NonFinite { t: self.t });
        }
        Ok(())
    }

    /// Checks a piece from the current time and acts on a jump of the
    /// external force (it can break a stick; `ag` cannot).
    fn begin_piece(&mut self, t_end: f64, exc: &Excitation) -> Result<Piece, SimError> {
        exc.check(self.t, t_end)?;
        if exc.fext != self.fext_now {
            self.fext_now = exc.fext;
            self.resolve_mode(0);
        }
        let h = if self.exact {
            self.map_step()
        } else {
            self.h_max
        };
        Ok(Piece::new(self.t, t_end, exc, h))
    }

    /// From now to `t_end` within `piece` by RK4 steps of at most `h_fine`
    /// with located events (the RK4 fast path between events).
    fn fine_steps(&mut self, t_end: f64, piece: &Piece) {
        let e = &piece.exc;
        let dt = self.t - piece.t_ref;
        let exc = Excitation {
            ag: e.ag + e.ag_rate * dt,
            ag_rate: e.ag_rate,
            fext: e.fext + e.fext_rate * dt,
            fext_rate: e.fext_rate,
        };
        let mut sub = Piece::new(self.t, t_end, &exc, self.h_fine);
        let mut none = std::iter::empty();
        loop {
            self.lean_steps(&mut sub, &mut none);
            if sub.i > sub.n {
                break;
            }
            self.step_located(sub.end_of(sub.i), &sub.exc, sub.t_ref);
            sub.i += 1;
        }
    }

    /// The inputs at the end of a finished piece.
    fn end_piece(&mut self, piece: &Piece) {
        let length = piece.t_end - piece.t_ref;
        self.ag_now = piece.exc.ag + piece.exc.ag_rate * length;
        self.fext_now = piece.exc.fext + piece.exc.fext_rate * length;
    }

    fn segment(&self, exc: &Excitation, t_ref: f64) -> Segment<'_> {
        Segment {
            sys: &self.sys,
            mode: &self.mode,
            dynamics: &self.dynamics,
            exc: *exc,
            rk: StructureRk4::new(&self.sys, &self.dynamics, exc, t_ref),
            t0: self.t,
            ag0: exc.ag + exc.ag_rate * (self.t - t_ref),
            u: &self.u,
            v: &self.v,
        }
    }

    /// Takes the step of length `h` that ends with the structure's cluster at
    /// `x1`: moves every body with its cluster, adds the work terms, and raises
    /// the peaks to the largest value of the cubic between the step ends.
    fn accept(&mut self, x1: &Structure, h: f64, exc: &Excitation, t_ref: f64) {
        let n = self.sys.n;
        let (mut du, mut v_end) = ([0.0; MAX_BODIES], [0.0; MAX_BODIES]);
        du[0] = x1[0] - self.u[0];
        v_end[0] = x1[1];
        // Clusters above the structure's: exact polynomials in time (what RK4
        // gives them), and Simpson's rule, exact, for their input work.
        let mut upper_work = 0.0;
        let d = &self.dynamics;
        let ag0 = exc.ag + exc.ag_rate * (self.t - t_ref);
        for c in 1..d.n_clusters {
            let v = self.v[d.bottom[c]];
            let [dc, vc, work] =
                upper_cluster_step(v, d.accel_const[c], d.mass[c], ag0, exc.ag_rate, h);
            (du[c], v_end[c]) = (dc, vc);
            upper_work += work;
        }
        let rk = StructureRk4::new(&self.sys, d, exc, t_ref);
        let (a0_start, jerk_start) = rk.accel_and_jerk(self.t, self.u[0], self.v[0]);
        let (u0_start, v0_start) = (self.u[0], self.v[0]);
        let d = &self.dynamics;
        for j in 1..=n {
            let (hi, lo) = (d.cluster_of[j], d.cluster_of[j - 1]);
            if hi != lo {
                let slip0 = self.u[j] - self.u[j - 1];
                let increment = du[hi] - du[lo];
                let (vrel0, vrel1) = (self.v[j] - self.v[j - 1], v_end[hi] - v_end[lo]);
                self.e_friction[j] -= d.slip_force[j] * increment;
                let peak = &mut self.peak_slip[j];
                hermite::raise_peak(peak, slip0, vrel0, slip0 + increment, vrel1, h);
            }
        }
        move_bodies(&mut self.u, &mut self.v, d, n, x1[0], &du, &v_end);
        self.e_input += x1[2] + upper_work;
        self.e_viscous += x1[3];
        self.t += h;
        self.stats.steps += 1;

        let (a0_end, jerk_end) = rk.accel_and_jerk(self.t, self.u[0], self.v[0]);
        hermite::raise_peak(&mut self.peak_u0, u0_start, v0_start, x1[0], x1[1], h);
        hermite::raise_peak(&mut self.peak_a0, a0_start, jerk_start, a0_end, jerk_end, h);
    }

    fn load0(&self) -> f64 {
        Dynamics::structure_load(&self.sys, self.u[0], self.v[0], self.fext_now)
    }

    fn structure_accel(&self) -> f64 {
        self.dynamics.accel(0, self.load0())
    }

    /// Interfaces whose relative velocity is exactly zero (free ones excluded).
    fn zero_mask(&self) -> u32 {
        let mut z = 0;
        for j in 1..=self.sys.n {
            if !self.sys.is_free(j) && self.v[j] == self.v[j - 1] {
                z |= 1 << j;
            }
        }
        z
    }

    fn stuck_mask(&self) -> u32 {
        (1..=self.sys.n)
            .filter(|&j| self.mode.is_stuck(j))
            .fold(0, |m, j| m | (1 << j))
    }

    /// Re-resolves the mode at the current state; counts a switch if it changed.
    fn resolve_mode(&mut self, must_break: u32) {
        let req = ResolveRequest {
            mode: self.mode,
            zero: self.zero_mask(),
            must_break,
            was_stuck: self.stuck_mask(),
            load0: self.load0(),
        };
        let res = mode::resolve(&self.sys, &req);
        if !res.consistent {
            self.stats.inconsistent += 1;
        } else if req.zero != 0 && mode::consistent_count(&self.sys, &req) > 1 {
            self.stats.ambiguous += 1;
        }
        if res.mode != self.mode {
            self.stats.events += 1;
            self.last_event = self.t;
            if self.first_switch.is_nan() && self.t >= self.watch_from {
                self.first_switch = self.t;
            }
            self.mode = res.mode;
            self.dynamics = Dynamics::new(&self.sys, &self.mode);
        }
    }

    /// Acts on guards that have fired at the current instant: a slipping
    /// interface whose relative velocity reached zero gets its two sides
    /// joined at their common momentum velocity; a stuck interface whose
    /// force reached `mus N` must break. Then the mode is resolved.
    fn fire(&mut self, slip_zeroed: u32, must_break: u32) {
        if slip_zeroed != 0 {
            self.join_velocities(slip_zeroed);
        }
        self.resolve_mode(must_break);
    }

    /// Sets one common velocity, the momentum average, on every group of
    /// bodies linked by stuck interfaces or by the interfaces in `joined`.
    fn join_velocities(&mut self, joined: u32) {
        let n = self.sys.n;
        let mut start = 0;
        for j in 1..=n + 1 {
            let linked = j <= n && (self.mode.is_stuck(j) || joined & (1 << j) != 0);
            if linked {
                continue;
            }
            // Bodies start..j-1 form a group.
            let group = start..j;
            let has_join = (start + 1..j).any(|i| joined & (1 << i) != 0);
            if has_join {
                let m: f64 = group.clone().map(|i| self.sys.mass[i]).sum();
                let p: f64 = group.clone().map(|i| self.sys.mass[i] * self.v[i]).sum();
                let v = p / m;
                for i in group {
                    self.v[i] = v;
                }
            }
            start = j;
        }
    }

    /// Guards of the current mode at the current state (infinite for free
    /// interfaces and for j > n).
    fn guards_now(&self, exc: &Excitation, t_ref: f64) -> [f64; MAX_BODIES] {
        let seg = self.segment(exc, t_ref);
        let x = seg.start();
        let mut g = [f64::INFINITY; MAX_BODIES];
        for (j, gj) in g.iter_mut().enumerate().take(self.sys.n + 1).skip(1) {
            *gj = seg.guard(j, &x, 0.0);
        }
        g
    }

    /// Fires the guards in `forced` and every guard among `candidates`
    /// that is zero or negative now.
    fn fire_violated(
        &mut self,
        exc: &Excitation,
        t_ref: f64,
        candidates: u32,
        forced: u32,
    ) -> bool {
        let g = self.guards_now(exc, t_ref);
        let (mut slip_zeroed, mut must_break) = (0, 0);
        for j in 1..=self.sys.n {
            let hit = forced & (1 << j) != 0 || (candidates & (1 << j) != 0 && g[j] <= 0.0);
            if hit {
                match self.mode.contact[j] {
                    Contact::Stuck => must_break |= 1 << j,
                    Contact::SlipForward | Contact::SlipBackward => slip_zeroed |= 1 << j,
                    Contact::Free => {}
                }
            }
        }
        if slip_zeroed | must_break != 0 {
            self.fire(slip_zeroed, must_break);
            true
        } else {
            false
        }
    }

    /// One internal step to `t1` with events located inside it.
    ///
    /// Chatter guard: a guard that is violated from the very start of a
    /// segment (no positive value inside it) fires at once, as a zero-length
    /// event; this settles degenerate contacts, such as a block "slipping"
    /// with exactly zero relative acceleration on an equal-friction stack. If
    /// the same interface does it again within the step, its guard is muted
    /// and switched at the step end; so are all guards after
    /// `MAX_EVENTS_PER_STEP` events in one step.
    fn step_located(&mut self, t1: f64, exc: &Excitation, t_ref: f64) {
        let all: u32 = (1..=self.sys.n).fold(0, |m, j| m | (1 << j));
        let mut muted: u32 = 0;
        let mut fired_at_once: u32 = 0;
        let mut events = 0;
        while self.t < t1 {
            let t0 = self.t;
            let h = t1 - t0;
            let mut at_once: u32 = 0;
            let (x1, earliest) = {
                let seg = self.segment(exc, t_ref);
                let (x0, x1) = (seg.start(), seg.structure_after(h));
                let mut earliest: Option<(f64, usize)> = None;
                let mut candidates = self.dynamics.changing_guards & !muted;
                while candidates != 0 {
                    let j = candidates.trailing_zeros() as usize;
                    candidates &= candidates - 1;
                    let g1 = seg.guard(j, &x1, h);
                    if g1 >= 0.0 {
                        continue;
                    }
                    let g0 = seg.guard(j, &x0, 0.0);
                    let start = if g0 > 0.0 {
                        Some((0.0, g0))
                    } else {
                        // The guard starts at zero (a contact that has just
                        // switched): bracket from the first positive sample.
                        (1..=6)
                            .map(|k| 0.5f64.powi(k))
                            .map(|th| (th, seg.guard_at(j, th, h)))
                            .find(|&(_, g)| g > 0.0)
                    };
                    match start {
                        Some(a) => {
                            let th = seg.locate(j, h, [a, (1.0, g1)]);
                            if earliest.is_none_or(|(e, _)| th < e) {
                                earliest = Some((th, j));
                            }
                        }
                        None if fired_at_once & (1 << j) == 0 => at_once |= 1 << j,
                        None => muted |= 1 << j,
                    }
                }
                (x1, earliest)
            };
            if at_once != 0 {
                fired_at_once |= at_once;
                self.fire_violated(exc, t_ref, 0, at_once);
                continue;
            }
            match earliest {
                None => {
                    self.accept(&x1, h, exc, t_ref);
                    self.t = t1;
                }
                Some((theta, located)) => {
                    // The located guard fires whatever its sign after
                    // rounding; others fire if they have reached zero too.
                    let h_event = theta * h;
                    let xe = self.segment(exc, t_ref).structure_after(h_event);
                    self.accept(&xe, h_event, exc, t_ref);
                    if theta >= 1.0 {
                        self.t = t1;
                    }
                    self.fire_violated(exc, t_ref, all & !muted, 1 << located);
                    events += 1;
                    if events >= MAX_EVENTS_PER_STEP {
                        muted = all;
                    }
                }
            }
        }
        if muted != 0 {
            self.stats.muted += u64::from(muted.count_ones());
            self.fire_violated(exc, t_ref, muted, 0);
        }
    }

    /// One internal step to `t1` switching modes only at its end (baseline).
    fn step_switch_at_end(&mut self, t1: f64, exc: &Excitation, t_ref: f64) {
        let h = t1 - self.t;
        let x1 = self.segment(exc, t_ref).structure_after(h);
        self.accept(&x1, h, exc, t_ref);
        self.t = t1;
        let all: u32 = (1..=self.sys.n).fold(0, |m, j| m | (1 << j));
        self.fire_violated(exc, t_ref, all, 0);
    }

    /// Writes the whole dynamic state (and the scene it belongs to).
    pub fn write_state(&self, w: &mut ByteWriter) {
        self.params.write(w);
        w.u8(match self.settings.method {
            Method::EventLocated => 1,
            Method::StepEnd => 2,
        });
        w.f64(self.settings.max_step);
        w.f64(self.t);
        w.f64s(&self.u);
        w.f64s(&self.v);
        w.f64s(&[self.e_input, self.e_viscous]);
        w.f64s(&self.e_friction);
        for c in self.mode.contact {
            w.u8(match c {
                Contact::Stuck => 0,
                Contact::SlipForward => 1,
                Contact::SlipBackward => 2,
                Contact::Free => 3,
            });
        }
        w.f64(self.peak_u0);
        w.f64s(&self.peak_slip);
        w.f64s(&[self.peak_a0, self.ag_now, self.fext_now, self.last_event]);
        let s = &self.stats;
        for x in [s.steps, s.events, s.inconsistent, s.muted, s.ambiguous] {
            w.u64(x);
        }
    }

    /// Reads a state written by [`Simulator::write_state`].
    pub fn read_state(r: &mut ByteReader) -> Result<Simulator, SnapshotError> {
        let p = Params::read(r)?;
        let method = match r.u8()? {
            1 => Method::EventLocated,
            2 => Method::StepEnd,
            m => return Err(format!("unknown solver {m} in the saved state")),
        };
        let settings = Settings {
            method,
            max_step: r.f64()?,
        };
        let mut sim = Simulator::new(&p, &settings).map_err(|e| e.to_string())?;
        sim.t = r.f64()?;
        r.f64s(&mut sim.u)?;
        r.f64s(&mut sim.v)?;
        sim.e_input = r.f64()?;
        sim.e_viscous = r.f64()?;
        r.f64s(&mut sim.e_friction)?;
        for c in sim.mode.contact.iter_mut() {
            *c = match r.u8()? {
                0 => Contact::Stuck,
                1 => Contact::SlipForward,
                2 => Contact::SlipBackward,
                3 => Contact::Free,
                x => return Err(format!("unknown contact state {x} in the saved state")),
            };
        }
        sim.check_restored_contacts()?;
        sim.dynamics = Dynamics::new(&sim.sys, &sim.mode);
        sim.peak_u0 = r.f64()?;
        r.f64s(&mut sim.peak_slip)?;
        let mut tail = [0.0; 4];
        r.f64s(&mut tail)?;
        [sim.peak_a0, sim.ag_now, sim.fext_now, sim.last_event] = tail;
        sim.stats = Stats {
            steps: r.u64()?,
            events: r.u64()?,
            inconsistent: r.u64()?,
            muted: r.u64()?,
            ambiguous: r.u64()?,
        };
        sim.check_restored()?;
        Ok(sim)
    }

    /// All reported quantities at the current time.
    pub fn outputs(&self) -> Outputs {
        let s = &self.sys;
        let d = &self.dynamics;
        let load0 = self.load0();
        let mut o = Outputs {
            t: self.t,
            up: self.u[0],
            vp: self.v[0],
            ap_abs: d.accel(0, load0),
            base_shear: s.k * self.u[0] + s.c * self.v[0],
            peak_up: self.peak_u0,
            peak_ap_abs: self.peak_a0,
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
            o.peak_slip[b] = self.peak_slip[j];
            o.e_friction_of[b] = self.e_friction[j];
        }
        o.e_friction = o.e_friction_of.iter().sum();
        o
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn substeps_round_up_but_not_past_rounding() {
        // Expected: ceil(length / h_max), with ratios within 1e-9 of an
        // integer taken as that integer, and at least one step.
        assert_eq!(substeps(0.005, 0.00125), 4.0);
        assert_eq!(substeps(0.005 * (1.0 + 1e-12), 0.00125), 4.0);
        assert_eq!(substeps(0.005 * (1.0 + 1e-6), 0.00125), 5.0);
        assert_eq!(substeps(0.0049, 0.00125), 4.0);
        assert_eq!(substeps(1e-9, 0.00125), 1.0);
        assert_eq!(substeps(7.3, 0.01), 730.0);
        // Beyond 2^52 every value is an integer: the same rule, by `ceil`.
        assert_eq!(substeps(1e10, 1e-8), (1e18 * (1.0 - 1e-9f64)).ceil());
    }

    #[test]
    fn bad_inputs_are_rejected_by_name_and_leave_the_state_alone() {
        let mut sim = Simulator::new(&Params::default(), &Settings::default()).unwrap();
        let nan_ag = Excitation {
            ag: f64::NAN,
            ..Default::default()
        };
        let e = sim.advance(0.01, &nan_ag).unwrap_err();
        assert!(e.to_string().starts_with("ag = NaN"));
        let inf_force = Excitation {
            fext_rate: f64::INFINITY,
            ..Default::default()
        };
        assert!(matches!(
            sim.advance(0.01, &inf_force),
            Err(SimError::BadInput {
                name: "der(Fext)",
                ..
            })
        ));
        sim.advance(0.01, &Excitation::default()).unwrap();
        assert!(matches!(
            sim.advance(0.005, &Excitation::default()),
            Err(SimError::BadTime { .. })
        ));
        assert_eq!(sim.time(), 0.01);
        let bad = Settings {
            max_step: -1.0,
            ..Settings::default()
        };
        let e = Simulator::new(&Params::default(), &bad).unwrap_err();
        assert_eq!(e.field, "maxStep");
    }

    #[test]
    fn reset_reproduces_a_run_bit_for_bit() {
        let mut sim = Simulator::new(&Params::default(), &Settings::default()).unwrap();
        let exc = Excitation {
            ag: 3.0,
            ag_rate: -20.0,
            ..Default::default()
        };
        sim.advance(0.3, &exc).unwrap();
        let first = sim.outputs();
        sim.reset();
        sim.advance(0.3, &exc).unwrap();
        assert_eq!(sim.outputs(), first);
        assert!(first.n_events > 0);
    }

    #[test]
    fn a_saved_state_continues_bit_for_bit() {
        let mut sim = Simulator::new(&Params::default(), &Settings::default()).unwrap();
        let exc = Excitation {
            ag: 4.0,
            ag_rate: -30.0,
            ..Default::default()
        };
        sim.advance(0.2, &exc).unwrap();
        let mut w = ByteWriter::default();
        sim.write_state(&mut w);
        let mut copy = Simulator::read_state(&mut ByteReader::new(&w.buf)).unwrap();
        for s in [&mut sim, &mut copy] {
            s.advance(
                0.4,
                &Excitation {
                    ag: -2.0,
                    ..Default::default()
                },
            )
            .unwrap();
        }
        assert_eq!(sim.outputs(), copy.outputs());
        assert!(Simulator::read_state(&mut ByteReader::new(&w.buf[..40])).is_err());
    }

    #[test]
    fn internal_step_respects_both_bounds() {
        let p = Params::default();
        let omega = 2.0 * std::f64::consts::PI / p.tp;
        let auto = Simulator::new(&p, &Settings::default()).unwrap();
        assert_eq!(
            auto.max_internal_step(),
            (ACCURATE_H_OMEGA / omega).min(ACCURATE_MAX_STEP)
        );
        let coarse = Settings {
            max_step: 10.0,
            ..Settings::default()
        };
        let sim = Simulator::new(&p, &coarse).unwrap();
        assert_eq!(sim.max_internal_step(), STABLE_H_OMEGA / omega);
    }
}
