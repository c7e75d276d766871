//! Baseline for comparisons, not a recommended mode: Coulomb friction
//! regularized as `F_j = -muk_j N_j tanh(v_j / eps)` (no sticking, no static
//! friction, no events), integrated by plain RK4 on every body with the
//! step the caller gives and no automatic bound. It is the smooth-friction
//! approach many codes use; its error has a floor of O(eps), it makes the
//! equations stiff (eigenvalues about mu g (1 + alpha) / eps), and without
//! a step bound RK4 diverges above h omega = 2.83 (RESEARCH.md §2).
//! [`stable_step`] gives the bound for a whole stack; the FMU's solver 3
//! never steps above it (see [`RegularizedSimulator::for_solver`]).

use crate::physics::engine::{Excitation, Outputs, SimError};
use crate::physics::hermite;
use crate::physics::params::{check_scalar, ParamError, Params, Support, MAX_BODIES, MIN_MAX_STEP};
use crate::physics::snapshot::{check_peaks, ByteReader, ByteWriter, SnapshotError};
use crate::physics::system::System;

/// Full state: u and v of every body, then input, viscous and friction work.
const STATE: usize = 2 * MAX_BODIES + 3;

/// RK4 step margin: plain RK4 is stable on the negative real axis to
/// `h |lambda| = 2.785` and on the imaginary axis to 2.83; the half-disk of
/// radius 2.5 in the left half-plane lies inside its stability region
/// (|R(z)| <= 0.873 on its edge).
pub const STABLE_H_LAMBDA: f64 = 2.5;

/// Largest stable RK4 step (s) of the regularized scene, and the interface
/// whose friction is the stiffest (0 when the structure's own frequency or
/// damping binds). Linearized at zero relative velocity (where tanh is
/// steepest), the system is `M u'' + (C + B^T D B) u' + K u = f`, with
/// `D_j = muk_j N_j / eps` per interface; every eigenvalue `s` of its
/// first-order form obeys `|s| <= max(omega_p, lambda_max)` with
/// `lambda_max` the largest eigenvalue of `M^-1/2 (C + B^T D B) M^-1/2`
/// (real roots lie in `[-lambda_max, 0]`, complex ones have `|s|^2 <=
/// omega_p^2`), so `h = 2.5 / max(omega_p, lambda_max)` keeps every one in
/// the half-disk where RK4 is stable.
pub fn stable_step(sys: &System, eps: f64) -> (f64, usize) {
    let n = sys.n;
    let mut a = nalgebra::DMatrix::<f64>::zeros(n + 1, n + 1);
    a[(0, 0)] = sys.c;
    let mut stiffest = (sys.omega_p.max(sys.c / sys.mass[0]), 0);
    for j in 1..=n {
        let d = sys.muk[j] * sys.normal[j] / eps;
        a[(j - 1, j - 1)] += d;
        a[(j, j)] += d;
        a[(j - 1, j)] -= d;
        a[(j, j - 1)] -= d;
        let alone = d * (1.0 / sys.mass[j - 1] + 1.0 / sys.mass[j]);
        if alone > stiffest.0 {
            stiffest = (alone, j);
        }
    }
    for r in 0..=n {
        for c in 0..=n {
            a[(r, c)] /= (sys.mass[r] * sys.mass[c]).sqrt();
        }
    }
    let lambda = a.symmetric_eigenvalues().max().max(sys.omega_p);
    (STABLE_H_LAMBDA / lambda, stiffest.1)
}

/// The regularized baseline integrates a structure only: a prescribed
/// support is refused (use the exact default).
fn refuse_prescribed(params: &Params) -> Result<(), ParamError> {
    if params.support == Support::Prescribed {
        return Err(ParamError {
            field: "support".into(),
            value: 1.0,
            allowed: "the structure (0) with the regularized baseline (solver 3): a prescribed \
                      support needs the exact default (solver 1)"
                .into(),
        });
    }
    Ok(())
}

/// A scene with regularized friction.
#[derive(Clone, Debug)]
pub struct RegularizedSimulator {
    params: Params,
    sys: System,
    eps: f64,
    step: f64,
    t: f64,
    y: [f64; STATE],
    peak_u0: f64,
    peak_slip: [f64; MAX_BODIES],
    peak_a0: f64,
    fext_now: f64,
    /// Internal steps over which some relative velocity changed sign: the
    /// chatter of a regularized law (it has no modes to switch).
    sign_changes: u64,
}

impl RegularizedSimulator {
    /// `eps` (m/s) sets the regularization; `step` (s) is the internal step,
    /// used as given (shortened only to end exactly at each excitation
    /// breakpoint), with no stability bound: a caller wanting one takes the
    /// smaller of its step and [`stable_step`], as the FMU's solver 3 does.
    pub fn new(params: &Params, eps: f64, step: f64) -> Result<RegularizedSimulator, ParamError> {
        let sys = System::new(params)?;
        refuse_prescribed(params)?;
        for (field, value) in [("frictionEps", eps), ("step", step)] {
            if !(value > 0.0 && value.is_finite()) {
                return Err(ParamError {
                    field: field.into(),
                    value,
                    allowed: "finite and > 0".into(),
                });
            }
        }
        Ok(RegularizedSimulator {
            params: params.clone(),
            sys,
            eps,
            step,
            t: 0.0,
            y: [0.0; STATE],
            peak_u0: 0.0,
            peak_slip: [0.0; MAX_BODIES],
            peak_a0: 0.0,
            fext_now: 0.0,
            sign_changes: 0,
        })
    }

    /// The FMU's solver 3: the step `max_step` (0: the baselines' automatic
    /// accuracy step, [`crate::baselines::auto_step`]), never above the RK4
    /// stability bound of the whole stack ([`stable_step`]; it is below the
    /// bare structure's, which `auto_step` also keeps). A scene whose bound
    /// is below the smallest allowed step is refused, naming `frictionEps`.
    pub fn for_solver(
        params: &Params,
        max_step: f64,
        friction_eps: f64,
    ) -> Result<RegularizedSimulator, ParamError> {
        check_scalar("frictionEps", friction_eps)?;
        let sys = System::new(params)?;
        refuse_prescribed(params)?;
        let (stable, stiffest) = stable_step(&sys, friction_eps);
        if stable < MIN_MAX_STEP {
            let which = match stiffest {
                0 => "the structure".to_string(),
                j => format!("interface {j}"),
            };
            return Err(ParamError {
                field: "frictionEps".into(),
                value: friction_eps,
                allowed: format!(
                    "large enough for a stable step of at least {MIN_MAX_STEP:e} s: \
                     solver 3 would need {stable:.3e} s ({which} is the stiffest, \
                     stiffness muk N / frictionEps); raise frictionEps or use solver 1"
                ),
            });
        }
        let step = crate::baselines::auto_step(max_step, sys.omega_p).min(stable);
        RegularizedSimulator::new(params, friction_eps, step)
    }

    /// The scene.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Writes the whole dynamic state (and the scene and settings).
    pub fn write_state(&self, w: &mut ByteWriter) {
        self.params.write(w);
        w.f64s(&[self.eps, self.step, self.t]);
        w.f64s(&self.y);
        w.f64(self.peak_u0);
        w.f64s(&self.peak_slip);
        w.f64s(&[self.peak_a0, self.fext_now]);
        w.u64(self.sign_changes);
    }

    /// Reads a state written by [`RegularizedSimulator::write_state`].
    pub fn read_state(r: &mut ByteReader) -> Result<RegularizedSimulator, SnapshotError> {
        let p = Params::read(r)?;
        let (eps, step) = (r.f64()?, r.f64()?);
        let mut s = RegularizedSimulator::new(&p, eps, step).map_err(|e| e.to_string())?;
        s.t = r.f64()?;
        r.f64s(&mut s.y)?;
        s.peak_u0 = r.f64()?;
        r.f64s(&mut s.peak_slip)?;
        s.peak_a0 = r.f64()?;
        s.fext_now = r.f64()?;
        s.sign_changes = r.u64()?;
        s.check_restored()?;
        Ok(s)
    }

    /// Refuses a restored state that could hang, fail or give non-finite
    /// outputs: a step outside `[1e-7 s, stability bound]`, a non-finite
    /// value, a negative time or peak, or motion beyond the stack.
    fn check_restored(&self) -> Result<(), SnapshotError> {
        let n = self.sys.n;
        let stable = stable_step(&self.sys, self.eps).0;
        if !(self.step >= MIN_MAX_STEP && self.step <= stable) {
            return Err(format!(
                "internal step {} s of the saved state is outside [1e-7, {stable:e}] s",
                self.step
            ));
        }
        let finite = [self.t, self.peak_u0, self.peak_a0, self.fext_now]
            .into_iter()
            .chain(self.y)
            .chain(self.peak_slip)
            .all(f64::is_finite);
        if !finite || self.t < 0.0 {
            return Err("a value of the saved state is not finite, or its time is negative".into());
        }
        check_peaks([self.peak_u0, self.peak_a0], &self.peak_slip)?;
        let beyond = (n + 1..MAX_BODIES)
            .any(|i| self.y[i] != 0.0 || self.y[MAX_BODIES + i] != 0.0 || self.peak_slip[i] != 0.0);
        if beyond || self.peak_slip[0] != 0.0 {
            return Err("the saved state has motion beyond its stack".into());
        }
        Ok(())
    }

    /// Current time (s).
    pub fn time(&self) -> f64 {
        self.t
    }

    /// The external force now, as the last call left it (N).
    pub fn fext_now(&self) -> f64 {
        self.fext_now
    }

    /// The internal step (s).
    pub fn step(&self) -> f64 {
        self.step
    }

    /// The regularization velocity (m/s).
    pub fn eps(&self) -> f64 {
        self.eps
    }

    /// The derived physical constants.
    pub fn system(&self) -> &System {
        &self.sys
    }

    /// Friction force of interface j at relative velocity `v_rel`.
    fn friction(&self, j: usize, v_rel: f64) -> f64 {
        -self.sys.muk[j] * self.sys.normal[j] * (v_rel / self.eps).tanh()
    }

    /// Absolute accelerations of all bodies.
    fn accelerations(&self, y: &[f64; STATE], fext: f64) -> [f64; MAX_BODIES] {
        let (s, n) = (&self.sys, self.sys.n);
        let v = |i: usize| y[MAX_BODIES + i];
        let mut f = [0.0; MAX_BODIES + 1];
        for (j, fj) in f.iter_mut().enumerate().take(n + 1).skip(1) {
            *fj = self.friction(j, v(j) - v(j - 1));
        }
        let mut a = [0.0; MAX_BODIES];
        a[0] = (fext - s.k * y[0] - s.c * v(0) - f[1]) / s.mass[0];
        for j in 1..=n {
            a[j] = (f[j] - f[j + 1]) / s.mass[j];
        }
        a
    }

    fn deriv(&self, y: &[f64; STATE], ag: f64, fext: f64) -> [f64; STATE] {
        let n = self.sys.n;
        let a = self.accelerations(y, fext);
        let mut dy = [0.0; STATE];
        let mut momentum = 0.0;
        for i in 0..=n {
            dy[i] = y[MAX_BODIES + i];
            dy[MAX_BODIES + i] = a[i] - ag;
            momentum += self.sys.mass[i] * y[MAX_BODIES + i];
        }
        let e = 2 * MAX_BODIES;
        dy[e] = fext * y[MAX_BODIES] - ag * momentum;
        dy[e + 1] = self.sys.c * y[MAX_BODIES] * y[MAX_BODIES];
        dy[e + 2] = (1..=n)
            .map(|j| {
                let v_rel = y[MAX_BODIES + j] - y[MAX_BODIES + j - 1];
                -self.friction(j, v_rel) * v_rel
            })
            .sum();
        dy
    }

    /// Advances to `t_end` under an excitation linear over `[now, t_end]`.
    pub fn advance(&mut self, t_end: f64, exc: &Excitation) -> Result<(), SimError> {
        exc.check(self.t, t_end)?;
        let t_ref = self.t;
        let at = |t: f64| exc.at(t - t_ref);
        let n_steps = crate::physics::engine::substeps(t_end - t_ref, self.step) as usize;
        let h = (t_end - t_ref) / n_steps as f64;
        for i in 0..n_steps {
            let t0 = t_ref + i as f64 * h;
            let y0 = self.y;
            let step = |y: &[f64; STATE], k: &[f64; STATE], c: f64| {
                let mut out = *y;
                for (o, d) in out.iter_mut().zip(k) {
                    *o += c * d;
                }
                out
            };
            let (ag0, f0) = at(t0);
            let (agm, fm) = at(t0 + 0.5 * h);
            let (ag1, f1) = at(t0 + h);
            let k1 = self.deriv(&y0, ag0, f0);
            let k2 = self.deriv(&step(&y0, &k1, 0.5 * h), agm, fm);
            let k3 = self.deriv(&step(&y0, &k2, 0.5 * h), agm, fm);
            let k4 = self.deriv(&step(&y0, &k3, h), ag1, f1);
            let mut y1 = y0;
            for i in 0..STATE {
                y1[i] += h / 6.0 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
            }
            self.track_peaks(&y0, &y1, h, f0, f1);
            let m = MAX_BODIES;
            let flipped = (1..=self.sys.n).any(|j| {
                let (r0, r1) = (y0[m + j] - y0[m + j - 1], y1[m + j] - y1[m + j - 1]);
                r0 * r1 < 0.0
            });
            self.sign_changes += u64::from(flipped);
            self.y = y1;
        }
        self.t = t_end;
        self.fext_now = at(t_end).1;
        if self.y.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(SimError::NonFinite { t: self.t })
        }
    }

    fn track_peaks(&mut self, y0: &[f64; STATE], y1: &[f64; STATE], h: f64, f0: f64, f1: f64) {
        let m = MAX_BODIES;
        hermite::raise_peak(&mut self.peak_u0, y0[0], y0[m], y1[0], y1[m], h);
        for j in 1..=self.sys.n {
            let (s0, s1) = (y0[j] - y0[j - 1], y1[j] - y1[j - 1]);
            let (r0, r1) = (y0[m + j] - y0[m + j - 1], y1[m + j] - y1[m + j - 1]);
            hermite::raise_peak(&mut self.peak_slip[j], s0, r0, s1, r1, h);
        }
        // Structure acceleration: sampled at step ends (a baseline).
        let a1 = self.accelerations(y1, f1)[0];
        let a0 = self.accelerations(y0, f0)[0];
        self.peak_a0 = self.peak_a0.max(a0.abs()).max(a1.abs());
    }

    /// The same outputs as the event-driven engine (`stuck` is never set).
    pub fn outputs(&self) -> Outputs {
        let (s, y, m) = (&self.sys, &self.y, MAX_BODIES);
        let a = self.accelerations(y, self.fext_now);
        let e = 2 * m;
        let mut o = Outputs {
            t: self.t,
            up: y[0],
            vp: y[m],
            ap_abs: a[0],
            base_shear: s.k * y[0] + s.c * y[m],
            peak_up: self.peak_u0,
            peak_ap_abs: self.peak_a0,
            e_input: y[e],
            e_kinetic: (0..=s.n)
                .map(|i| 0.5 * s.mass[i] * y[m + i] * y[m + i])
                .sum(),
            e_strain: 0.5 * s.k * y[0] * y[0],
            e_viscous: y[e + 1],
            e_friction: y[e + 2],
            n_events: self.sign_changes,
            ..Outputs::default()
        };
        for j in 1..=s.n {
            let b = j - 1;
            o.ub[b] = y[j];
            o.vb[b] = y[m + j];
            o.slip[b] = y[j] - y[j - 1];
            o.ab_abs[b] = a[j];
            o.force[b] = self.friction(j, y[m + j] - y[m + j - 1]);
            o.peak_slip[b] = self.peak_slip[j];
        }
        // No block sticks: the floor force is the friction of interface 1.
        if s.n >= 1 {
            o.floor_force = -o.force[0];
            o.sliding_force = o.floor_force;
        }
        o
    }
}
