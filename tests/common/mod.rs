//! Test helpers: records, and an exact event-driven reference solution
//! written independently of the engine's reduced (cluster) formulation.
//!
//! The reference integrates the *full* chain (every body's u and v): in each
//! mode the stick forces come from the Delassus system `W_SS f_S = -(b_S +
//! W_SL f_L)` solved with nalgebra, the mode's linear ODE with linear forcing
//! is propagated exactly by a matrix exponential, and guard crossings are
//! found by bisection on that exact solution (to ~1e-14 s). A crossing is
//! seen where a guard changes sign between two of the `sub` samples a piece
//! is checked at, or where its rate turns from falling to rising between
//! them and its least value there is not positive (a graze: a slip that
//! touches zero and turns back, or a stick whose force touches its limit and
//! falls back, within a sample; fuzzing found two slips' grazes in about
//! 3 700 random scenes before the reference looked for them, both located
//! by the engine; tests/inputs_with_slopes.rs keeps one). Only the choice
//! of mode at an event is delegated to the engine's `mode::resolve`, which
//! the property tests check against projected Gauss–Seidel separately.
//!
//! A prescribed support (`Support::Prescribed`) is body 0 pinned to the
//! input: no spring, no damper, an infinite mass in the Delassus system
//! (its row of `W` has no `1/m0`), its absolute acceleration `ag` itself
//! (so the blocks' stick forces depend on `ag`: the generator gets an `ag`
//! column), its velocity kept at 0 when velocities are joined, and `ag`
//! jumps resolved as events (as `Fext` jumps are on a structure). Its input
//! and friction work are integrated exactly (the motion is polynomial).
#![allow(dead_code)]

use nalgebra::{DMatrix, DVector};
use stacked_live_load::fmi::instance::{Instance, LogSink, Status};
use stacked_live_load::physics::mode::{self, Contact, Mode, ResolveRequest};
use stacked_live_load::physics::system::System;
use stacked_live_load::{GroundMotion, Params, Support};
use std::f64::consts::PI;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// A mode's propagator, kept while the mode and the step stay the same:
/// the mode, the step, `exp(H step)`, the generator `H` and its forcing.
type PropagatorCache = (Mode, f64, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>);

mod child;
pub mod second;
#[allow(unused_imports)]
pub use child::in_child;

/// `../shared/ground_motions/NAME` beside the repository.
pub fn shared_record(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/ground_motions")
        .join(name)
}

pub fn read_shared(name: &str, g: f64) -> GroundMotion {
    GroundMotion::read(&shared_record(name), g).expect("shared record readable")
}

/// First `seconds` of a record (same samples).
pub fn truncate(gm: &GroundMotion, seconds: f64) -> GroundMotion {
    let n = gm.time.partition_point(|&t| t <= seconds + 1e-9);
    GroundMotion {
        time: gm.time[..n].to_vec(),
        accel: gm.accel[..n].to_vec(),
    }
}

/// Rescales a record to a given peak ground acceleration (m/s^2).
pub fn scaled_to_pga(gm: &GroundMotion, pga: f64) -> GroundMotion {
    let s = pga / gm.pga();
    GroundMotion {
        time: gm.time.clone(),
        accel: gm.accel.iter().map(|a| a * s).collect(),
    }
}

#[allow(unused_imports)]
pub use stacked_live_load::ground::synthetic::broadband;

/// Matrix exponential by scaling and squaring of a degree-20 Taylor sum.
pub fn expm(a: &DMatrix<f64>) -> DMatrix<f64> {
    let norm = a.iter().map(|x| x.abs()).sum::<f64>().max(1e-300);
    let s = (norm.log2().ceil() + 1.0).max(0.0) as i32;
    let scaled = a / 2f64.powi(s);
    let n = a.nrows();
    let mut term = DMatrix::identity(n, n);
    let mut sum = DMatrix::identity(n, n);
    for k in 1..=20 {
        term = &term * &scaled / k as f64;
        sum += &term;
    }
    for _ in 0..s {
        sum = &sum * &sum;
    }
    sum
}

/// Peaks and final state of a reference run.
#[derive(Clone, Debug)]
pub struct ExactResult {
    pub peak_u0: f64,
    pub peak_slip: Vec<f64>,
    pub u: Vec<f64>,
    pub v: Vec<f64>,
    pub events: usize,
    /// The time of every event (s, record time), in order.
    pub event_times: Vec<f64>,
    /// u0 at every record sample.
    pub u0_history: Vec<f64>,
    /// Prescribed support only (0 otherwise): the input work
    /// `-∫ Σ m_j ag u_j' dt` and the friction work of each interface.
    pub e_input: f64,
    pub e_friction: Vec<f64>,
}

/// One linear piece of the inputs, ending at `t_end`; values at its start.
#[derive(Clone, Copy, Debug)]
pub struct InputPiece {
    pub t_end: f64,
    pub ag: f64,
    pub ag_rate: f64,
    pub fext: f64,
    pub fext_rate: f64,
}

/// The exact event-driven reference.
pub struct Exact {
    sys: System,
    m: usize,
    mass: Vec<f64>,
    /// 1 / mass of each body (0 for a prescribed support).
    inv_mass: Vec<f64>,
    prescribed: bool,
    k: f64,
    c: f64,
    normal: Vec<f64>,
    /// On a prescribed support with a mobility: the reference mode, the
    /// mode when the inputs were last set (at every piece's start).
    ref_mode: std::cell::Cell<Mode>,
    /// The first piece's reference mode kept for all (`keeping_reference`).
    one_reference: bool,
}

impl Exact {
    pub fn new(p: &Params) -> Exact {
        let m = p.n_blocks + 1;
        let mut mass = vec![p.mp];
        mass.extend((0..p.n_blocks).map(|j| p.alpha[j] * p.mp));
        let omega = 2.0 * PI / p.tp;
        let k = p.mp * omega * omega;
        let normal: Vec<f64> = (0..m)
            .map(|j| {
                if j == 0 {
                    0.0
                } else {
                    p.g * mass[j..].iter().sum::<f64>()
                }
            })
            .collect();
        let prescribed = p.support == stacked_live_load::Support::Prescribed;
        let inv_mass = (0..m)
            .map(|i| {
                if i == 0 && prescribed {
                    0.0
                } else {
                    1.0 / mass[i]
                }
            })
            .collect();
        let (k, c) = if prescribed {
            (0.0, 0.0)
        } else {
            (k, 2.0 * p.zeta * (k * p.mp).sqrt())
        };
        let sys = System::new(p).unwrap();
        Exact {
            ref_mode: std::cell::Cell::new(Mode::all_stuck(&sys)),
            one_reference: false,
            sys,
            m,
            mass,
            inv_mass,
            prescribed,
            k,
            c,
            normal,
        }
    }

    /// The same reference with the support's mobility `m_b` of a
    /// prescribed support (the engine's `Simulator::set_support_mobility`):
    /// its own derivation of the law. The support is a floor of mass `M_f =
    /// 1 / m_b` that the rest of the master's model pushes with `P = M_f ag
    /// - F_ref(ag)`, where `F_ref(ag)` is the force the stack puts on a
    /// support moving at `ag` in the reference mode (the force the master
    /// took for its floor's acceleration `ag`): the Delassus system with
    /// body 0 of mass `M_f` under `P`.
    pub fn with_mobility(mut self, mobility: f64) -> Exact {
        self.sys.mobility = mobility;
        self
    }

    /// On a prescribed support, the first piece's mode stays the reference
    /// of the support's law for every piece (the pieces of one
    /// `advance_pieces` call, one communication step of a master).
    pub fn keeping_reference(mut self) -> Exact {
        self.one_reference = true;
        self
    }

    /// Absolute accelerations of the bodies and interface forces (index j-1
    /// for interface j) in `mode`, from the Delassus system.
    pub fn chain(&self, mode: &Mode, u0: f64, v0: f64) -> (DVector<f64>, DVector<f64>) {
        self.chain_with_force(mode, u0, v0, 0.0)
    }

    /// As [`Exact::chain`], with an external force `fext` on the structure.
    pub fn chain_with_force(
        &self,
        mode: &Mode,
        u0: f64,
        v0: f64,
        fext: f64,
    ) -> (DVector<f64>, DVector<f64>) {
        self.chain_full(mode, u0, v0, fext, 0.0)
    }

    /// As [`Exact::chain_with_force`] with the support's acceleration `ag`,
    /// which moves body 0 of a prescribed support (and nothing else); with
    /// a mobility, body 0 is the floor of [`Exact::with_mobility`].
    pub fn chain_full(
        &self,
        mode: &Mode,
        u0: f64,
        v0: f64,
        fext: f64,
        ag: f64,
    ) -> (DVector<f64>, DVector<f64>) {
        if self.prescribed && self.sys.mobility != 0.0 {
            let mf = 1.0 / self.sys.mobility;
            let f_ref = self.floor_force_pinned(&self.ref_mode.get(), ag);
            let p = mf * ag - f_ref;
            return self.chain_core(mode, p, mf.recip(), mf, None);
        }
        if self.prescribed {
            return self.chain_core(mode, 0.0, 0.0, 0.0, Some(ag));
        }
        let s0 = -self.k * u0 - self.c * v0 + fext;
        self.chain_core(mode, s0, self.inv_mass[0], self.mass[0], None)
    }

    /// The force the stack puts on a support moving at `ag` in `mode` (`-F_1`).
    pub fn floor_force_pinned(&self, mode: &Mode, ag: f64) -> f64 {
        if self.m == 1 {
            return 0.0;
        }
        let (_, f) = self.chain_core(mode, 0.0, 0.0, 0.0, Some(ag));
        -f[0]
    }

    /// The Delassus system with body 0 under the force `s0` (mass `mass0`,
    /// inverse `inv0`), or pinned at the acceleration `pinned`.
    fn chain_core(
        &self,
        mode: &Mode,
        s0: f64,
        inv0: f64,
        mass0: f64,
        pinned: Option<f64>,
    ) -> (DVector<f64>, DVector<f64>) {
        let n = self.m - 1;
        let mut inv = self.inv_mass.clone();
        inv[0] = inv0;
        let mut f = DVector::zeros(n);
        let stuck: Vec<usize> = (1..=n).filter(|&j| mode.is_stuck(j)).collect();
        for j in 1..=n {
            if !mode.is_stuck(j) {
                f[j - 1] = -self.sys.muk[j] * self.normal[j] * mode.contact[j].slip_sign();
            }
        }
        if !stuck.is_empty() {
            // r = W f + b, relative accelerations of the interfaces.
            let w = |a: usize, b: usize| -> f64 {
                if a == b {
                    inv[a - 1] + inv[a]
                } else if a + 1 == b {
                    -inv[a]
                } else if b + 1 == a {
                    -inv[b]
                } else {
                    0.0
                }
            };
            let ns = stuck.len();
            let wss = DMatrix::from_fn(ns, ns, |r, q| w(stuck[r], stuck[q]));
            let rhs = DVector::from_fn(ns, |r, _| {
                let j = stuck[r];
                let b = match (j, pinned) {
                    (1, Some(ag)) => -ag,
                    (1, None) => -s0 / mass0,
                    _ => 0.0,
                };
                let wl: f64 = (1..=n)
                    .filter(|&l| !mode.is_stuck(l))
                    .map(|l| w(j, l) * f[l - 1])
                    .sum();
                -(b + wl)
            });
            let fs = wss.lu().solve(&rhs).expect("W_SS is positive definite");
            for (r, &j) in stuck.iter().enumerate() {
                f[j - 1] = fs[r];
            }
        }
        let a = DVector::from_fn(self.m, |i, _| {
            if i == 0 {
                if let Some(ag) = pinned {
                    return ag;
                }
            }
            let below = if i == 0 { s0 } else { f[i - 1] };
            let above = if i < n { f[i] } else { 0.0 };
            (below - above) / if i == 0 { mass0 } else { self.mass[i] }
        });
        (a, f)
    }

    /// Generator `H` of the augmented state z = [u, v, 1, ag, ag', Fext,
    /// Fext'] in `mode` (`z' = H z`), and the interface forces as rows on
    /// `z` (`F = R z`: affine in u0, v0, Fext and ag).
    fn generator(&self, mode: &Mode) -> (DMatrix<f64>, DMatrix<f64>) {
        let m = self.m;
        let dim = 2 * m + 5;
        let (a0, f0) = self.chain(mode, 0.0, 0.0);
        let (au, fu) = self.chain(mode, 1.0, 0.0);
        let (av, fv) = self.chain(mode, 0.0, 1.0);
        let (af, ff) = self.chain_with_force(mode, 0.0, 0.0, 1.0);
        let (aag, fag) = self.chain_full(mode, 0.0, 0.0, 0.0, 1.0);
        let mut forces = DMatrix::zeros(m - 1, dim);
        for i in 0..m - 1 {
            forces[(i, 0)] = fu[i] - f0[i];
            forces[(i, m)] = fv[i] - f0[i];
            forces[(i, 2 * m)] = f0[i];
            forces[(i, 2 * m + 1)] = fag[i] - f0[i];
            forces[(i, 2 * m + 3)] = ff[i] - f0[i];
        }
        let mut h = DMatrix::zeros(dim, dim);
        for i in 0..m {
            h[(i, m + i)] = 1.0;
            h[(m + i, 0)] = au[i] - a0[i];
            h[(m + i, m)] = av[i] - a0[i];
            h[(m + i, 2 * m)] = a0[i];
            // Relative acceleration: A - ag, A depending on ag only on a
            // prescribed support (exactly 0 for its body 0).
            h[(m + i, 2 * m + 1)] = (aag[i] - a0[i]) - 1.0;
            h[(m + i, 2 * m + 3)] = af[i] - a0[i];
        }
        h[(2 * m + 1, 2 * m + 2)] = 1.0;
        h[(2 * m + 3, 2 * m + 4)] = 1.0;
        (h, forces)
    }

    /// The rate of guard `j` at `z`, from the state's rates `z' = H z` and
    /// the forces' rows: a slip's relative acceleration, signed; a stick's
    /// `-d|F|/dt`.
    fn guard_rate(
        &self,
        mode: &Mode,
        z: &DVector<f64>,
        rates: &DVector<f64>,
        forces: &DMatrix<f64>,
        j: usize,
    ) -> f64 {
        let m = self.m;
        match mode.contact[j] {
            Contact::Stuck => -(forces.row(j - 1) * z)[0].signum() * (forces.row(j - 1) * rates)[0],
            Contact::Free => 0.0,
            c => c.slip_sign() * (rates[m + j] - rates[m + j - 1]),
        }
    }

    fn guard(&self, mode: &Mode, z: &DVector<f64>, j: usize) -> f64 {
        let m = self.m;
        match mode.contact[j] {
            Contact::Stuck => {
                let (_, f) = self.chain_full(mode, z[0], z[m], z[2 * m + 3], z[2 * m + 1]);
                // Same slack as the engine's consistency tolerance (equal-mu stacks).
                self.sys.mus[j] * self.normal[j] * (1.0 + mode::CONSISTENCY_TOL) - f[j - 1].abs()
            }
            Contact::Free => f64::INFINITY,
            c => c.slip_sign() * (z[m + j] - z[m + j - 1]),
        }
    }

    /// Runs the record from rest; `sub` samples per record interval are used
    /// to detect guard crossings and extrema before bisection.
    pub fn run(&self, gm: &GroundMotion, sub: usize) -> ExactResult {
        let pieces: Vec<InputPiece> = gm
            .time
            .windows(2)
            .zip(gm.accel.windows(2))
            .map(|(t, a)| InputPiece {
                t_end: t[1],
                ag: a[0],
                ag_rate: (a[1] - a[0]) / (t[1] - t[0]),
                fext: 0.0,
                fext_rate: 0.0,
            })
            .collect();
        self.run_pieces(gm.time[0], &pieces, sub)
    }

    /// Runs from rest at `t_start` through consecutive linear pieces of
    /// `ag` and `Fext` (values at each piece's start: `Fext` may jump there,
    /// and a jump is resolved as an instantaneous event, as a stuck contact
    /// can break under it). `u0_history` holds u0 at every piece end.
    pub fn run_pieces(&self, t_start: f64, pieces: &[InputPiece], sub: usize) -> ExactResult {
        let m = self.m;
        let n = m - 1;
        let mut mode = Mode::all_stuck(&self.sys);
        let mut z = DVector::zeros(2 * m + 5);
        z[2 * m] = 1.0;
        let mut res = ExactResult {
            peak_u0: 0.0,
            peak_slip: vec![0.0; n],
            u: vec![],
            v: vec![],
            events: 0,
            event_times: vec![],
            u0_history: vec![0.0],
            e_input: 0.0,
            e_friction: vec![0.0; n],
        };
        let mut cache: Option<PropagatorCache> = None;
        // Relative displacement of each stuck pair, fixed when it stuck.
        let mut offsets = vec![0.0; m];
        let mut t_a = t_start;
        for (k, piece) in pieces.iter().enumerate() {
            // This piece runs from t_a (the previous one's end) to its end.
            let len = piece.t_end - t_a;
            let (a_a, slope) = (piece.ag, piece.ag_rate);
            // A piece is a communication step: on a prescribed support its
            // start's mode is the reference of the support's law, after the
            // support's drift from the input frame (non-zero only with a
            // mobility) is taken out of every body, slips and relative
            // velocities kept, the change of kinetic energy (relative to
            // the frame) booked as input work.
            // A change of the law can move the support at once, as a jump
            // of ag does: an event too.
            let mut law_changed = false;
            if self.prescribed && (k == 0 || !self.one_reference) {
                let (u0, v0) = (z[0], z[m]);
                for i in 0..m {
                    let v = z[m + i] - v0;
                    if i > 0 {
                        res.e_input += 0.5 * self.mass[i] * (v * v - z[m + i] * z[m + i]);
                    }
                    z[i] -= u0;
                    z[m + i] = v;
                }
                (z[0], z[m]) = (0.0, 0.0);
                if self.ref_mode.get() != mode {
                    self.ref_mode.set(mode);
                    cache = None;
                    law_changed = self.sys.mobility != 0.0;
                }
            }
            // On a prescribed support a jump of ag is an event too.
            let ag_jump = law_changed
                || self.prescribed
                    && (piece.ag - z[2 * m + 1]).abs()
                        > 1e-12 * piece.ag.abs().max(z[2 * m + 1].abs());
            z[2 * m + 1] = a_a;
            z[2 * m + 2] = slope;
            let jump = piece.fext - z[2 * m + 3];
            z[2 * m + 3] = piece.fext;
            z[2 * m + 4] = piece.fext_rate;
            if jump.abs() > 1e-12 * piece.fext.abs().max(1.0) || ag_jump {
                let before = mode;
                self.switch_settled(&mut mode, &mut z, 0);
                for j in 1..m {
                    if mode.is_stuck(j) && !before.is_stuck(j) {
                        offsets[j] = z[j] - z[j - 1];
                    }
                }
                res.events += usize::from(mode != before);
            }
            if len <= 0.0 {
                res.u0_history.push(z[0]);
                t_a = piece.t_end;
                continue;
            }
            let mut tau = 0.0;
            // A bound instead of a hang: where two frictions are equal the
            // reference can switch back and forth with no time passing.
            let mut switches_here = 0;
            while tau < len {
                let delta = (len - tau) / sub as f64;
                let fresh =
                    !matches!(&cache, Some((cm, cd, _, _, _)) if *cm == mode && *cd == delta);
                if fresh {
                    let (h, forces) = self.generator(&mode);
                    cache = Some((mode, delta, expm(&(&h * delta)), h, forces));
                }
                let (_, _, e_delta, h, forces) = cache.as_ref().unwrap();
                let z_start = z.clone();
                let mut g_prev: Vec<f64> = (1..=n).map(|j| self.guard(&mode, &z, j)).collect();
                let mut armed: Vec<bool> = g_prev.iter().map(|&g| g > 0.0).collect();
                let mut prev = z.clone();
                let mut event = None;
                for k in 1..=sub {
                    let mut next = e_delta * &prev;
                    self.hold_stuck(&mode, &mut next, &offsets);
                    let tk = |f: f64| (k as f64 - 1.0 + f) * delta;
                    // The state's rates at both samples, for the guards' rates.
                    let rates = [h * &prev, h * &next];
                    for j in 1..=n {
                        let g = self.guard(&mode, &next, j);
                        let mut from = 0.0;
                        if !armed[j - 1] && g <= 0.0 && k == 1 {
                            // A contact that has just switched may hold only for
                            // a fraction of a sub-sample: probe geometrically.
                            if let Some(f) = (1..=30).map(|e| 0.5f64.powi(e)).find(|&f| {
                                let zz = expm(&(h * (f * delta))) * &prev;
                                self.guard(&mode, &zz, j) > 0.0
                            }) {
                                armed[j - 1] = true;
                                from = f;
                            }
                        }
                        let at = |f: f64| expm(&(h * (f * delta))) * &prev;
                        let rate = |z: &DVector<f64>, rates: &DVector<f64>| {
                            self.guard_rate(&mode, z, rates, forces, j)
                        };
                        if !armed[j - 1] {
                            armed[j - 1] = g > 0.0;
                        } else if g < 0.0 {
                            let f = bisect(from, 1.0, |f| self.guard(&mode, &at(f), j) > 0.0);
                            if event.is_none_or(|(t, _)| tk(f) < t) {
                                event = Some((tk(f), j));
                            }
                        } else if may_graze(
                            [g_prev[j - 1], g],
                            [rate(&prev, &rates[0]), rate(&next, &rates[1])],
                            delta,
                        ) {
                            // A guard that turns back between the samples (a
                            // graze): its least value, where its rate changes
                            // sign, decides whether it reached zero.
                            let least = bisect(0.0, 1.0, |f| {
                                let z = at(f);
                                rate(&z, &(h * &z)) < 0.0
                            });
                            if self.guard(&mode, &at(least), j) <= 0.0 {
                                let f = bisect(from, least, |f| self.guard(&mode, &at(f), j) > 0.0);
                                if event.is_none_or(|(t, _)| tk(f) < t) {
                                    event = Some((tk(f), j));
                                }
                            }
                        }
                        g_prev[j - 1] = g;
                    }
                    // Extrema of u0 and of the slips between samples, on the
                    // exact trajectory only: up to the event if there is one.
                    match event {
                        Some((te, _)) => {
                            let f = te / delta - (k as f64 - 1.0);
                            let mut at_event = expm(&(h * (f * delta))) * &prev;
                            self.hold_stuck(&mode, &mut at_event, &offsets);
                            self.track_peaks(h, &prev, &at_event, f * delta, &mut res);
                            self.track_work(&mode, h, &prev, &at_event, f * delta, &mut res);
                            break;
                        }
                        None => {
                            self.track_peaks(h, &prev, &next, delta, &mut res);
                            self.track_work(&mode, h, &prev, &next, delta, &mut res);
                        }
                    }
                    prev = next;
                }
                match event {
                    None => {
                        z = prev;
                        tau = len;
                    }
                    Some((te, located)) => {
                        z = expm(&(h * te)) * &z_start;
                        self.hold_stuck(&mode, &mut z, &offsets);
                        tau += te;
                        z[2 * m + 1] = a_a + slope * tau;
                        z[2 * m + 3] = piece.fext + piece.fext_rate * tau;
                        let before = mode;
                        self.switch_settled(&mut mode, &mut z, located);
                        for j in 1..m {
                            if mode.is_stuck(j) && !before.is_stuck(j) {
                                offsets[j] = z[j] - z[j - 1];
                            }
                        }
                        res.events += 1;
                        switches_here += 1;
                        assert!(
                            switches_here < 10_000,
                            "reference: {switches_here} switches in one piece by t = {}",
                            t_a + tau
                        );
                        res.event_times.push(t_a + tau);
                        let abs_u0 = z[0].abs();
                        res.peak_u0 = res.peak_u0.max(abs_u0);
                    }
                }
            }
            res.u0_history.push(z[0]);
            t_a = piece.t_end;
        }
        res.u = (0..m).map(|i| z[i]).collect();
        res.v = (0..m).map(|i| z[m + i]).collect();
        res
    }

    /// Fires every guard that is <= 0: joins velocities, resolves the mode.
    /// In exact arithmetic stuck bodies keep their offset and share one
    /// velocity; the full-state propagation only does so up to rounding.
    fn hold_stuck(&self, mode: &Mode, z: &mut DVector<f64>, offsets: &[f64]) {
        let m = self.m;
        for j in 1..m {
            if mode.is_stuck(j) {
                z[j] = z[j - 1] + offsets[j];
                z[m + j] = z[m + j - 1];
            }
        }
    }

    /// [`Exact::switch`], and on a prescribed support again while the new
    /// mode breaks the contact law at once under the support's own
    /// acceleration `ag` (which it follows between switches): a mode
    /// resolved with the support's mobility can hold a stick that `ag`
    /// breaks, or start a slip that `ag` turns back. The engine fires such
    /// a contact at once and resolves again.
    fn switch_settled(&self, mode: &mut Mode, z: &mut DVector<f64>, located: usize) {
        self.switch(mode, z, located);
        if !self.prescribed {
            return;
        }
        let m = self.m;
        for _ in 0..8 {
            let (a, _) = self.chain_full(mode, z[0], z[m], z[2 * m + 3], z[2 * m + 1]);
            let at_once = (1..m).find(|&j| match mode.contact[j] {
                Contact::Stuck => self.guard(mode, z, j) < 0.0,
                Contact::Free => false,
                c => z[m + j] == z[m + j - 1] && c.slip_sign() * (a[j] - a[j - 1]) < 0.0,
            });
            match at_once {
                Some(j) => self.switch(mode, z, j),
                None => break,
            }
        }
    }

    /// The located guard fires whatever its sign after rounding.
    fn switch(&self, mode: &mut Mode, z: &mut DVector<f64>, located: usize) {
        let m = self.m;
        let n = m - 1;
        let mut must_break = 0u32;
        let mut joined = vec![false; m];
        // At a jump (`located` 0) on a prescribed support, a slip at zero
        // relative velocity whose relative acceleration still goes its way
        // goes on (it has just started; the engine's `violated_at_jump`).
        let (a_now, _) = self.chain_full(mode, z[0], z[m], z[2 * m + 3], z[2 * m + 1]);
        let goes_on = |j: usize| {
            let c = mode.contact[j];
            located == 0
                && self.prescribed
                && matches!(c, Contact::SlipForward | Contact::SlipBackward)
                && z[m + j] == z[m + j - 1]
                && c.slip_sign() * (a_now[j] - a_now[j - 1]) >= 0.0
        };
        // j is the interface: the guard, the closure and two arrays take it.
        #[allow(clippy::needless_range_loop)]
        for j in 1..=n {
            if j == located || (self.guard(mode, z, j) <= 0.0 && !goes_on(j)) {
                match mode.contact[j] {
                    Contact::Stuck => must_break |= 1 << j,
                    Contact::Free => {}
                    _ => joined[j] = true,
                }
            }
        }
        // Momentum-average velocity over groups linked by stuck or joined interfaces.
        let mut start = 0;
        // j runs one past the last interface (m, a group's end), not over `joined`.
        #[allow(clippy::needless_range_loop)]
        for j in 1..=m {
            if j < m && (mode.is_stuck(j) || joined[j]) {
                continue;
            }
            if j - start > 1 {
                let mm: f64 = (start..j).map(|i| self.mass[i]).sum();
                let p: f64 = (start..j).map(|i| self.mass[i] * z[m + i]).sum();
                // A prescribed support keeps its velocity.
                let v = if start == 0 && self.prescribed {
                    z[m]
                } else {
                    p / mm
                };
                for i in start..j {
                    z[m + i] = v;
                }
            }
            start = j;
        }
        // In exact arithmetic stuck bodies share one velocity; rounding in
        // the full-state propagation does not, so stuck counts as zero.
        let zero = (1..=n)
            .filter(|&j| !self.sys.is_free(j) && (joined[j] || mode.is_stuck(j)))
            .fold(0, |acc, j| acc | (1 << j));
        let was_stuck = (1..=n)
            .filter(|&j| mode.is_stuck(j))
            .fold(0, |a, j| a | (1 << j));
        // The resolver's selection rule (the engine's), its law of a
        // prescribed support told the reference mode's mass and load as the
        // reference finds them: the blocks stuck to the support, and the
        // force on them from above, F_ref(0).
        let mut sys = self.sys.clone();
        let load0 = if self.prescribed {
            let r = self.ref_mode.get();
            sys.ref_mass = (1..m)
                .take_while(|&j| r.is_stuck(j))
                .map(|j| self.mass[j])
                .sum();
            sys.ref_load = self.floor_force_pinned(&r, 0.0);
            z[2 * m + 1]
        } else {
            -self.k * z[0] - self.c * z[m] + z[2 * m + 3]
        };
        let req = ResolveRequest {
            mode: *mode,
            zero,
            must_break,
            was_stuck,
            load0,
        };
        let res = mode::resolve(&sys, &req);
        *mode = res.mode;
        if res.consistent {
            // Checked against the reference's own law: every interface of
            // `zero` stuck within mus N, or slipping the way its relative
            // acceleration goes.
            let (a, f) = self.chain_full(mode, z[0], z[m], z[2 * m + 3], z[2 * m + 1]);
            for j in 1..=n {
                if zero & (1 << j) == 0 {
                    continue;
                }
                let ok = match mode.contact[j] {
                    Contact::Stuck => {
                        f[j - 1].abs() <= self.sys.mus[j] * self.normal[j] * (1.0 + 1e-8)
                    }
                    Contact::Free => true,
                    c => c.slip_sign() * (a[j] - a[j - 1]) >= -1e-8 * self.sys.g,
                };
                assert!(
                    ok,
                    "the resolved mode {mode:?} breaks the reference's law at {j}"
                );
            }
        }
    }

    /// Input and friction work over a stretch of length `delta` from `a` to
    /// `b` in `mode`, on a prescribed support (nothing otherwise): there
    /// every velocity is a polynomial of degree 2 in time (`v_i^(k) = (H^k
    /// z)_(m+i)`, zero from k = 3) and `ag` one of degree 1, so `-∫ m ag v`
    /// is integrated exactly; a slipping interface's friction work is
    /// `muk N |Δ slip|` (its direction holds over the stretch).
    fn track_work(
        &self,
        mode: &Mode,
        h: &DMatrix<f64>,
        a: &DVector<f64>,
        b: &DVector<f64>,
        delta: f64,
        res: &mut ExactResult,
    ) {
        if !self.prescribed {
            return;
        }
        let m = self.m;
        let z1 = h * a;
        let z2 = h * &z1;
        let (g0, g1) = (a[2 * m + 1], a[2 * m + 2]);
        let mut work = 0.0;
        for i in 1..m {
            // v = c0 + c1 t + c2 t^2, ag = g0 + g1 t over [0, delta].
            let (c0, c1, c2) = (a[m + i], z1[m + i], 0.5 * z2[m + i]);
            let d = delta;
            let integral = g0 * (c0 * d + c1 * d * d / 2.0 + c2 * d.powi(3) / 3.0)
                + g1 * (c0 * d * d / 2.0 + c1 * d.powi(3) / 3.0 + c2 * d.powi(4) / 4.0);
            work -= self.mass[i] * integral;
        }
        if m > 1 && self.sys.mobility != 0.0 {
            // The support's drift from the input frame: the force F_1 of
            // the support on block 1 (affine in ag, so linear in time) over
            // the support's velocity relative to the frame, ∫ F_1 v0.
            let f1 = |z: &DVector<f64>| {
                self.chain_full(mode, z[0], z[m], z[2 * m + 3], z[2 * m + 1])
                    .1[0]
            };
            let (fa, fb) = (f1(a), f1(b));
            let d = delta;
            let (c0, c1, c2) = (a[m], z1[m], 0.5 * z2[m]);
            let (f0, f1r) = (fa, (fb - fa) / d);
            work += f0 * (c0 * d + c1 * d * d / 2.0 + c2 * d.powi(3) / 3.0)
                + f1r * (c0 * d * d / 2.0 + c1 * d.powi(3) / 3.0 + c2 * d.powi(4) / 4.0);
        }
        res.e_input += work;
        for j in 1..m {
            if !mode.is_stuck(j) && !self.sys.is_free(j) {
                let slip = |z: &DVector<f64>| z[j] - z[j - 1];
                res.e_friction[j - 1] +=
                    self.sys.muk[j] * self.normal[j] * (slip(b) - slip(a)).abs();
            }
        }
    }

    /// Peak |u0| and |slip| between two exact samples: at the ends and where
    /// the rate crosses zero (bisection on the exact solution).
    fn track_peaks(
        &self,
        h: &DMatrix<f64>,
        a: &DVector<f64>,
        b: &DVector<f64>,
        delta: f64,
        res: &mut ExactResult,
    ) {
        let m = self.m;
        let check =
            |value: &dyn Fn(&DVector<f64>) -> f64, rate: &dyn Fn(&DVector<f64>) -> f64| -> f64 {
                let mut best = value(a).abs().max(value(b).abs());
                if rate(a) * rate(b) < 0.0 {
                    let s = rate(a).signum();
                    let f = bisect(0.0, 1.0, |f| {
                        rate(&(expm(&(h * (f * delta))) * a)) * s > 0.0
                    });
                    best = best.max(value(&(expm(&(h * (f * delta))) * a)).abs());
                }
                best
            };
        let p = check(&|z| z[0], &|z| z[m]);
        res.peak_u0 = res.peak_u0.max(p);
        for j in 1..m {
            let p = check(&|z| z[j] - z[j - 1], &|z| z[m + j] - z[m + j - 1]);
            res.peak_slip[j - 1] = res.peak_slip[j - 1].max(p);
        }
    }
}

/// Whether a guard positive at both ends of a sample (values `g`, rates
/// `rates`, the sample `delta` long) may reach zero inside it: it falls
/// at the start and rises at the end, and the cubic through its ends comes
/// within a tenth of them, or of a millionth of its change over the sample,
/// of zero (the cubic is good to far better over a sample; the exact least
/// value is then found by bisection).
fn may_graze([g0, g1]: [f64; 2], [d0, d1]: [f64; 2], delta: f64) -> bool {
    if !(g0 > 0.0 && d0 < 0.0 && d1 > 0.0) {
        return false;
    }
    let (d0, d1) = (d0 * delta, d1 * delta);
    let cubic = |t: f64| {
        let s = 1.0 - t;
        g0 * s * s * (1.0 + 2.0 * t) + g1 * t * t * (3.0 - 2.0 * t) + d0 * t * s * s
            - d1 * t * t * s
    };
    let least = (0..=64)
        .map(|i| cubic(i as f64 / 64.0))
        .fold(f64::INFINITY, f64::min);
    least < 0.1 * g0.min(g1) + 1e-6 * (d0.abs() + d1.abs())
}

/// Bisection for the switch of a predicate from true (at `lo`) to false;
/// returns the right end of the final bracket.
pub fn bisect(mut lo: f64, mut hi: f64, mut pred: impl FnMut(f64) -> bool) -> f64 {
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if pred(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// Relative difference.
pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

/// Relative difference of slips, with a 1 nm floor (an interface that never
/// slips is 0 in both solutions up to rounding).
pub fn rel_slip(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-9)
}

/// Small deterministic generator (xorshift64*) for property tests.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545F4914F6CDD1D) >> 11) as f64 / (1u64 << 53) as f64
    }

    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }

    pub fn below(&mut self, n: usize) -> usize {
        (self.next_f64() * n as f64) as usize % n
    }
}

/// Runs a simulator through a record sample by sample, calling `each` after
/// every sample (for histories and per-instant checks).
pub fn run_sampled(
    sim: &mut stacked_live_load::Simulator,
    gm: &GroundMotion,
    mut each: impl FnMut(&stacked_live_load::Simulator),
) {
    for &t in &gm.time[1..] {
        stacked_live_load::ground::record::advance_with_record(
            sim,
            t,
            gm,
            1.0,
            &Default::default(),
        )
        .unwrap();
        each(sim);
    }
}

/// An FMU instance's log, kept for the tests to read.
#[derive(Clone, Default)]
pub struct Capture(Arc<Mutex<Vec<String>>>);

impl LogSink for Capture {
    fn log(&self, _status: Status, _category: &str, message: &str) {
        self.0.lock().unwrap().push(message.to_string());
    }
}

impl Capture {
    /// The last message logged (empty if none).
    pub fn last(&self) -> String {
        self.0.lock().unwrap().last().cloned().unwrap_or_default()
    }

    /// Every message logged so far.
    pub fn all(&self) -> Vec<String> {
        self.0.lock().unwrap().clone()
    }
}

/// A new FMU instance named `name` whose log the test can read.
pub fn instance(name: &str) -> (Instance, Capture) {
    let log = Capture::default();
    (Instance::new(name, None, Box::new(log.clone()), false), log)
}

/// An instance initialized from `start` (no stop time) after `setup`;
/// fails the test if initialization does.
pub fn started(start: f64, setup: impl FnOnce(&mut Instance)) -> (Instance, Capture) {
    let (mut inst, log) = instance("test");
    assert_eq!(inst.setup_experiment(start, None), Status::Ok);
    assert_eq!(inst.enter_initialization_mode(), Status::Ok);
    setup(&mut inst);
    assert_eq!(
        inst.exit_initialization_mode(),
        Status::Ok,
        "{}",
        log.last()
    );
    (inst, log)
}

/// Sample interval `k` of a record as a linear piece of `ag` (its end time
/// and its excitation): the samples a co-simulation master would set as
/// inputs with slopes, for the benchmarks that compare that with the record.
#[allow(dead_code)]
pub fn record_piece(
    gm: &stacked_live_load::GroundMotion,
    k: usize,
) -> (f64, stacked_live_load::Excitation) {
    let (t0, t1) = (gm.time[k], gm.time[k + 1]);
    let exc = stacked_live_load::Excitation {
        ag: gm.accel[k],
        ag_rate: (gm.accel[k + 1] - gm.accel[k]) / (t1 - t0),
        ..Default::default()
    };
    (t1, exc)
}

/// All of `gm`'s samples as [`record_piece`]s, built before a benchmark
/// times the engine on them (a master computes the slopes it passes).
pub fn record_pieces(
    gm: &stacked_live_load::GroundMotion,
) -> Vec<(f64, stacked_live_load::Excitation)> {
    (0..gm.time.len() - 1)
        .map(|k| record_piece(gm, k))
        .collect()
}

/// A stack on a prescribed support against the reference: slips, peak
/// slips, displacements and energies (1e-9 of their scales); returns the
/// worst relative difference.
pub fn compare_on_support(o: &stacked_live_load::Outputs, exact: &ExactResult, label: &str) -> f64 {
    let n = exact.peak_slip.len();
    let mut worst = 0.0f64;
    let scale_u = exact.u.iter().fold(1e-6f64, |m, x| m.max(x.abs()));
    for j in 0..n {
        worst = worst.max(rel_slip(o.peak_slip[j], exact.peak_slip[j]));
        let slip = exact.u[j + 1] - exact.u[j];
        worst = worst.max((o.slip[j] - slip).abs() / scale_u);
        worst = worst.max((o.ub[j] - exact.u[j + 1]).abs() / scale_u);
    }
    let scale_e = exact.e_input.abs().max(1e-9);
    worst = worst.max((o.e_input - exact.e_input).abs() / scale_e);
    for j in 0..n {
        worst = worst.max((o.e_friction_of[j] - exact.e_friction[j]).abs() / scale_e);
    }
    // The support's drift from the input frame and its peak (0 without
    // mobility).
    worst = worst.max((o.up - exact.u[0]).abs() / scale_u);
    worst = worst.max((o.peak_up - exact.peak_u0).abs() / scale_u);
    assert!(
        worst < 1e-9,
        "{label}: differs from the exact reference by {worst:.2e}\n engine {:?} {} {:?} {} {}\n exact {:?} {} {:?} {} {}",
        &o.peak_slip[..n],
        o.e_input,
        &o.e_friction_of[..n],
        o.up,
        o.peak_up,
        exact.peak_slip,
        exact.e_input,
        exact.e_friction,
        exact.u[0],
        exact.peak_u0
    );
    worst
}

/// The benchmarks' stacks (`benches/frontier.rs`, `examples/scaling.rs`):
/// the paper's two blocks (`Params::default`), and above them lighter, less
/// rough blocks, friction falling upwards but never equal to the one below
/// (equal coefficients make a riding block's stick force exactly mus N,
/// where stuck and sliding are both consistent).
pub fn graded_stack(n: usize) -> stacked_live_load::Params {
    let mut p = stacked_live_load::Params {
        n_blocks: n,
        ..Default::default()
    };
    for j in 2..n {
        p.alpha[j] = 0.25 / j as f64;
        p.mus[j] = 0.05 - 0.004 * (j - 1) as f64;
        p.muk[j] = p.mus[j];
    }
    p
}

/// Issue #21's tall stack with static above kinetic friction: eight blocks,
/// Tp 0.6 s, alpha 0.12 at the bottom down to 0.04 at the top, mu from
/// 0.3 / 0.25 at the bottom down to 0.1 / 0.08 at the top (linear).
pub fn graded_stack_static_above_kinetic() -> stacked_live_load::Params {
    let mut p = stacked_live_load::Params {
        n_blocks: 8,
        tp: 0.6,
        ..Default::default()
    };
    for j in 0..8 {
        let x = j as f64 / 7.0;
        p.alpha[j] = 0.12 - 0.08 * x;
        p.mus[j] = 0.3 - 0.2 * x;
        p.muk[j] = 0.25 - 0.17 * x;
    }
    p
}

/// For the benches and timing examples: `NARROW=1` (or `ISA=baseline`) runs
/// the engine's baseline x86-64 copy even where a wider one could, `ISA=avx2`
/// at most its AVX2 copy (`stacked_live_load::isa`); returns the name of the
/// copy that runs.
pub fn engine_copy_from_env() -> &'static str {
    use stacked_live_load::isa::{self, Isa};
    let narrow = std::env::var("NARROW").is_ok_and(|v| v == "1");
    let limit = match std::env::var("ISA").as_deref() {
        _ if narrow => Isa::Baseline,
        Ok("baseline") => Isa::Baseline,
        Ok("avx2") => Isa::Avx2,
        Ok("avx512") | Err(_) => Isa::Avx512,
        Ok(other) => panic!("ISA={other}: it must be baseline, avx2 or avx512"),
    };
    isa::allow_up_to(limit);
    match isa::chosen() {
        Isa::Avx512 => "AVX-512",
        Isa::Avx2 => "AVX2",
        Isa::Baseline => "baseline x86-64",
    }
}

/// Median of timings.
pub fn median(mut x: Vec<f64>) -> f64 {
    x.sort_by(|a, b| a.total_cmp(b));
    x[x.len() / 2]
}

/// The benches' coarse broadband records (seeds of their own, 20 s): `c1` at
/// 0.01 s, `c2` and `c3` at 0.02 s (most real records are sampled at 0.01 or
/// 0.02 s).
pub fn coarse_record(name: &str) -> GroundMotion {
    let (seed, dt) = match name {
        "c1" => (0xc0a51, 0.01),
        "c2" => (0xc0a52, 0.02),
        _ => (0xc0a53, 0.02),
    };
    broadband_record(&mut Rng(seed), 20.0, dt)
}

/// A broadband record: 60 sines with log-uniform frequencies in 0.1–25 Hz,
/// amplitudes falling as 1/sqrt(f), random phases, a build-up and a decay,
/// scaled to a PGA drawn in 0.3–0.6 g; sampled every `dt`.
pub fn broadband_record(rng: &mut Rng, duration: f64, dt: f64) -> GroundMotion {
    let comps: Vec<(f64, f64)> = (0..60)
        .map(|_| {
            let f = 0.1 * (250f64).powf(rng.next_f64());
            (f, 2.0 * PI * rng.next_f64())
        })
        .collect();
    let n = (duration / dt).round() as usize + 1;
    let rise = 0.15 * duration;
    let raw: Vec<f64> = (0..n)
        .map(|i| {
            let t = i as f64 * dt;
            let env =
                (t / rise).min(1.0) * (-(t - 0.6 * duration).max(0.0) / (0.15 * duration)).exp();
            env * comps
                .iter()
                .map(|(f, ph)| (2.0 * PI * f * t + ph).sin() / f.sqrt())
                .sum::<f64>()
        })
        .collect();
    let peak = raw.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    let pga = rng.uniform(0.3, 0.6) * 9.81;
    GroundMotion::uniform(dt, raw.iter().map(|a| a * pga / peak).collect())
}

/// A random stack of `n` blocks, mus >= muk (equal on about half of the
/// interfaces), on the structure or on a prescribed support.
pub fn random_stack(rng: &mut Rng, n: usize, support: Support) -> Params {
    let mut p = Params {
        n_blocks: n,
        tp: rng.uniform(0.2, 1.5),
        zeta: rng.uniform(0.0, 0.1),
        support,
        ..Params::default()
    };
    for j in 0..n {
        p.alpha[j] = rng.uniform(0.05, 0.4);
        p.muk[j] = rng.uniform(0.02, 0.3);
        p.mus[j] = p.muk[j]
            * if rng.next_f64() < 0.5 {
                1.0
            } else {
                rng.uniform(1.0, 1.5)
            };
    }
    p
}
