//! Time integration of the reduced system of the current mode, and the running peaks and energy
//! balance.
//!
//! The default (solver 1) is exact: each substep (`ω h <= 0.5`, or `maxStep` where shorter) goes on
//! the exact map of the mode wherever it is proved free of switches and new peaks, and elsewhere on
//! the exact motion's Taylor polynomials with the switch located on them. The RK4 baseline (solver
//! 2, the paper's method: switches at step ends) is the only RK4 left; the default never enters it.
//!
//! The state is kept per body (`u`, `v` relative to the support); a step packs one displacement and
//! one velocity per cluster plus the energy quadratures into a short vector, integrates it, and
//! moves every body of a cluster by its cluster's increment.
//!
//! This file holds the [`Simulator`] and its stepping loop; beside it: `pieces` (excitation pieces,
//! step sizes), `sweep` (the default's one driver: substeps on the exact map of `exact_map`, proved
//! free of switches by `proofs`), `exact_events` (the default's other substeps: switches located on
//! the exact motion, with the polynomials of `poly`), `bodies` (the clusters above the structure's,
//! moving every body with its cluster), `events` (guards, firing, resolution), `report` (outputs,
//! counters, errors), `saved_state` and `state_check` (saved states and their validation). The RK4
//! baseline's step lives apart, in `crate::baselines::step_end`: the `Method::StepEnd` branch of
//! the stepping loop is its only caller.

use crate::limits::{SWITCH_WORK, TRY_WORK};
use crate::physics::hermite;
use crate::physics::mode::{self, Contact, Dynamics, Mode, ResolveRequest};
use crate::physics::params::{
    check_scalar, Method, ParamError, Params, Settings, MAX_BLOCKS, MAX_BODIES,
};
use crate::physics::snapshot::{ByteReader, ByteWriter, SnapshotError};
use crate::physics::system::System;

mod bodies;
mod events;
mod exact_events;
mod exact_map;
mod pieces;
mod poly;
mod proofs;
mod report;
mod saved_state;
mod state_check;
mod sweep;

pub(crate) use bodies::{friction_work, move_bodies, upper_cluster_step};
pub(crate) use exact_events::Scratch;
pub(crate) use pieces::Piece;
pub use pieces::{
    finite_terms, same_up_to_rounding, substeps, CheckedPieces, Excitation, PieceSource, Plain,
    EVENT_TIME_TOL, FINE_H_OMEGA, FINE_MAX_STEP, MAX_EVENTS_PER_STEP,
};
pub use proofs::PRESCRIBED_MAX_STEP;
pub use report::{Outputs, SimError, Stats};

/// The simulator: one scene, its state, peaks and energy terms.
///
/// The `pub(crate)` fields are the ones the step-end baseline
/// (`crate::baselines::step_end`) reads and writes: `sys`, `t`, `u`, `v`,
/// `dynamics`, `e_input`, `e_viscous`, `e_friction`, the peaks and `stats`.
#[derive(Clone, Debug)]
pub struct Simulator {
    params: Params,
    pub(crate) sys: System,
    settings: Settings,
    /// Largest internal step: the exact default's longest substep, or the
    /// step of the RK4 baseline (solver 2).
    h_max: f64,
    /// Stretches of the exact motion where a substep cannot be decided.
    h_fine: f64,
    /// Exact maps in use (derived data only: rebuilt identically on demand).
    maps: exact_map::MapCache,
    /// Dynamics of the modes met (derived data only, as `maps`).
    dyn_cache: events::DynamicsCache,
    pub(crate) t: f64,
    pub(crate) u: [f64; MAX_BODIES],
    pub(crate) v: [f64; MAX_BODIES],
    pub(crate) e_input: f64,
    pub(crate) e_viscous: f64,
    pub(crate) e_friction: [f64; MAX_BODIES],
    mode: Mode,
    pub(crate) dynamics: Dynamics,
    pub(crate) peak_u0: f64,
    pub(crate) peak_slip: [f64; MAX_BODIES],
    pub(crate) peak_a0: f64,
    ag_now: f64,
    fext_now: f64,
    last_event: f64,
    /// Switches are watched from this time on (`watch_switches`).
    watch_from: f64,
    /// The first switch at or after `watch_from` (NaN: none yet).
    first_switch: f64,
    pub(crate) stats: Stats,
    /// The event path's polynomials (zeroed at the first event only; no state).
    scratch: Option<Box<Scratch>>,
    /// Assignments the mode resolver tried (its work; not saved).
    tries: u64,
    /// `advance*` stop with [`SimError::WorkLimit`] once [`Simulator::work`]
    /// passes this (`set_work_budget`).
    work_limit: u64,
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
            h_max: 0.0, // by the method, below
            // (omega_p = 0 on a prescribed support: FINE_MAX_STEP.)
            h_fine: (FINE_H_OMEGA / sys.omega_p).min(FINE_MAX_STEP),
            maps: exact_map::MapCache::default(),
            dyn_cache: events::DynamicsCache::default(),
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
            scratch: None,
            tries: 0,
            work_limit: u64::MAX,
        };
        sim.h_max = match settings.method {
            Method::EventLocated => sim.map_step(),
            Method::StepEnd => crate::baselines::auto_step(settings.max_step, sim.sys.omega_p),
        };
        sim.take_reference();
        // (A state from outside: no slip at zero broke at this instant.)
        sim.resolve_mode(0, !0);
        sim.take_reference();
        sim.stats.events = 0;
        sim.last_event = f64::NAN;
        Ok(sim)
    }

    /// Back to rest at t = 0 with the same scene (and support mobility);
    /// the reference mode is the mode at rest.
    pub fn reset(&mut self) {
        let mobility = self.sys.mobility;
        *self = Simulator::new(&self.params, &self.settings).expect("validated before");
        self.set_support_mobility(mobility)
            .expect("validated before");
    }

    /// Sets the displacement and velocity of every body (relative to the
    /// support, index 0 = structure) and resolves the mode. Peaks restart
    /// from this state; energies are zeroed. On a prescribed support body 0
    /// is the support: `u[0]` and `v[0]` are taken as 0 whatever is given.
    pub fn set_state(&mut self, u: &[f64], v: &[f64]) {
        let n = self.sys.n;
        self.u = [0.0; MAX_BODIES];
        self.v = [0.0; MAX_BODIES];
        self.u[..=n].copy_from_slice(&u[..=n]);
        self.v[..=n].copy_from_slice(&v[..=n]);
        if self.sys.prescribed() {
            (self.u[0], self.v[0]) = (0.0, 0.0);
        }
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
        // The resolution rebuilds the dynamics only when it changes the
        // mode: the slips set here must have theirs already (the slips set
        // here are the reference of the resolution, the mode it gives the
        // reference from then on).
        self.rebuild_dynamics();
        self.take_reference();
        // (As in `new`: no slip at zero broke at this instant.)
        self.resolve_mode(0, !0);
        self.take_reference();
        self.peak_u0 = self.u[0].abs();
        self.peak_slip = [0.0; MAX_BODIES];
        for j in 1..=n {
            self.peak_slip[j] = (self.u[j] - self.u[j - 1]).abs();
        }
        self.peak_a0 = self.dynamics.accel(0, self.load0()).abs();
    }

    /// Sets the support's mobility `m_b = d(floor acceleration) /
    /// d(floor force)` (1/kg; 1 / M_f for a floor of lumped mass M_f), used
    /// in the law of a prescribed support from now on: in a mode other than
    /// the reference one (the mode when the inputs were last set) the
    /// support moves at `g ag + c` ([`mode::support_law`]), in the mode
    /// resolutions and between them. 0 (the default): a support that
    /// nothing the stack does moves. Finite, from 0 to 1e9
    /// (`supportMobility`); on a structure it is kept but unused.
    pub fn set_support_mobility(&mut self, mobility: f64) -> Result<(), ParamError> {
        check_scalar("supportMobility", mobility)?;
        if mobility != self.sys.mobility {
            self.sys.mobility = mobility;
            if self.sys.prescribed() {
                self.rebuild_dynamics();
            }
        }
        Ok(())
    }

    /// The support's mobility ([`Simulator::set_support_mobility`]).
    pub fn support_mobility(&self) -> f64 {
        self.sys.mobility
    }

    /// Current time (s).
    pub fn time(&self) -> f64 {
        self.t
    }

    /// The external force now, as the last call left it (N).
    pub fn fext_now(&self) -> f64 {
        self.fext_now
    }

    /// The ground (on a prescribed support: the support's) acceleration
    /// now, as the last call left it (m/s2).
    pub fn ag_now(&self) -> f64 {
        self.ag_now
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

    /// The work done so far, in internal steps: every internal step,
    /// [`SWITCH_WORK`] per switch and [`TRY_WORK`] per assignment the mode
    /// resolver tried.
    pub fn work(&self) -> u64 {
        let s = &self.stats;
        s.steps
            .saturating_add(SWITCH_WORK.saturating_mul(s.events))
            .saturating_add(TRY_WORK.saturating_mul(self.tries))
    }

    /// From now on, `advance*` stop with [`SimError::WorkLimit`] at the end
    /// of the first substep after which [`Simulator::work`] has grown by
    /// more than `units` (the state is then a substep's end).
    pub fn set_work_budget(&mut self, units: u64) {
        self.work_limit = self.work().saturating_add(units);
    }

    /// The error of a spent work budget, checked between substeps.
    fn check_work(&self) -> Result<(), SimError> {
        if self.work() > self.work_limit {
            return Err(SimError::WorkLimit { t: self.t });
        }
        Ok(())
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

    /// Whether the current mode satisfies the contact law (within tolerance, and the rounding
    /// of a stick a call ended at its capacity, 1e-12: its guard at zero, it breaks at the next
    /// call's start; saved there, its state is the engine's own).
    pub fn mode_is_consistent(&self) -> bool {
        mode::violation(&self.sys, &self.mode, self.zero_mask(), self.load0())
            <= mode::CONSISTENCY_TOL + 1e-12
    }

    /// Advances to `t_end` under an excitation that is linear over
    /// `[now, t_end]` (values given at the current time).
    pub fn advance(&mut self, t_end: f64, exc: &Excitation) -> Result<(), SimError> {
        // No source after it: the sweep then has no code to move on.
        let law_changed = self.take_reference();
        self.advance_source_from(Some((t_end, *exc)), Plain(std::iter::empty()), law_changed)
    }

    /// Advances through consecutive linear pieces, each given by its end time and its
    /// excitation (values at its start): `advance` on the first, then
    /// [`Simulator::advance_keeping_reference`] on each (the same as `advance` on each up to
    /// rounding, except on a prescribed support with a mobility: its law keeps one reference).
    pub fn advance_pieces(
        &mut self,
        pieces: impl IntoIterator<Item = (f64, Excitation)>,
    ) -> Result<(), SimError> {
        self.advance_source(CheckedPieces::new(pieces.into_iter(), &self.sys))
    }

    /// [`Simulator::advance_pieces`] from a [`PieceSource`] (a record's
    /// samples promise the pieces that continue the previous one).
    ///
    /// On a prescribed support the mode at the call's start becomes the
    /// reference of the support's law (the master computed the inputs with
    /// it), after the support's drift is taken out ([`mode::support_law`]).
    pub fn advance_source(&mut self, mut pieces: impl PieceSource) -> Result<(), SimError> {
        let law_changed = self.take_reference();
        self.advance_source_from(pieces.next_piece(), pieces, law_changed)
    }

    /// As [`Simulator::advance`], but the support's law keeps its reference
    /// (the mode at the start of the last call that took one): a look past
    /// the end of a step, before the master has set inputs for the mode the
    /// step ended in, sees the motion that step would have gone on with. A
    /// new reference there would make the support follow the held `ag`, the
    /// floor's acceleration in the old mode, at once (`ports::at_step_start`).
    pub fn advance_keeping_reference(
        &mut self,
        t_end: f64,
        exc: &Excitation,
    ) -> Result<(), SimError> {
        self.advance_source_from(Some((t_end, *exc)), Plain(std::iter::empty()), false)
    }

    /// From the `first` piece on, then `pieces`.
    #[inline(always)]
    fn advance_source_from(
        &mut self,
        first: Option<(f64, Excitation)>,
        mut pieces: impl PieceSource,
        mut law_changed: bool,
    ) -> Result<(), SimError> {
        let mut pending = first;
        // (Every pass sets `pending` anew.)
        while let Some((t_end, exc)) = pending {
            let mut piece = self.begin_piece(t_end, &exc, law_changed)?;
            law_changed = false;
            match self.settings.method {
                Method::EventLocated => loop {
                    // Substeps proved event-free on the exact map; the one
                    // it cannot prove on the exact motion with events
                    // located on it.
                    pending = self.sweep(&mut piece, &mut pieces);
                    if piece.i > piece.n {
                        break;
                    }
                    let mut scratch = self.scratch.take().unwrap_or_default();
                    self.exact_stretch(piece.end_of(piece.i), &piece, 0, &mut scratch);
                    self.scratch = Some(scratch);
                    piece.i += 1;
                    self.check_work()?;
                },
                // The baseline (`crate::baselines::step_end`).
                Method::StepEnd => {
                    for i in 1..=piece.n {
                        self.step_switch_at_end(piece.end_of(i), &exc, piece.t_ref);
                        self.check_work()?;
                    }
                    pending = pieces.next_piece();
                }
            }
            // The inputs at the piece's end (inside it, set where read: `fire_violated`).
            (self.ag_now, self.fext_now) = piece.exc.at(piece.t_end - piece.t_ref);
            let exact = self.settings.method == Method::EventLocated;
            if exact && pending.is_none() && self.sys.prescribed() {
                self.settle_at_end(&piece);
            }
        }
        self.check_finite()
    }

    /// An error if any displacement or velocity is not finite.
    fn check_finite(&self) -> Result<(), SimError> {
        let n = self.sys.n;
        let (u, v) = (&self.u[..=n], &self.v[..=n]);
        // Their sum first (`finite_terms`), each value only where it fails.
        let sum = u.iter().zip(v).fold(0.0, |s, (a, b)| s + a + b);
        if finite_terms(sum) || u.iter().chain(v).all(|x| x.is_finite()) {
            return Ok(());
        }
        Err(SimError::NonFinite { t: self.t })
    }

    /// Checks a piece from the current time and acts on a jump of the
    /// external force (it can break a stick; `ag` cannot, but on a
    /// prescribed support, where it is the support's acceleration and a
    /// non-zero `Fext` is refused).
    /// `law_changed`: the support's law changed at this instant
    /// ([`Simulator::take_reference`]), which can move it at once as a jump
    /// of `ag` does.
    #[inline(always)]
    fn begin_piece(
        &mut self,
        t_end: f64,
        exc: &Excitation,
        law_changed: bool,
    ) -> Result<Piece, SimError> {
        exc.check(self.t, t_end)?;
        let prescribed = self.sys.prescribed();
        if prescribed && (exc.fext != 0.0 || exc.fext_rate != 0.0) {
            let (name, value) = if exc.fext != 0.0 {
                ("Fext", exc.fext)
            } else {
                ("der(Fext)", exc.fext_rate)
            };
            return Err(SimError::NoForceOnSupport { name, value });
        }
        // On a prescribed support a jump of `ag` moves the support's cluster
        // at once, as a jump of `Fext` a structure's.
        // (An unchanged `Fext`, most calls, without the test's arithmetic.)
        if (exc.fext != self.fext_now && pieces::is_jump(exc.fext, self.fext_now))
            || (prescribed && (law_changed || pieces::is_jump(exc.ag, self.ag_now)))
        {
            self.fire_at_jump(exc);
        }
        Ok(Piece::new(self.t, t_end, exc, self.h_max))
    }

    /// At a jump of the inputs, the guards that it violates fire as at
    /// any event (out of line: rare).
    #[cold]
    #[inline(never)]
    fn fire_at_jump(&mut self, exc: &Excitation) {
        let candidates = self.violated_at_jump(exc);
        self.fire_violated(exc, self.t, candidates, 0);
        // The absolute acceleration jumps with the inputs: its running peak
        // takes the new value now (a call of length 0 takes no substep).
        self.peak_a0 = self.peak_a0.max(self.dynamics.accel(0, self.load0()).abs());
    }

    /// The structure cluster's load now ([`Dynamics::load0`]).
    fn load0(&self) -> f64 {
        Dynamics::load0(&self.sys, self.u[0], self.v[0], self.ag_now, self.fext_now)
    }

    /// On a prescribed support, makes the current mode the reference of
    /// the support's law ([`mode::support_law`]): the mode in force when the
    /// master sets the inputs. The support's drift from the input frame
    /// (`u0`, `v0`, non-zero only after a switch with a mobility) is taken
    /// out of every body first: the master's floor is where the support is
    /// at a communication point; the slips and relative velocities are
    /// kept, and the change of the stack's kinetic energy relative to the
    /// frame is booked as input work (the balance stays closed). The
    /// dynamics are rebuilt where the reference or the mobility changes
    /// them.
    ///
    /// Returns whether the support's law changed: its acceleration can
    /// then jump at once, as at a jump of `ag` (the caller fires the guards
    /// it violates).
    #[inline]
    fn take_reference(&mut self) -> bool {
        if !self.sys.prescribed() {
            return false;
        }
        self.take_support_reference()
    }

    /// [`Simulator::take_reference`] on a prescribed support.
    #[inline(never)]
    fn take_support_reference(&mut self) -> bool {
        let n = self.sys.n;
        let (u0, v0) = (self.u[0], self.v[0]);
        if u0 != 0.0 || v0 != 0.0 {
            let mut kinetic_change = 0.0;
            for i in 0..=n {
                let v = self.v[i] - v0;
                kinetic_change += 0.5 * self.sys.mass[i] * (v * v - self.v[i] * self.v[i]);
                self.u[i] -= u0;
                self.v[i] = v;
            }
            // Exactly 0 at the support, whatever rounding did above.
            (self.u[0], self.v[0]) = (0.0, 0.0);
            self.e_input += kinetic_change;
        }
        let d = &self.dynamics;
        let reference = (d.mass[0], d.slip_load[0]);
        if reference != (self.sys.ref_mass, self.sys.ref_load) {
            (self.sys.ref_mass, self.sys.ref_load) = reference;
            if self.sys.mobility != 0.0 {
                self.rebuild_dynamics();
                return true;
            }
        }
        false
    }

    /// The dynamics of the current mode anew, and the cache emptied (after
    /// a change of what a prescribed support's law depends on).
    fn rebuild_dynamics(&mut self) {
        self.dyn_cache.clear();
        self.dynamics = Dynamics::new(&self.sys, &self.mode);
    }
}
