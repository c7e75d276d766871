//! Time integration: RK4 on the reduced system of the current mode, with
//! stick/slip events located inside the step (or, as a baseline, checked at
//! step ends only), running peaks and the energy balance.
//!
//! The state is kept per body (`u`, `v` relative to the support); a step
//! packs one displacement and one velocity per cluster plus the energy
//! quadratures into a short vector, integrates it, and moves every body of a
//! cluster by its cluster's increment.

use crate::hermite;
use crate::mode::{self, Contact, Dynamics, Mode, ResolveRequest};
use crate::params::{Method, ParamError, Params, Settings, MAX_BLOCKS, MAX_BODIES};
use crate::system::System;

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

/// RK4 step limit for the bare structure: stability needs `h ω_p < 2.83`
/// (undamped); we keep a margin.
pub const STABLE_H_OMEGA: f64 = 2.5;
/// Default accuracy bound: `h ω_p <= 0.03`, chosen so that the default
/// settings meet the accuracy targets: peaks within 1e-6 relative of the
/// exact solution and an energy residual below 1e-8 of the input (measured:
/// the residual is 4e-8 at 0.05 and falls at order 4; see README).
pub const ACCURATE_H_OMEGA: f64 = 0.03;
/// Event tolerance on time (s).
pub const EVENT_TIME_TOL: f64 = 1e-12;
/// Chatter guard: at most this many located events in one internal step;
/// past it the rest of the step switches at its end only.
pub const MAX_EVENTS_PER_STEP: u32 = 64;

/// Largest internal step for the given settings and structure.
pub fn auto_step(settings: &Settings, omega_p: f64) -> f64 {
    let stable = STABLE_H_OMEGA / omega_p;
    if settings.max_step > 0.0 {
        settings.max_step.min(stable)
    } else {
        ACCURATE_H_OMEGA / omega_p
    }
}

/// An error while advancing.
#[derive(Clone, Debug, PartialEq)]
pub enum SimError {
    /// An input was NaN or infinite.
    BadInput { name: &'static str, value: f64 },
    /// `t_end` is before the current time.
    BadTime { now: f64, t_end: f64 },
    /// The state left the finite numbers (cannot happen with the step bound;
    /// reported rather than propagated as NaN).
    NonFinite { t: f64 },
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
}

/// Everything the product reports at the current time. Block arrays are
/// indexed by block number minus one; entries beyond `n_blocks` are 0.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Outputs {
    pub t: f64,
    pub up: f64,
    pub vp: f64,
    pub ap_abs: f64,
    pub base_shear: f64,
    pub ub: [f64; MAX_BLOCKS],
    pub vb: [f64; MAX_BLOCKS],
    pub slip: [f64; MAX_BLOCKS],
    pub ab_abs: [f64; MAX_BLOCKS],
    pub force: [f64; MAX_BLOCKS],
    pub stuck: [bool; MAX_BLOCKS],
    pub peak_up: f64,
    pub peak_slip: [f64; MAX_BLOCKS],
    pub peak_ap_abs: f64,
    pub e_input: f64,
    pub e_kinetic: f64,
    pub e_strain: f64,
    pub e_viscous: f64,
    pub e_friction: f64,
    pub e_friction_of: [f64; MAX_BLOCKS],
    pub n_events: u64,
}

impl Outputs {
    /// Input energy minus the stored and dissipated energy.
    pub fn energy_residual(&self) -> f64 {
        self.e_input - (self.e_kinetic + self.e_strain + self.e_viscous + self.e_friction)
    }
}

/// Packed vector: (u, v) of every cluster, then the input and viscous
/// energy quadratures. Friction work needs no quadrature of its own: RK4's
/// quadrature of `-F v_rel` equals `-F` times RK4's own slip increment.
const STATE: usize = 2 * MAX_BODIES + 2;
type Vector = [f64; STATE];

/// The frozen ingredients of one RK4 segment: a mode and a linear excitation.
struct Segment<'a> {
    sys: &'a System,
    mode: &'a Mode,
    dynamics: &'a Dynamics,
    exc: Excitation,
    t_ref: f64,
    /// Offset of the energy quadratures in the packed vector.
    e0: usize,
}

impl Segment<'_> {
    #[inline]
    fn inputs(&self, t: f64) -> (f64, f64) {
        let dt = t - self.t_ref;
        (
            self.exc.ag + self.exc.ag_rate * dt,
            self.exc.fext + self.exc.fext_rate * dt,
        )
    }

    #[inline]
    fn load0(&self, y: &Vector, fext: f64) -> f64 {
        Dynamics::structure_load(self.sys, y[0], y[1], fext)
    }

    /// Derivative of (u0, v0, input power, viscous power) of the
    /// structure's cluster.
    #[inline]
    fn structure_rates(&self, t: f64, u0: f64, v0: f64) -> [f64; 4] {
        let (ag, fext) = self.inputs(t);
        let d = self.dynamics;
        let a = d.accel0(Dynamics::structure_load(self.sys, u0, v0, fext)) - ag;
        [v0, a, (fext - ag * d.mass[0]) * v0, self.sys.c * v0 * v0]
    }

    /// One RK4 step of length `h` from `y0` at `t0`.
    ///
    /// Only the structure's cluster needs the four stages: every other
    /// cluster has a constant absolute acceleration in the mode, so RK4 on it
    /// reduces to its exact Taylor polynomial (u cubic, v quadratic in t), and
    /// RK4's quadrature of its input power `ag v` is Simpson's rule, exact for
    /// that cubic. Both are evaluated in closed form: the same numbers RK4
    /// gives, without the work.
    fn rk4(&self, y0: &Vector, t0: f64, h: f64) -> Vector {
        let e0 = self.e0;
        let mut y1 = *y0;
        let x = [y0[0], y0[1]];
        let k1 = self.structure_rates(t0, x[0], x[1]);
        let k2 = self.structure_rates(t0 + 0.5 * h, x[0] + 0.5 * h * k1[0], x[1] + 0.5 * h * k1[1]);
        let k3 = self.structure_rates(t0 + 0.5 * h, x[0] + 0.5 * h * k2[0], x[1] + 0.5 * h * k2[1]);
        let k4 = self.structure_rates(t0 + h, x[0] + h * k3[0], x[1] + h * k3[1]);
        let w = h / 6.0;
        let combine = |i: usize| w * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
        y1[0] += combine(0);
        y1[1] += combine(1);
        y1[e0] += combine(2);
        y1[e0 + 1] += combine(3);

        let d = self.dynamics;
        if d.n_clusters > 1 {
            let (ag0, _) = self.inputs(t0);
            let (agm, _) = self.inputs(t0 + 0.5 * h);
            let (ag1, _) = self.inputs(t0 + h);
            let mut input_work = 0.0;
            for c in 1..d.n_clusters {
                let (u, v) = (y0[2 * c], y0[2 * c + 1]);
                let a = d.accel_const[c];
                let vm = v + 0.25 * h * (2.0 * a - ag0 - agm);
                let v1 = v + h * (a - agm);
                y1[2 * c] = u + h * v + h * h * (0.5 * a - (ag0 + 2.0 * agm) / 6.0);
                y1[2 * c + 1] = v1;
                input_work -= d.mass[c] * w * (ag0 * v + 4.0 * agm * vm + ag1 * v1);
            }
            y1[e0] += input_work;
        }
        y1
    }

    /// Guard of interface j: positive while its current contact state holds.
    fn guard(&self, j: usize, y: &Vector, t: f64) -> f64 {
        let d = self.dynamics;
        match self.mode.contact[j] {
            Contact::Stuck => {
                // Same slack as the resolver's consistency check, so that a
                // stick it accepted starts with a guard >= 0. In a stack with
                // equal friction coefficients the stick force of a block riding
                // on a sliding one is exactly mus N; without the slack rounding
                // alone would make it chatter.
                let (_, fext) = self.inputs(t);
                let f = d.force(j, self.mode, self.load0(y, fext));
                self.sys.mus[j] * self.sys.normal[j] * (1.0 + mode::CONSISTENCY_TOL) - f.abs()
            }
            Contact::SlipForward | Contact::SlipBackward => {
                let v_rel = y[2 * d.cluster_of[j] + 1] - y[2 * d.cluster_of[j - 1] + 1];
                self.mode.contact[j].slip_sign() * v_rel
            }
            Contact::Free => f64::INFINITY,
        }
    }

    /// Instant (as a fraction of `h`) where guard j crosses zero, bracketed
    /// between `a` (guard > 0) and `b` (guard <= 0); returns the right end of
    /// the final bracket, where the guard has already changed sign. Illinois
    /// iteration on RK4 re-steps from the step start.
    fn locate(&self, j: usize, y0: &Vector, t0: f64, h: f64, bracket: [(f64, f64); 2]) -> f64 {
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
            let gc = self.guard(j, &self.rk4(y0, t0, c * h), t0 + c * h);
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

    pub fn time(&self) -> f64 {
        self.t
    }

    /// Time of the latest mode switch (NaN before the first).
    pub fn last_event_time(&self) -> f64 {
        self.last_event
    }

    pub fn stats(&self) -> Stats {
        self.stats
    }

    pub fn mode(&self) -> &Mode {
        &self.mode
    }

    pub fn system(&self) -> &System {
        &self.sys
    }

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
        for (name, value) in [
            ("ag", exc.ag),
            ("der(ag)", exc.ag_rate),
            ("Fext", exc.fext),
            ("der(Fext)", exc.fext_rate),
            ("t_end", t_end),
        ] {
            if !value.is_finite() {
                return Err(SimError::BadInput { name, value });
            }
        }
        if t_end < self.t {
            return Err(SimError::BadTime { now: self.t, t_end });
        }
        let t_ref = self.t;
        if exc.fext != self.fext_now {
            // A jump in the external force can break a stick (ag cannot).
            self.fext_now = exc.fext;
            self.resolve_mode(0);
        }
        self.ag_now = exc.ag;
        let length = t_end - t_ref;
        if length > 0.0 {
            let n = (length / self.h_max).ceil().max(1.0);
            let h = length / n;
            let n = n as usize;
            for i in 1..=n {
                let t1 = if i == n { t_end } else { t_ref + i as f64 * h };
                match self.settings.method {
                    Method::EventLocated => self.step_located(t1, exc, t_ref),
                    Method::StepEnd => self.step_switch_at_end(t1, exc, t_ref),
                }
            }
        }
        self.ag_now = exc.ag + exc.ag_rate * length;
        self.fext_now = exc.fext + exc.fext_rate * length;
        if !(self.u.iter().chain(self.v.iter()).all(|x| x.is_finite())) {
            return Err(SimError::NonFinite { t: self.t });
        }
        Ok(())
    }

    fn segment(&self, exc: &Excitation, t_ref: f64) -> Segment<'_> {
        let nc = self.dynamics.n_clusters;
        Segment {
            sys: &self.sys,
            mode: &self.mode,
            dynamics: &self.dynamics,
            exc: *exc,
            t_ref,
            e0: 2 * nc,
        }
    }

    fn pack(&self) -> Vector {
        let d = &self.dynamics;
        let mut y = [0.0; STATE];
        for c in 0..d.n_clusters {
            y[2 * c] = self.u[d.bottom[c]];
            y[2 * c + 1] = self.v[d.bottom[c]];
        }
        let e0 = 2 * d.n_clusters;
        y[e0] = self.e_input;
        y[e0 + 1] = self.e_viscous;
        y
    }

    /// Takes the packed state `y1` reached after `h` from `y0` at `t0`:
    /// moves every body with its cluster, adds the friction work, and raises
    /// the peaks to the largest value of the cubic between the ends.
    fn accept(&mut self, y0: &Vector, y1: &Vector, t0: f64, h: f64, exc: &Excitation, t_ref: f64) {
        let n = self.sys.n;
        let (a0_start, jerk_start) = self.structure_accel_and_jerk(exc, t_ref, t0);
        let d = &self.dynamics;
        for j in 1..=n {
            let (hi, lo) = (d.cluster_of[j], d.cluster_of[j - 1]);
            if hi != lo {
                let slip0 = self.u[j] - self.u[j - 1];
                let increment = (y1[2 * hi] - y0[2 * hi]) - (y1[2 * lo] - y0[2 * lo]);
                let (vrel0, vrel1) = (
                    y0[2 * hi + 1] - y0[2 * lo + 1],
                    y1[2 * hi + 1] - y1[2 * lo + 1],
                );
                self.e_friction[j] -= d.slip_force[j] * increment;
                let peak = &mut self.peak_slip[j];
                *peak = peak.max(hermite::max_abs_above(
                    slip0,
                    vrel0,
                    slip0 + increment,
                    vrel1,
                    h,
                    *peak,
                ));
            }
        }
        for i in 0..=n {
            let c = d.cluster_of[i];
            self.u[i] += y1[2 * c] - y0[2 * c];
            self.v[i] = y1[2 * c + 1];
        }
        let e0 = 2 * d.n_clusters;
        self.e_input = y1[e0];
        self.e_viscous = y1[e0 + 1];
        self.t = t0 + h;
        self.stats.steps += 1;

        let (a0_end, jerk_end) = self.structure_accel_and_jerk(exc, t_ref, self.t);
        let peak = hermite::max_abs_above(y0[0], y0[1], y1[0], y1[1], h, self.peak_u0);
        self.peak_u0 = self.peak_u0.max(peak);
        let peak = hermite::max_abs_above(a0_start, jerk_start, a0_end, jerk_end, h, self.peak_a0);
        self.peak_a0 = self.peak_a0.max(peak);
    }

    fn load0(&self) -> f64 {
        Dynamics::structure_load(&self.sys, self.u[0], self.v[0], self.fext_now)
    }

    fn structure_accel(&self) -> f64 {
        self.dynamics.accel(0, self.load0())
    }

    /// Absolute acceleration of the structure and its time derivative at `t`.
    fn structure_accel_and_jerk(&self, exc: &Excitation, t_ref: f64, t: f64) -> (f64, f64) {
        let ag = exc.ag + exc.ag_rate * (t - t_ref);
        let fext = exc.fext + exc.fext_rate * (t - t_ref);
        let load0 = Dynamics::structure_load(&self.sys, self.u[0], self.v[0], fext);
        let a = self.dynamics.accel(0, load0);
        let rel_acc = a - ag;
        let jerk =
            (exc.fext_rate - self.sys.k * self.v[0] - self.sys.c * rel_acc) / self.dynamics.mass[0];
        (a, jerk)
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
        }
        if res.mode != self.mode {
            self.stats.events += 1;
            self.last_event = self.t;
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
        let y = self.pack();
        let mut g = [f64::INFINITY; MAX_BODIES];
        for (j, gj) in g.iter_mut().enumerate().take(self.sys.n + 1).skip(1) {
            *gj = seg.guard(j, &y, self.t);
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
            let y0 = self.pack();
            let mut at_once: u32 = 0;
            let (y1, earliest) = {
                let seg = self.segment(exc, t_ref);
                let y1 = seg.rk4(&y0, t0, h);
                let mut earliest: Option<(f64, usize)> = None;
                for j in 1..=self.sys.n {
                    if muted & (1 << j) != 0 || self.sys.is_free(j) {
                        continue;
                    }
                    let g1 = seg.guard(j, &y1, t1);
                    if g1 >= 0.0 {
                        continue;
                    }
                    let g0 = seg.guard(j, &y0, t0);
                    let start = if g0 > 0.0 {
                        Some((0.0, g0))
                    } else {
                        // The guard starts at zero (a contact that has just
                        // switched): bracket from the first positive sample.
                        (1..=6)
                            .map(|k| 0.5f64.powi(k))
                            .map(|th| (th, seg.guard(j, &seg.rk4(&y0, t0, th * h), t0 + th * h)))
                            .find(|&(_, g)| g > 0.0)
                    };
                    match start {
                        Some(a) => {
                            let th = seg.locate(j, &y0, t0, h, [a, (1.0, g1)]);
                            if earliest.is_none_or(|(e, _)| th < e) {
                                earliest = Some((th, j));
                            }
                        }
                        None if fired_at_once & (1 << j) == 0 => at_once |= 1 << j,
                        None => muted |= 1 << j,
                    }
                }
                (y1, earliest)
            };
            if at_once != 0 {
                fired_at_once |= at_once;
                self.fire_violated(exc, t_ref, 0, at_once);
                continue;
            }
            match earliest {
                None => {
                    self.accept(&y0, &y1, t0, h, exc, t_ref);
                }
                Some((theta, located)) => {
                    // The located guard fires whatever its sign after
                    // rounding; others fire if they have reached zero too.
                    let h_event = theta * h;
                    let ye = self.segment(exc, t_ref).rk4(&y0, t0, h_event);
                    self.accept(&y0, &ye, t0, h_event, exc, t_ref);
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
        let t0 = self.t;
        let y0 = self.pack();
        let y1 = self.segment(exc, t_ref).rk4(&y0, t0, t1 - t0);
        self.accept(&y0, &y1, t0, t1 - t0, exc, t_ref);
        self.t = t1;
        let all: u32 = (1..=self.sys.n).fold(0, |m, j| m | (1 << j));
        self.fire_violated(exc, t_ref, all, 0);
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
    fn internal_step_respects_both_bounds() {
        let p = Params::default();
        let omega = 2.0 * std::f64::consts::PI / p.tp;
        let auto = Simulator::new(&p, &Settings::default()).unwrap();
        assert_eq!(auto.max_internal_step(), ACCURATE_H_OMEGA / omega);
        let coarse = Settings {
            max_step: 10.0,
            ..Settings::default()
        };
        let sim = Simulator::new(&p, &coarse).unwrap();
        assert_eq!(sim.max_internal_step(), STABLE_H_OMEGA / omega);
    }
}
