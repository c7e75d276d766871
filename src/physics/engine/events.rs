//! Stick/slip events: the guards at the current instant, firing a contact
//! and resolving the mode (for every path), and the step-end switching step
//! of the RK4 baseline (solver 2).

use super::*;

impl Simulator {
    /// Interfaces whose relative velocity is exactly zero (free ones excluded).
    pub(super) fn zero_mask(&self) -> u32 {
        let mut z = 0;
        // Half-open ranges on the event path: an inclusive range's
        // iterator tests an extra flag at every step.
        for j in 1..self.sys.n + 1 {
            z |= u32::from(self.v[j] == self.v[j - 1]) << j;
        }
        z & !self.sys.free
    }

    /// Re-resolves the mode at the current state; counts a switch if it changed. `must_break`:
    /// sticks whose force reached its limit; `settled`: slips whose relative velocity reached
    /// zero. Any other slip at zero began at this instant and broke here: a second resolution at
    /// the same instant (a contact that fires at once) keeps it broken unless nothing else is
    /// consistent (rule 1), rather than preferring it stuck.
    pub(crate) fn resolve_mode(&mut self, must_break: u32, settled: u32) {
        let (zero, was_stuck) = (self.zero_mask(), self.mode.stuck_mask());
        let req = ResolveRequest {
            mode: self.mode,
            zero,
            must_break: must_break | (zero & !was_stuck & !settled),
            was_stuck,
            load0: self.load0(),
        };
        let res = mode::resolve(&self.sys, &req);
        self.tries += u64::from(res.tries);
        if !res.consistent {
            self.stats.inconsistent += 1;
        }
        if res.mode != self.mode {
            // Counted at switches only: the count tries all 3^k assignments,
            // too costly for the resolutions that keep the mode (a stuck
            // stack under a moving force re-resolves at every jump).
            if res.ambiguous {
                self.stats.ambiguous += 1;
            }
            self.stats.events += 1;
            self.last_event = self.t;
            if self.first_switch.is_nan() && self.t >= self.watch_from {
                self.first_switch = self.t;
            }
            self.mode = res.mode;
            self.dyn_cache
                .load(&self.sys, &self.mode, &mut self.dynamics);
        }
    }

    /// Interfaces whose relative velocity is against their contact: a stick
    /// that moves, a slip the other way.
    pub(crate) fn against_contact(&self) -> u32 {
        let mut against = 0;
        for j in 1..self.sys.n + 1 {
            let dv = self.v[j] - self.v[j - 1];
            let wrong = match self.mode.contact[j] {
                Contact::Stuck => dv != 0.0,
                Contact::SlipForward => dv < 0.0,
                Contact::SlipBackward => dv > 0.0,
                Contact::Free => false,
            };
            against |= u32::from(wrong) << j;
        }
        against
    }

    /// Sets one common velocity, the momentum average, on every group of
    /// bodies linked by stuck interfaces or by the interfaces in `joined`.
    pub(crate) fn join_velocities(&mut self, joined: u32) {
        // The groups' bounds: the clusters' ends less the joined interfaces.
        let bounds = self.mode.cluster_ends() & !joined;
        let mut rest = joined & self.sys.interfaces();
        while rest != 0 {
            // Bodies start..end, the group of the lowest joined interface left.
            let [start, end] = mode::span_around(bounds, rest.trailing_zeros() as usize);
            rest &= !((1u32 << end) - 1);
            let group = start..end;
            let m: f64 = group.clone().map(|i| self.sys.mass[i]).sum();
            let p: f64 = group.clone().map(|i| self.sys.mass[i] * self.v[i]).sum();
            // A prescribed support keeps its velocity (0).
            let v = if start == 0 && self.sys.prescribed() {
                self.v[0]
            } else {
                p / m
            };
            for i in group {
                self.v[i] = v;
            }
        }
    }

    /// The inputs at the current time inside a piece: every stick/slip
    /// decision at an instant sees that instant's `Fext` (the structure's
    /// load), never the value at the piece's start.
    pub(super) fn take_inputs_now(&mut self, exc: &Excitation, t_ref: f64) {
        (self.ag_now, self.fext_now) = exc.at(self.t - t_ref);
    }

    /// The guard of interface `j` in the current mode at the current state
    /// and inputs (`load0`, [`Simulator::load0`]; infinite for a free
    /// interface): positive while its contact state holds. A stick's
    /// carries the resolver's consistency slack ([`mode::stick_capacity`]),
    /// so that a stick it accepted starts with a guard >= 0 (in a stack with
    /// equal friction a block riding on a sliding one has |F| = mus N
    /// exactly; rounding alone would chatter).
    #[inline]
    fn guard_now(&self, j: usize, load0: f64) -> f64 {
        let c = self.mode.contact[j];
        match c {
            Contact::Stuck => {
                let f = self.dynamics.force(j, &self.mode, load0);
                mode::stick_capacity(&self.sys, j) - f.abs()
            }
            Contact::SlipForward | Contact::SlipBackward => {
                c.slip_sign() * (self.v[j] - self.v[j - 1])
            }
            Contact::Free => f64::INFINITY,
        }
    }

    /// The guards that may fire at a jump of the inputs to `exc` now: all,
    /// but on a prescribed support a slip at zero relative velocity (one
    /// that has just started) whose relative acceleration under the new
    /// inputs still goes its way: it is not a switch, and resolving it
    /// anew would lose what started it (a stick at its limit, which the
    /// rule "the most stuck interfaces" would take back). A co-simulation
    /// that redoes its step up to a switch exchanges its values at that
    /// very instant: the support's acceleration then jumps by the error of
    /// the step's extrapolation, and the slip must go on.
    pub(super) fn violated_at_jump(&mut self, exc: &Excitation) -> u32 {
        let all = self.sys.interfaces();
        if !self.sys.prescribed() {
            return all;
        }
        self.take_inputs_now(exc, self.t);
        let load0 = self.load0();
        let mut candidates = all;
        for j in 1..=self.sys.n {
            let c = self.mode.contact[j];
            let starting = matches!(c, Contact::SlipForward | Contact::SlipBackward)
                && self.v[j] == self.v[j - 1];
            if starting && c.slip_sign() * self.dynamics.rel_accel(j, load0) >= 0.0 {
                candidates &= !(1 << j);
            }
        }
        candidates
    }

    /// At the end of a call on a prescribed support: a guard at zero up to
    /// rounding (1e-12 of its scale) that is about to cross fires now,
    /// not at the start of the next call. A master that redoes its step up
    /// to a switch it was told of (`first_switch`) then gets the mode after
    /// it at that communication point, as the monolithic model has it
    /// there; the exact motion is the same either way.
    pub(super) fn settle_at_end(&mut self, piece: &Piece) {
        let (n, d) = (self.sys.n, &self.dynamics);
        let load0 = self.load0();
        // The rate of the support cluster's acceleration (prescribed: g ag').
        let a0_rate = d.ag_gain * piece.exc.ag_rate;
        let mut forced = 0u32;
        for j in 1..=n {
            let c = self.mode.contact[j];
            match c {
                Contact::SlipForward | Contact::SlipBackward => {
                    // Its scale: how far the relative velocity moves over
                    // a substep.
                    let (sign, rate) = (c.slip_sign(), d.rel_accel(j, load0));
                    let g = sign * (self.v[j] - self.v[j - 1]);
                    if g <= 1e-12 * rate.abs() * self.h_max && sign * rate < 0.0 {
                        forced |= 1 << j;
                    }
                }
                Contact::Stuck if d.cluster_of[j] == 0 => {
                    let f = d.force(j, &self.mode, load0);
                    let cap = mode::stick_capacity(&self.sys, j);
                    if cap - f.abs() <= 1e-12 * cap && f.signum() * d.mass_above[j] * a0_rate > 0.0
                    {
                        forced |= 1 << j;
                    }
                }
                _ => {}
            }
        }
        if forced != 0 {
            self.fire_violated(&piece.exc, piece.t_ref, 0, forced);
        }
    }

    /// Fires the guards in `forced` and every guard among `candidates`
    /// that is zero or negative now. A slipping interface whose relative velocity reached zero
    /// gets its two sides joined at their common momentum velocity; a stuck one whose force
    /// reached `mus N` must break. (A join moves the bodies by as much as their relative velocity
    /// was: by rounding here, and the next stretch's guards see that at once.)
    pub(super) fn fire_violated(
        &mut self,
        exc: &Excitation,
        t_ref: f64,
        candidates: u32,
        forced: u32,
    ) {
        let (slip_zeroed, must_break) = self.violated_now(exc, t_ref, candidates, forced);
        if slip_zeroed | must_break != 0 {
            self.join_velocities(slip_zeroed);
            self.resolve_mode(must_break, slip_zeroed);
        }
    }

    /// The guards in `forced` and those among `candidates` that are zero or negative now, with
    /// the inputs taken at this instant: the slips that reached zero, the sticks that must break.
    #[inline(always)]
    pub(crate) fn violated_now(
        &mut self,
        exc: &Excitation,
        t_ref: f64,
        candidates: u32,
        forced: u32,
    ) -> (u32, u32) {
        self.take_inputs_now(exc, t_ref);
        let load0 = self.load0();
        let (mut slip_zeroed, mut must_break) = (0, 0);
        // Only the interfaces asked about: a guard is computed where it
        // decides (not for a forced one).
        let mut asked = (forced | candidates) & self.sys.interfaces();
        while asked != 0 {
            let j = asked.trailing_zeros() as usize;
            asked &= asked - 1;
            let hit = forced & (1 << j) != 0 || self.guard_now(j, load0) <= 0.0;
            if hit {
                match self.mode.contact[j] {
                    Contact::Stuck => must_break |= 1 << j,
                    Contact::SlipForward | Contact::SlipBackward => slip_zeroed |= 1 << j,
                    Contact::Free => {}
                }
            }
        }
        (slip_zeroed, must_break)
    }

    /// Fires the located guard `j` whatever its sign after rounding, and
    /// every other one `searched` (not proved positive over the stretch),
    /// not `muted`, at zero too; counts the step's `events` and mutes every
    /// guard after `MAX_EVENTS_PER_STEP`.
    pub(super) fn fire_located(
        &mut self,
        exc: &Excitation,
        t_ref: f64,
        [j, searched]: [u32; 2],
        muted: &mut u32,
        events: &mut u32,
    ) {
        let all = self.sys.interfaces();
        self.fire_violated(exc, t_ref, searched & !*muted, 1 << j);
        *events += 1;
        if *events >= MAX_EVENTS_PER_STEP {
            *muted = all;
        }
    }

    /// At a step's end: the guards muted in it switch there if violated.
    pub(super) fn fire_muted(&mut self, exc: &Excitation, t_ref: f64, muted: u32) {
        if muted != 0 {
            self.stats.muted += u64::from(muted.count_ones());
            self.fire_violated(exc, t_ref, muted, 0);
        }
    }
}

/// The dynamics of the modes met so far: a switch back to a mode copies
/// them instead of rebuilding them (derived data only: each entry is
/// `Dynamics::new` of its mode, rebuilt identically on demand).
#[derive(Clone, Debug)]
pub(super) struct DynamicsCache {
    keys: Vec<u32>,
    dynamics: Vec<Dynamics>,
    /// Entry replaced next once full.
    next: usize,
    /// By a hash of the key, the entry last found or kept for it, plus one
    /// (0: none): most loads look at one key, not at every key.
    hint: [u8; HINT_SLOTS],
}

impl Default for DynamicsCache {
    fn default() -> DynamicsCache {
        DynamicsCache {
            keys: Vec::new(),
            dynamics: Vec::new(),
            next: 0,
            hint: [0; HINT_SLOTS],
        }
    }
}

/// Slots of [`DynamicsCache`]'s hint (a power of two).
const HINT_SLOTS: usize = 128;

/// How many modes' dynamics are kept (then the oldest is replaced).
const DYNAMICS_CACHE_SIZE: usize = 64;

impl DynamicsCache {
    /// The mode as a number: two bits per interface, and the block count.
    fn key(mode: &Mode) -> u32 {
        let mut k = mode.n as u32;
        for j in 1..mode.n + 1 {
            k |= (mode.contact[j] as u32) << (2 * j + 2);
        }
        k
    }

    /// Forgets every entry (their dynamics were built for another reference
    /// mode or mobility of a prescribed support).
    pub(super) fn clear(&mut self) {
        *self = DynamicsCache::default();
    }

    /// The hint's slot of `key` (Fibonacci hashing).
    fn slot(key: u32) -> usize {
        (key.wrapping_mul(0x9E37_79B9) >> (32 - HINT_SLOTS.trailing_zeros())) as usize
    }

    /// Sets `out` to the dynamics of `mode`, built if missing.
    #[inline]
    pub(super) fn load(&mut self, sys: &System, mode: &Mode, out: &mut Dynamics) {
        let key = DynamicsCache::key(mode);
        let slot = DynamicsCache::slot(key);
        // Never hinted: no entry has this slot (hints are cleared only with the entries).
        let found = match usize::from(self.hint[slot]) {
            0 => None,
            hinted if self.keys[hinted - 1] == key => Some(hinted - 1),
            _ => self.keys.iter().position(|&k| k == key),
        };
        let Some(i) = found else {
            return self.insert(key, sys, mode, out);
        };
        self.hint[slot] = (i + 1) as u8;
        *out = self.dynamics[i];
    }

    /// A mode met for the first time: its dynamics built, kept and copied
    /// to `out` (out of line: a few dozen times per run).
    #[cold]
    #[inline(never)]
    fn insert(&mut self, key: u32, sys: &System, mode: &Mode, out: &mut Dynamics) {
        // Built in `out`, then copied once.
        out.build(sys, mode);
        let i = if self.keys.len() < DYNAMICS_CACHE_SIZE {
            if self.keys.is_empty() {
                // Room for every entry at once: a growing vector would copy
                // the dynamics kept so far at each doubling.
                self.keys.reserve_exact(DYNAMICS_CACHE_SIZE);
                self.dynamics.reserve_exact(DYNAMICS_CACHE_SIZE);
            }
            self.keys.push(key);
            self.dynamics.push(*out);
            self.keys.len() - 1
        } else {
            let i = self.next;
            (self.keys[i], self.dynamics[i]) = (key, *out);
            self.next = (i + 1) % DYNAMICS_CACHE_SIZE;
            i
        };
        self.hint[DynamicsCache::slot(key)] = (i + 1) as u8;
    }
}
