//! Stick/slip modes of the interfaces, the reduced dynamics of a mode, and the
//! resolution of a consistent mode at an instant.
//!
//! In a mode, bodies joined by stuck interfaces form a *cluster* that moves as
//! one rigid mass: one degree of freedom. Only the cluster holding the
//! structure feels the spring and damper; every other cluster is driven by
//! the constant kinetic friction of the slipping interfaces at its ends, so
//! its absolute acceleration is constant for the whole mode.
//!
//! Everything here is written in *absolute* accelerations `A_i = u_i'' + ag`:
//! the ground acceleration drops out of every force and of every relative
//! acceleration, so stick/slip decisions never depend on `ag`.
//!
//! On a prescribed support (`Support::Prescribed`) body 0 is the support:
//! its cluster's absolute acceleration is `g ag + c`, the input `ag` itself
//! in the reference mode or without mobility ([`support_law`],
//! [`Dynamics::accel0`], [`Dynamics::input_accel`]), and `ag` then enters
//! the stick/slip decisions.

use crate::physics::params::MAX_BODIES;
use crate::physics::system::System;
use std::ops::Range;

/// State of one interface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Contact {
    /// Relative velocity zero, friction force whatever keeps it so (|F| <= mus N).
    Stuck,
    /// Upper body moving in +x relative to the lower one: F = -muk N.
    SlipForward,
    /// Upper body moving in -x relative to the lower one: F = +muk N.
    SlipBackward,
    /// No friction (mus = 0): F = 0, never sticks, never an event.
    Free,
}

impl Contact {
    /// Sign of the relative velocity in a slipping mode (0 otherwise).
    #[inline]
    pub fn slip_sign(self) -> f64 {
        // A table in declaration order (Stuck, SlipForward, SlipBackward,
        // Free): no branch on the walk's hot path.
        const SIGN: [f64; 4] = [0.0, 1.0, -1.0, 0.0];
        SIGN[self as usize]
    }

    /// Slipping forward, or backward (`backward`: the rule's bit 1).
    pub fn slip(backward: bool) -> Contact {
        [Contact::SlipForward, Contact::SlipBackward][usize::from(backward)]
    }
}

/// The contact state of every interface; index j = 1..=n (index 0 unused).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mode {
    /// Number of blocks.
    pub n: usize,
    /// Contact of interface j at index j (index 0 unused).
    pub contact: [Contact; MAX_BODIES],
}

impl Mode {
    /// Every interface stuck, but free (μs = 0) ones.
    pub fn all_stuck(sys: &System) -> Mode {
        let mut contact = [Contact::Free; MAX_BODIES];
        for (j, c) in contact.iter_mut().enumerate().take(sys.n + 1).skip(1) {
            if !sys.is_free(j) {
                *c = Contact::Stuck;
            }
        }
        Mode { n: sys.n, contact }
    }

    /// Whether interface j is stuck.
    pub fn is_stuck(&self, j: usize) -> bool {
        self.contact[j] == Contact::Stuck
    }

    /// The stuck interfaces (bit j).
    pub fn stuck_mask(&self) -> u32 {
        // Contacts 1..=8 as a word's bytes (`Stuck` is 0): each zero byte's high bit, gathered.
        let x = u64::from_le_bytes(self.contact.map(|c| c as u8)[1..].try_into().unwrap());
        let low = 0x7f7f_7f7f_7f7f_7f7f;
        let stuck = (!(((x & low) + low) | x | low) >> 7).wrapping_mul(0x0102_0408_1020_4080);
        ((stuck >> 56) as u32) << 1 & ((2u32 << self.n) - 2)
    }

    /// Where the clusters end: the interfaces not stuck, and the top (bit n + 1).
    pub fn cluster_ends(&self) -> u32 {
        !self.stuck_mask() & ((4u32 << self.n) - 2)
    }
}

/// The bodies between the `ends` around body `i`: from the highest end at or below `i` (or 0)
/// to the lowest above it.
pub(crate) fn span_around(ends: u32, i: usize) -> [usize; 2] {
    let (below, above) = (ends & ((2u32 << i) - 1), ends & !((2u32 << i) - 1));
    [
        (31 - (below | 1).leading_zeros()) as usize,
        above.trailing_zeros() as usize,
    ]
}

/// A guard of a mode in the form the fast path evaluates it at a step end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Guard {
    /// A stuck interface in the structure's cluster: positive while its force
    /// `mass_above A0 + f_top` (A0 the cluster's absolute acceleration) stays
    /// within `cap = mus N (1 + CONSISTENCY_TOL)`.
    Stuck {
        /// Mass of the bodies it carries.
        mass_above: f64,
        /// Friction force on the top of its cluster.
        f_top: f64,
        /// Static capacity with the consistency slack.
        cap: f64,
    },
    /// A slipping interface: `sign (v[hi] - v[lo])` of its two clusters.
    Slip {
        /// Cluster above the interface.
        hi: usize,
        /// Cluster below it.
        lo: usize,
        /// Direction of slip.
        sign: f64,
    },
}

/// A band of the structure's absolute acceleration inside which every
/// stuck guard of `guards` is positive by a margin far above rounding: the
/// stick `|mass_above A + f_top| <= cap` solved for A and shrunk by 1e-12
/// of its scale.
pub fn safe_accel_band(guards: &[Guard]) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for g in guards {
        if let Guard::Stuck {
            mass_above,
            f_top,
            cap,
        } = *g
        {
            let margin = 1e-12 * (cap + f_top.abs()) / mass_above;
            lo = lo.max((-cap - f_top) / mass_above + margin);
            hi = hi.min((cap - f_top) / mass_above - margin);
        }
    }
    (lo, hi)
}

/// An interface between two clusters (its slip changes in the mode).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moving {
    /// The interface.
    pub j: usize,
    /// Cluster above it.
    pub hi: usize,
    /// Cluster below it.
    pub lo: usize,
}

/// The rule of [`Dynamics::input_accel`] (the part of the structure
/// cluster's absolute acceleration that the inputs make), written once:
/// `fext / M0 + g ag`. `AG = false` drops `ag`'s term, exactly zero on a
/// structure (`g = 0`, [`Dynamics::input_rule`]).
#[derive(Clone, Copy, Debug)]
pub struct InputRule<const AG: bool> {
    inv_mass0: f64,
    ag_gain: f64,
}

impl<const AG: bool> InputRule<AG> {
    /// The acceleration that `ag` and `fext` make.
    #[inline(always)]
    pub fn accel(&self, ag: f64, fext: f64) -> f64 {
        if AG {
            fext * self.inv_mass0 + ag * self.ag_gain
        } else {
            fext * self.inv_mass0
        }
    }
}

/// The reduced dynamics of one mode: clusters, their masses and the
/// constant forces the slipping interfaces put on them.
#[derive(Clone, Copy, Debug)]
pub struct Dynamics {
    /// Number of clusters (degrees of freedom).
    pub n_clusters: usize,
    /// Cluster of each body.
    pub cluster_of: [usize; MAX_BODIES],
    /// Lowest and highest body of each cluster.
    pub bottom: [usize; MAX_BODIES],
    /// Highest body of each cluster.
    pub top: [usize; MAX_BODIES],
    /// Mass of each cluster.
    pub mass: [f64; MAX_BODIES],
    /// Constant force on each cluster from the slipping interfaces at its ends.
    pub slip_load: [f64; MAX_BODIES],
    /// Friction force of each slipping or free interface (0 for stuck ones).
    pub slip_force: [f64; MAX_BODIES],
    /// For a stuck interface j: mass of bodies j..=top of its cluster.
    pub mass_above: [f64; MAX_BODIES],
    /// `slip_load / mass` of each cluster: the whole absolute acceleration
    /// of clusters above the structure's, constant in the mode.
    pub accel_const: [f64; MAX_BODIES],
    /// 1 / mass of the structure's cluster; 0 on a prescribed support (no
    /// force moves it: it moves with `ag`).
    pub inv_mass0: f64,
    /// `ag`'s share of the structure cluster's absolute acceleration: 0 on
    /// a structure (forces move it), the gain `g` of [`support_law`] on a
    /// prescribed support (1 in the reference mode). With `inv_mass0`, the
    /// one rule of every integrator ([`Dynamics::input_accel`]).
    pub ag_gain: f64,
    /// The constant part of the structure cluster's absolute acceleration,
    /// the one place every integrator reads it: `slip_load[0] / M0` on a
    /// structure (as `slip_load[0] * inv_mass0`), the constant `c` of
    /// [`support_law`] on a prescribed support (0 in the reference mode).
    pub load_accel0: f64,
    /// On a prescribed support, the force on the support's cluster that its
    /// drift from the input frame works against, beyond the input `-M' ag`:
    /// `M' (a0 - ag) - s' - M' (g - 1) ag = M' c - s'` (N), so that the
    /// support's work on the stack over a displacement `Δu0` of the support
    /// relative to the input frame is `support_force Δu0` (0 on a structure).
    pub support_force: f64,
    /// Whether body 0 is a prescribed support.
    pub prescribed: bool,
    /// Interfaces (bit j) whose guard can change sign within the mode:
    /// slipping ones, and stuck ones in the structure's cluster. A stick
    /// higher up carries a constant force; a free interface has no guard.
    pub changing_guards: u32,
    /// Of `changing_guards`, the stuck interfaces (their guards are
    /// [`Guard::Stuck`]).
    pub stuck_guards: u32,
    /// The guards of `changing_guards`, in order, first `n_guards` entries.
    pub guards: [Guard; MAX_BODIES],
    /// Number of entries of `guards`.
    pub n_guards: usize,
    /// Interfaces between two clusters, first `n_moving` entries.
    pub moving: [Moving; MAX_BODIES],
    /// Number of entries of `moving`.
    pub n_moving: usize,
    /// The band of the structure's absolute acceleration inside which its
    /// cluster's stuck interfaces hold ([`safe_accel_band`]), if it has any.
    pub stick_band: Option<(f64, f64)>,
    /// Direction of slip of moving interface m (between clusters m and
    /// m + 1; 0 for a free one).
    pub slip_sign: [f64; MAX_BODIES],
}

impl Dynamics {
    /// The clusters and constant loads of `mode`, its guards and moving
    /// interfaces.
    pub fn new(sys: &System, mode: &Mode) -> Dynamics {
        let mut d = Dynamics::clusters(sys, mode);
        d.add_guards(sys, mode);
        d
    }

    /// Sets `self` to [`Dynamics::new`] of `mode`, built in place.
    pub(crate) fn build(&mut self, sys: &System, mode: &Mode) {
        *self = Dynamics::clusters(sys, mode);
        self.add_guards(sys, mode);
    }

    /// The guards and moving interfaces of `mode` on its clusters.
    fn add_guards(&mut self, sys: &System, mode: &Mode) {
        let d = self;
        // Not free, and not a stick above the structure's cluster (its top, `top[0]`).
        let constant = mode.stuck_mask() & !((2u32 << d.top[0]) - 1);
        d.changing_guards = sys.interfaces() & !sys.free & !constant;
        for j in 1..sys.n + 1 {
            let (hi, lo) = (d.cluster_of[j], d.cluster_of[j - 1]);
            if hi != lo {
                d.moving[d.n_moving] = Moving { j, hi, lo };
                d.n_moving += 1;
            }
            if d.changing_guards & (1 << j) == 0 {
                continue;
            }
            d.guards[d.n_guards] = if mode.is_stuck(j) {
                d.stuck_guards |= 1 << j;
                let (mass_above, f_top) = d.force_affine(j, mode);
                Guard::Stuck {
                    mass_above,
                    f_top,
                    cap: stick_capacity(sys, j),
                }
            } else {
                let sign = mode.contact[j].slip_sign();
                d.slip_sign[lo] = sign;
                Guard::Slip { hi, lo, sign }
            };
            d.n_guards += 1;
        }
        let guards = &d.guards[..d.n_guards];
        if guards.iter().any(|g| matches!(g, Guard::Stuck { .. })) {
            d.stick_band = Some(safe_accel_band(guards));
        }
    }

    /// The clusters, masses and forces of `mode` only, without its guards
    /// (the part `cluster_law` follows operation for operation).
    pub fn clusters(sys: &System, mode: &Mode) -> Dynamics {
        let mut d = Dynamics {
            n_clusters: 0,
            cluster_of: [0; MAX_BODIES],
            bottom: [0; MAX_BODIES],
            top: [0; MAX_BODIES],
            mass: [0.0; MAX_BODIES],
            slip_load: [0.0; MAX_BODIES],
            slip_force: [0.0; MAX_BODIES],
            mass_above: [0.0; MAX_BODIES],
            accel_const: [0.0; MAX_BODIES],
            inv_mass0: 0.0,
            ag_gain: 0.0,
            load_accel0: 0.0,
            support_force: 0.0,
            prescribed: sys.prescribed(),
            changing_guards: 0,
            stuck_guards: 0,
            guards: [Guard::Slip {
                hi: 0,
                lo: 0,
                sign: 0.0,
            }; MAX_BODIES],
            n_guards: 0,
            moving: [Moving { j: 0, hi: 0, lo: 0 }; MAX_BODIES],
            n_moving: 0,
            stick_band: None,
            slip_sign: [0.0; MAX_BODIES],
        };
        for i in 0..sys.n + 1 {
            if i == 0 || !mode.is_stuck(i) {
                d.n_clusters += 1;
                d.bottom[d.n_clusters - 1] = i;
            }
            let c = d.n_clusters - 1;
            d.cluster_of[i] = c;
            d.top[c] = i;
            d.mass[c] += sys.mass[i];
        }
        for j in 1..sys.n + 1 {
            let f = -sys.muk[j] * sys.normal[j] * mode.contact[j].slip_sign();
            d.slip_force[j] = f;
            if !mode.is_stuck(j) {
                d.slip_load[d.cluster_of[j]] += f;
                d.slip_load[d.cluster_of[j - 1]] -= f;
            }
        }
        for c in 1..d.n_clusters {
            d.accel_const[c] = d.slip_load[c] / d.mass[c];
        }
        if sys.prescribed() {
            // The support's cluster (possibly of no mass) moves at `g ag +
            // c`: `ag` itself in the reference mode (g = 1, c = 0).
            let (gain, c) = support_law(sys, d.mass[0], d.slip_load[0]);
            (d.inv_mass0, d.ag_gain) = (0.0, gain);
            // (c = 0: the value before the law, a zero of either sign.)
            d.load_accel0 = if c != 0.0 {
                c
            } else {
                d.slip_load[0] * d.inv_mass0
            };
            d.support_force = d.mass[0] * c - d.slip_load[0];
        } else {
            d.accel_const[0] = d.slip_load[0] / d.mass[0];
            d.inv_mass0 = 1.0 / d.mass[0];
            d.load_accel0 = d.slip_load[0] * d.inv_mass0;
        }
        for c in 0..d.n_clusters {
            let mut above = 0.0;
            for j in (d.bottom[c]..d.top[c] + 1).rev() {
                above += sys.mass[j];
                d.mass_above[j] = above;
            }
        }
        d
    }

    /// Force of the spring, the damper and `fext` on the structure.
    #[inline]
    pub fn structure_load(sys: &System, u0: f64, v0: f64, fext: f64) -> f64 {
        fext - sys.k * u0 - sys.c * v0
    }

    /// The structure cluster's load as [`Dynamics::accel0`] takes it (the
    /// `load0` of every method here): on a structure the force of the
    /// spring, the damper and `fext` (N); on a prescribed support the input
    /// `ag` (m/s2), the support's acceleration in the reference mode.
    #[inline]
    pub fn load0(sys: &System, u0: f64, v0: f64, ag: f64, fext: f64) -> f64 {
        if sys.prescribed() {
            ag
        } else {
            Dynamics::structure_load(sys, u0, v0, fext)
        }
    }

    /// The part of the structure cluster's absolute acceleration that the
    /// inputs make: `fext / M0` on a structure, `g ag` on a prescribed
    /// support. Its acceleration is this plus `load_accel0 - (k u0 + c v0)
    /// / M0` (`k = c = 0` on a prescribed support): the rule the
    /// integrators use, written here once (their forcing relative to the
    /// input frame is this minus `ag` plus `load_accel0`, exactly 0 on a
    /// prescribed support in its reference mode).
    #[inline(always)]
    pub fn input_accel(&self, ag: f64, fext: f64) -> f64 {
        self.input_rule::<true>().accel(ag, fext)
    }

    /// [`Dynamics::input_accel`]'s rule in registers, for the loops that
    /// apply it at every substep. `AG = false` is for a structure only,
    /// where `ag_gain` is 0: `ag`'s term (an exact zero) is left out at
    /// compile time, so the structure's substep does not pay for the
    /// support's term.
    #[inline(always)]
    pub fn input_rule<const AG: bool>(&self) -> InputRule<AG> {
        debug_assert!(AG || (self.ag_gain == 0.0 && !self.prescribed));
        InputRule {
            inv_mass0: self.inv_mass0,
            ag_gain: self.ag_gain,
        }
    }
    /// Absolute acceleration of cluster `c`; `load0` is the structure load
    /// (used only by cluster 0).
    #[inline]
    pub fn accel(&self, c: usize, load0: f64) -> f64 {
        if c == 0 {
            self.accel0(load0)
        } else {
            self.accel_const[c]
        }
    }

    /// Absolute acceleration of the structure's cluster: `(slip load +
    /// load0) / M0` on a structure, `g ag + c` on a prescribed support
    /// (`load0 = ag`, [`Dynamics::load0`]; [`support_law`]).
    #[inline]
    pub fn accel0(&self, load0: f64) -> f64 {
        if self.prescribed {
            support_accel(self.ag_gain, self.load_accel0, load0)
        } else {
            (self.slip_load[0] + load0) * self.inv_mass0
        }
    }

    /// Rate of the structure cluster's absolute acceleration `A0` at
    /// velocity `v0` and acceleration `accel0`: the inputs' rates through
    /// the input rule, less the spring's and the damper's, `(k v0 + c (A0 -
    /// ag)) / M0` (`k = c = 0` on a prescribed support).
    #[inline]
    pub fn accel0_rate(
        &self,
        sys: &System,
        [v0, accel0, ag]: [f64; 3],
        [ag_rate, fext_rate]: [f64; 2],
    ) -> f64 {
        (fext_rate - sys.k * v0 - sys.c * (accel0 - ag)) * self.inv_mass0 + ag_rate * self.ag_gain
    }

    /// The force the stack puts on body 0 (the structure or the support)
    /// along +x: `-F_1` (0 without blocks).
    pub fn floor_force(&self, mode: &Mode, load0: f64) -> f64 {
        if mode.n == 0 {
            0.0
        } else {
            -self.force(1, mode, load0)
        }
    }

    /// Mass of the blocks stuck to body 0 (its cluster without it), kg.
    pub fn attached_mass(&self, mode: &Mode) -> f64 {
        if mode.n >= 1 && mode.is_stuck(1) {
            self.mass_above[1]
        } else {
            0.0
        }
    }

    /// `floor_force + attached_mass A0`: the force of the first slipping
    /// interface above the attached blocks on them (`-F_{k+1}`, 0 if none),
    /// or `floor_force` itself while interface 1 slips. Constant in a mode.
    pub fn sliding_force(&self, mode: &Mode) -> f64 {
        if mode.n == 0 {
            0.0
        } else {
            0.0 - self.force_affine(1, mode).1
        }
    }

    /// Friction force of interface j (force of body j-1 on body j).
    #[inline]
    pub fn force(&self, j: usize, mode: &Mode, load0: f64) -> f64 {
        let (mass_above, f_top) = self.force_affine(j, mode);
        if mode.is_stuck(j) {
            mass_above * self.accel(self.cluster_of[j], load0) + f_top
        } else {
            f_top
        }
    }

    /// The force of interface j as `a A + b`, A the absolute acceleration of
    /// its upper body's cluster: for a stuck interface the bodies j..=top move
    /// with the cluster, so F_j = M_above A + F_{top+1}; a slipping or free
    /// one carries its constant friction force (a = 0).
    #[inline]
    pub fn force_affine(&self, j: usize, mode: &Mode) -> (f64, f64) {
        if mode.is_stuck(j) {
            let above = self.top[self.cluster_of[j]] + 1;
            let f_top = if above <= mode.n {
                self.slip_force[above]
            } else {
                0.0
            };
            (self.mass_above[j], f_top)
        } else {
            (0.0, self.slip_force[j])
        }
    }

    /// Relative absolute acceleration of interface j (body j minus body j-1).
    pub fn rel_accel(&self, j: usize, load0: f64) -> f64 {
        self.accel(self.cluster_of[j], load0) - self.accel(self.cluster_of[j - 1], load0)
    }
}

/// The law of a prescribed support's cluster in a mode whose cluster on the
/// support has mass `mass` (`M'`, the blocks stuck to it) and constant load
/// `load` (`s'`, from the first slipping interface above it): its absolute
/// acceleration is `g ag + c` ([`support_accel`]) with
///
/// `g = (1 + m_b M_ref) / (1 + m_b M')`, `c = m_b (s' - s_ref) / (1 + m_b M')`,
///
/// `m_b` the support's mobility and `(M_ref, s_ref)` those of the reference
/// mode ([`System::ref_mass`]). The master's input `ag` is its floor's
/// acceleration under the stack's force of the reference mode, `F_ref = -M_ref
/// ag + s_ref`; the rest of its model pushes the floor (mass `1 / m_b`) with
/// `P = ag / m_b - F_ref`, and in a mode with `(M', s')` the floor carrying
/// the stack moves at `(P + s') m_b / (1 + m_b M')`: the expression above,
/// linear in `ag`, holding continuously until the inputs are next set. In
/// the reference mode, or with `m_b = 0`, `g = 1` and `c = 0` exactly. The
/// one rule of the resolver (`cluster_law`) and of every integrator
/// (through [`Dynamics`]). (docs/model-and-numerics.md, "A stack on a
/// prescribed support".)
#[inline]
pub fn support_law(sys: &System, mass: f64, load: f64) -> (f64, f64) {
    let mb = sys.mobility;
    let den = 1.0 + mb * mass;
    (
        (1.0 + mb * sys.ref_mass) / den,
        mb * (load - sys.ref_load) / den,
    )
}

/// `g ag + c` ([`support_law`]): `ag` itself, bit for bit, when `g = 1`
/// and `c = 0`.
#[inline(always)]
pub fn support_accel(gain: f64, c: f64, ag: f64) -> f64 {
    if gain == 1.0 && c == 0.0 {
        ag
    } else {
        gain * ag + c
    }
}

/// Numerical slack of the consistency checks, relative to the natural scale
/// of each quantity (`mus N` for forces, `g` for accelerations).
pub const CONSISTENCY_TOL: f64 = 1e-10;

/// Largest stick force interface j holds before a guard fires: `mus N`
/// with the consistency slack, so that a stick the resolver accepted
/// starts with a guard >= 0 (docs/model-and-numerics.md, "Events").
pub fn stick_capacity(sys: &System, j: usize) -> f64 {
    sys.mus[j] * sys.normal[j] * (1.0 + CONSISTENCY_TOL)
}

/// Largest violation of the contact law by `mode` at an instant, among the
/// interfaces in `zero` (bit j set: relative velocity exactly zero). Zero
/// or negative means consistent.
pub fn violation(sys: &System, mode: &Mode, zero: u32, load0: f64) -> f64 {
    let zero = zero & !sys.free;
    let (mut worst, mut bottom, mut accel_below) = (f64::NEG_INFINITY, 0, 0.0);
    for end in 1..sys.n + 2 {
        if end <= sys.n && mode.is_stuck(end) {
            continue;
        }
        let ends = [bottom, end];
        let (accel, w) = cluster_law(sys, mode, zero, load0, ends, accel_below, f64::INFINITY);
        worst = worst.max(w);
        (bottom, accel_below) = (end, accel);
    }
    worst
}

/// Whether `mode` satisfies the contact law at the interfaces of `zero`
/// (free ones excluded by the caller): [`violation`] `<= CONSISTENCY_TOL`,
/// decided cluster by cluster with the same [`cluster_law`], skipping the
/// clusters that decide nothing (no interface of `zero` at their bottom,
/// inside, or at their top, where the cluster above needs their
/// acceleration) and stopping at the first that breaks the law.
#[inline(always)]
fn consistent(sys: &System, mode: &Mode, zero: u32, load0: f64) -> bool {
    let (mut bottom, mut accel_below) = (0, 0.0);
    // The clusters' tops (bits 1..=n + 1 not stuck), up to the last `zero` decides.
    let mut ends = mode.cluster_ends();
    while ends != 0 && zero >> bottom != 0 {
        let end = ends.trailing_zeros() as usize;
        ends &= ends - 1;
        // Bits bottom..=end (bit 0 and bit n + 1 are never in `zero`).
        let span = (2u32 << end) - (1u32 << bottom);
        if zero & span != 0 {
            let ends = [bottom, end];
            let (accel, w) =
                cluster_law(sys, mode, zero, load0, ends, accel_below, CONSISTENCY_TOL);
            if w > CONSISTENCY_TOL {
                return false;
            }
            accel_below = accel;
        }
        bottom = end;
    }
    true
}

/// The contact law on one cluster of `mode`, bodies `bottom..end` (the
/// interface `end` above it slips, is free, or is the top of the stack):
/// its absolute acceleration, and the largest violation among the
/// interfaces of `zero` it decides — the slip at its bottom against the
/// cluster below (absolute acceleration `accel_below`), and its stuck
/// interfaces inside (`-inf`: none). Consistent means `<= CONSISTENCY_TOL`.
/// The one place this law is written: [`violation`] takes it cluster by
/// cluster, the resolver's walk as each cluster closes. The arithmetic is
/// that of [`Dynamics::clusters`] and [`Dynamics::force`], operation for
/// operation (the masses are `System`'s tables of the same sums).
///
/// On a prescribed support the cluster on it (blocks of mass `M'`, load `s'`
/// from the interface above) moves by [`support_law`] (`load0 = ag`), as
/// the integrators move it afterwards.
///
/// The interfaces are taken from the bottom up and the search stops once the violation exceeds
/// `enough`: a caller that only asks whether the law holds passes `CONSISTENCY_TOL` (most clusters
/// a walk tries fail at once; a stick within its limit, violation <= 0, is passed over), one that
/// ranks violations `f64::INFINITY` (the largest).
#[inline(always)]
fn cluster_law(
    sys: &System,
    mode: &Mode,
    zero: u32,
    load0: f64,
    [bottom, end]: [usize; 2],
    accel_below: f64,
    enough: f64,
) -> (f64, f64) {
    let slip_force = |j: usize| -sys.muk[j] * sys.normal[j] * mode.contact[j].slip_sign();
    let mass = sys.mass_up[bottom][end];
    let mut load = 0.0;
    if bottom >= 1 {
        load += slip_force(bottom);
    }
    let f_top = if end <= sys.n { slip_force(end) } else { 0.0 };
    if end <= sys.n {
        load -= f_top;
    }
    let accel = if bottom == 0 {
        if sys.prescribed() {
            let (gain, c) = support_law(sys, mass, load);
            support_accel(gain, c, load0)
        } else {
            (load + load0) * (1.0 / mass)
        }
    } else {
        load / mass
    };
    let mut worst = f64::NEG_INFINITY;
    if bottom >= 1 && zero & (1 << bottom) != 0 {
        worst = -mode.contact[bottom].slip_sign() * (accel - accel_below) / sys.g;
    }
    let mut inside = zero & ((1u32 << end) - 1) & !((2u32 << bottom) - 1);
    while inside != 0 {
        if worst > enough {
            break; // decided: the rest cannot lower it
        }
        let i = inside.trailing_zeros() as usize;
        inside &= inside - 1;
        let limit = sys.mus[i] * sys.normal[i];
        let force = sys.mass_down[i][end] * accel + f_top;
        if force.abs() > limit || enough == f64::INFINITY {
            worst = worst.max((force.abs() - limit) / limit);
        }
    }
    (accel, worst)
}

/// The force of stuck interface `j` of `mode` (body j-1 on body j) under
/// the structure load `load0`, as [`cluster_law`] and [`Dynamics::force`] have
/// it, along a walk up the stack of one mode ([`body_accel`]).
#[inline(always)]
fn stuck_force_up(sys: &System, mode: &Mode, load0: f64, j: usize, last: &mut Met) -> f64 {
    let (end, accel) = body_accel(sys, mode, load0, j, last);
    let f_top = if end <= sys.n {
        -sys.muk[end] * sys.normal[end] * mode.contact[end].slip_sign()
    } else {
        0.0
    };
    sys.mass_down[j][end] * accel + f_top
}

/// The set bits of `m` (interfaces of a mask), from the lowest.
fn bits(mut m: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        let j = m.trailing_zeros() as usize;
        m &= m.wrapping_sub(1);
        (j < 32).then_some(j)
    })
}

/// A cluster met on a walk up the stack: the interface above it, its
/// absolute acceleration.
type Met = (usize, f64);

/// The interface above the cluster of `mode` that holds body `i` and the
/// cluster's absolute acceleration by [`cluster_law`] (as [`Dynamics::accel`]
/// has it), along a walk up the stack (`i` never decreasing): `last`, the
/// cluster met last, is taken again only past its top.
#[inline(always)]
fn body_accel(sys: &System, mode: &Mode, load0: f64, i: usize, last: &mut Met) -> Met {
    if i >= last.0 {
        let [bottom, end] = span_around(mode.cluster_ends(), i);
        let (accel, _) = cluster_law(sys, mode, 0, load0, [bottom, end], 0.0, f64::INFINITY);
        *last = (end, accel);
    }
    *last
}

/// What the resolution is asked to decide.
#[derive(Clone, Copy, Debug)]
pub struct ResolveRequest {
    /// Current mode; the contacts of interfaces not in `zero` are kept.
    pub mode: Mode,
    /// Interfaces with zero relative velocity (bit j), free ones excluded.
    pub zero: u32,
    /// Interfaces whose stick force has just reached `mus N`: they may not stay stuck.
    pub must_break: u32,
    /// Interfaces that were stuck before this instant (preferred to stay so).
    pub was_stuck: u32,
    /// Structure load (spring, damper, external force) at this instant; on a
    /// prescribed support the input `ag` ([`Dynamics::load0`]).
    pub load0: f64,
}

impl ResolveRequest {
    /// Whether `mode` keeps a stick of `must_break` at its limit, `|F| >= mus N (1 - 1e-8)`: the
    /// state just left, consistent or not by rounding, no rival. Its guard fired at `mus N (1 +
    /// 1e-10)` within 1e-12 s, so `|F|` within 1e-9 of it; a slip elsewhere relieves by percents.
    pub fn keeps_breaking(&self, sys: &System, mode: &Mode) -> bool {
        let (breaking, mut last) = (self.zero & self.must_break, (0, 0.0));
        let limit = |j: usize| sys.mus[j] * sys.normal[j] * (1.0 - 1e-8);
        let mut kept = bits(breaking & mode.stuck_mask());
        kept.any(|j| stuck_force_up(sys, mode, self.load0, j, &mut last).abs() >= limit(j))
    }

    /// Rule 1 where sticks reach `mus N` together: of the sticks of `zero` whose force over `mus
    /// N` equals a breaking one's to 1e-12, the lowest must break instead, and the others may
    /// stay stuck: the stack above slides as one, as it does with μs = μk. Which guard fired
    /// first is rounding; this makes one call and the same input cut in pieces agree. Such ties
    /// come from equal μs (a stuck stack's forces over `mus N` are one acceleration over μs g):
    /// they are looked for only where a breaking stick is one of [`System::shared_mus`].
    #[inline(always)]
    fn with_tied_breaks_lowest(mut self, sys: &System) -> ResolveRequest {
        if self.must_break & self.zero & sys.shared_mus != 0 {
            self.must_break = self.tied_breaks_lowest(sys);
        }
        self
    }

    /// [`ResolveRequest::with_tied_breaks_lowest`]'s `must_break` (out of line: rare).
    #[inline(never)]
    fn tied_breaks_lowest(&self, sys: &System) -> u32 {
        let sticks = self.zero & self.mode.stuck_mask() & !sys.free;
        let (breaking, mut last) = (sticks & self.must_break, (0, 0.0));
        let mut ratio = [f64::NAN; MAX_BODIES];
        for j in bits(sticks) {
            let f = stuck_force_up(sys, &self.mode, self.load0, j, &mut last);
            ratio[j] = f.abs() / (sys.mus[j] * sys.normal[j]);
        }
        let tied = |b: usize| bits(sticks).find(|&j| (ratio[j] - ratio[b]).abs() <= 1e-12);
        let lowest = bits(breaking).fold(0, |m, b| m | 1 << tied(b).unwrap_or(b));
        self.must_break & !breaking | lowest
    }
}

/// Outcome of a resolution.
#[derive(Clone, Copy, Debug)]
pub struct Resolved {
    /// The mode found.
    pub mode: Mode,
    /// False when no assignment satisfied the contact law within
    /// [`CONSISTENCY_TOL`] and the least violating one was taken.
    pub consistent: bool,
    /// Whether the rule chose among several consistent assignments (rivals, mus > muk only),
    /// none keeping a stick of `must_break` at its limit ([`ResolveRequest::keeps_breaking`]).
    pub ambiguous: bool,
    /// Assignments tried (the work of the resolution).
    pub tries: u32,
}

/// Finds a consistent mode: every interface in `zero` is stuck, or starts
/// slipping in a direction its relative acceleration agrees with.
///
/// Selection rule (needed when mus > muk, where several assignments can be
/// consistent; for mus = muk the consistent assignment is unique):
/// 1. interfaces in `must_break` do not stay stuck (unless nothing else is consistent);
/// 2. the largest number of stuck interfaces wins;
/// 3. then the largest number of interfaces that were stuck before;
/// 4. then the first in enumeration order ([`resolve_by_enumeration`]),
///    which prefers sticking lower interfaces and slipping forward.
///
/// The consistent assignments are found by a walk up the stack that closes
/// each cluster as soon as both its ends are chosen and drops every branch
/// whose closed clusters already break the contact law: the contact law of
/// a cluster's stuck interfaces depends only on that cluster, and that of a
/// slip only on the two clusters it separates. Where no assignment is
/// consistent, the enumeration of all 3^k picks the least violating one.
pub fn resolve(sys: &System, req: &ResolveRequest) -> Resolved {
    let req = &req.with_tied_breaks_lowest(sys);
    resolve_most_stuck(sys, req, 0..1)
        .or_else(|| resolve_cascade(sys, req))
        .or_else(|| resolve_most_stuck(sys, req, 1..3))
        .unwrap_or_else(|| resolve_by_walk(sys, req))
}

/// [`resolve`] for a cascade with mus = muk: from all of `zero` stuck (where none must break, level
/// 0 of [`resolve_most_stuck`], taken as it is), the stick most over its static limit slips the way
/// its force drives it, until the contact law holds: the walk's assignment where
/// [`only_consistent`] proves it unique.
#[inline(never)]
fn resolve_cascade(sys: &System, req: &ResolveRequest) -> Option<Resolved> {
    let (zero, mut mode) = (req.zero & !sys.free, req.mode);
    sys.equal_friction(zero).then_some(())?;
    bits(zero & sys.interfaces()).for_each(|j| mode.contact[j] = Contact::Stuck);
    for tries in 1..zero.count_ones() + 2 {
        if consistent(sys, &mode, zero, req.load0) {
            let (consistent, ambiguous) = (true, false);
            let res = Resolved {
                mode,
                consistent,
                ambiguous,
                tries,
            };
            let first = tries == 1 && zero & req.must_break == 0;
            return (first || only_consistent(sys, &mode, zero, req.load0, zero)).then_some(res);
        }
        let (mut j, mut x, mut last) = (0, 1.0f64, (0, 0.0));
        for i in bits(zero & mode.stuck_mask()) {
            let f = stuck_force_up(sys, &mode, req.load0, i, &mut last);
            let f = f / (sys.mus[i] * sys.normal[i]);
            (j, x) = if f.abs() > x.abs() { (i, f) } else { (j, x) };
        }
        (j > 0).then_some(())?;
        mode.contact[j] = Contact::slip(x > 0.0);
    }
    None
}

/// [`resolve`] where [`resolve_most_stuck`] and [`resolve_cascade`] do not
/// decide: the walk (out of line: the usual switch runs compact code).
#[inline(never)]
fn resolve_by_walk(sys: &System, req: &ResolveRequest) -> Resolved {
    let walk = Walk::new(sys, req);
    let search = walk.search(true, u32::MAX);
    let Some((_, mode)) = search.best else {
        let mut all = resolve_by_enumeration(sys, req);
        all.tries += search.tries;
        return all;
    };
    // Several rivals (the rule decided); the bounded walk may have skipped
    // the others.
    let equal = sys.equal_friction(req.zero);
    let (ambiguous, tries) = match search.count {
        0 | 1 => ambiguity(sys, req, &mode),
        _ => (!equal, 0),
    };
    Resolved {
        mode,
        consistent: true,
        ambiguous,
        tries: search.tries + tries,
    }
}

/// Most switches, decided without the walk: every interface of `zero` stuck but those of
/// `must_break` (at most two) and `more` others, for each `more` of `levels` (the levels below
/// failed), in the rule's order: no assignment without a stick of `must_break` keeps more stuck
/// (rules 1, 2), the extra slips go through those not stuck before first (rule 3), the highest
/// first (rule 4's stuck bits), the directions by their bits (rule 4's rest). The first consistent
/// is the walk's, with its [`ambiguity`]; `None`: none, or not covered (level 0 with mus = muk and
/// none breaking, all stuck: the cascade's first try).
#[inline(always)]
fn resolve_most_stuck(sys: &System, req: &ResolveRequest, levels: Range<u32>) -> Option<Resolved> {
    let zero = req.zero & !sys.free;
    let breaking = zero & req.must_break;
    let cascade = levels.start == 0 && breaking == 0 && sys.equal_friction(zero);
    if breaking.count_ones() > 2 || cascade {
        return None;
    }
    let mut stuck = req.mode;
    bits(zero & sys.interfaces()).for_each(|j| stuck.contact[j] = Contact::Stuck);
    let others = zero & !breaking;
    // The interfaces of `set` from the top (bits), or a 0 alone if `none`.
    let top = |set: u32| (set != 0).then(|| 1u32 << (31 - set.leading_zeros()));
    let picks = move |set: u32, none: bool| {
        let set = if none { 0 } else { set };
        let down = std::iter::successors(top(set), move |&b| top(set & (b - 1)));
        none.then_some(0).into_iter().chain(down)
    };
    let mut tries = 0;
    for more in levels {
        for lost in 0..more + 1 {
            for hi in picks(others, more == 0) {
                for lo in picks(others & hi.wrapping_sub(1), more < 2) {
                    if ((hi | lo) & req.was_stuck).count_ones() != lost {
                        continue;
                    }
                    let slips = breaking | hi | lo;
                    // Slip directions as the rule's bits (backward = 1, from the bottom).
                    for code in 0u32..1 << slips.count_ones() {
                        let (mut mode, mut rest, mut bits) = (stuck, slips, code);
                        while rest != 0 {
                            let j = rest.trailing_zeros() as usize;
                            mode.contact[j] = Contact::slip(bits & 1 == 1);
                            (rest, bits) = (rest & (rest - 1), bits >> 1);
                        }
                        tries += 1;
                        if consistent(sys, &mode, zero, req.load0) {
                            let (ambiguous, more_tries) = ambiguity(sys, req, &mode);
                            return Some(Resolved {
                                mode,
                                consistent: true,
                                ambiguous,
                                tries: tries + more_tries,
                            });
                        }
                    }
                }
            }
        }
    }
    None
}

/// The ambiguity of the chosen `mode` and its tries: none where mus = muk or [`only_consistent`]
/// leaves only rivals sticking a slip of `must_break` (a free one in `zero` fails it) with none
/// in `mode`; with one, around `mode` with it stuck (their terms there are zero), only that one,
/// a rival unless at its limit ([`ResolveRequest::keeps_breaking`]); one stick slipped the way its
/// force drives it past `muk N` if consistent; else the unbounded walk. (Inlined: sweep 7% slower.)
#[inline(never)]
fn ambiguity(sys: &System, req: &ResolveRequest, mode: &Mode) -> (bool, u32) {
    if sys.equal_friction(req.zero) {
        return (false, 0);
    }
    let (zero, load0, mut stuck) = (req.zero & !sys.free, req.load0, *mode);
    let others = zero & !req.must_break;
    let slips = zero & req.must_break & !mode.stuck_mask();
    if slips.count_ones() < 2 && only_consistent(sys, mode, req.zero, load0, others) {
        if slips == 0 {
            return (false, 0);
        }
        stuck.contact[slips.trailing_zeros() as usize] = Contact::Stuck;
        if consistent(sys, &stuck, zero & !slips, load0)
            && only_consistent(sys, &stuck, req.zero & !slips, load0, others)
        {
            let rival = consistent(sys, &stuck, zero, load0) && !req.keeps_breaking(sys, &stuck);
            return (rival && !req.keeps_breaking(sys, mode), 2);
        }
    }
    let (mut tries, mut last, counted) = (0, (0, 0.0), !req.keeps_breaking(sys, mode));
    for j in bits(if counted { zero & mode.stuck_mask() } else { 0 }) {
        let force = stuck_force_up(sys, mode, load0, j, &mut last);
        if force.abs() > sys.muk[j] * sys.normal[j] {
            let mut rival = *mode;
            rival.contact[j] = Contact::slip(force > 0.0);
            tries += 1;
            if consistent(sys, &rival, zero, load0) && !req.keeps_breaking(sys, &rival) {
                return (true, tries);
            }
        }
    }
    // The unbounded walk, to a second rival.
    let all = Walk::new(sys, req).search(false, 2);
    (all.count > 1, tries + all.tries)
}

/// Whether no consistent assignment differs from `mode` at `ifaces` by
/// slipped sticks, reversed slips or stuck slips of `sticking`, `mode`
/// consistent there. A rival's force changes `g` move the bodies by `da`:
/// `Q = Σ m da² = Σ g_i dr_i` (Newton, by parts), each term at most `4 muk N
/// eps g`, or `(mus N (1 + eps) - muk N) r` where a slip sticks (`r > 0` its
/// relative acceleration); a difference needs `Q M` (`M` the blocks' mass) at
/// least `(muk N - |F|)²` (a stick slipping), `(2 muk N)²` (a slip reversing)
/// or `M r² min(m_i, m_(i-1)) / 2` (a slip sticking): each twice the bound.
fn only_consistent(sys: &System, mode: &Mode, ifaces: u32, load0: f64, sticking: u32) -> bool {
    let (eps, mass) = (CONSISTENCY_TOL, sys.mass_up[1][sys.n + 1]);
    let (mut bound, mut need) = (0.0, f64::INFINITY);
    let mut last = (0, 0.0);
    bits(ifaces & sys.interfaces()).all(|j| {
        let k = sys.muk[j] * sys.normal[j];
        bound += 4.0 * k * eps * sys.g;
        need = need.min(if mode.is_stuck(j) {
            let margin = (k - stuck_force_up(sys, mode, load0, j, &mut last).abs()).max(0.0);
            margin * margin
        } else if sticking & (1 << j) != 0 {
            // Its relative acceleration: only the two clusters it separates.
            let below = body_accel(sys, mode, load0, j - 1, &mut last).1;
            let rel = body_accel(sys, mode, load0, j, &mut last).1 - below;
            let r = (mode.contact[j].slip_sign() * rel).max(0.0);
            bound += (sys.mus[j] * sys.normal[j] * (1.0 + eps) - k) * r;
            (4.0 * k * k).min(0.5 * sys.mass[j].min(sys.mass[j - 1]) * mass * r * r)
        } else {
            4.0 * k * k
        });
        need > 2.0 * bound * mass // (a NaN fails)
    })
}

/// The state of a walk: the best consistent assignment so far and how many
/// rivals ([`Resolved::ambiguous`]) were found; `bound`: drop branches that
/// cannot beat the best on the rule's first two criteria; `limit`: stop
/// after so many.
struct Search {
    /// The assignment being built (every contact of the walk's branch).
    mode: Mode,
    best: Option<(Key, Mode)>,
    count: u32,
    bound: bool,
    limit: u32,
    /// Clusters closed (the walk's work, as the enumeration's tries).
    tries: u32,
}

/// Rank of a consistent assignment under the selection rule (smaller wins):
/// a stuck interface of `must_break`, minus the stuck count, minus the kept
/// count, then the enumeration order (stuck set, then slip directions, as
/// bits over the interfaces in `zero` from the bottom).
type Key = (bool, i32, i32, u32, u32);

/// The walk of [`resolve`] over the interfaces in `zero`.
struct Walk<'a> {
    sys: &'a System,
    req: &'a ResolveRequest,
    /// Position in the list of interfaces in `zero` (bit index) of each
    /// interface, or `usize::MAX` for the others (their contact is kept).
    index: [usize; MAX_BODIES],
    /// Number of interfaces in `zero` from j up (entry n + 1: none).
    remaining: [i32; MAX_BODIES + 1],
    /// Of those, the ones that were stuck before (`was_stuck`).
    remaining_kept: [i32; MAX_BODIES + 1],
    /// The same two counts without the interfaces of `must_break` (a
    /// branch that keeps none of those stuck can only gain these).
    remaining_unbroken: [[i32; 2]; MAX_BODIES + 1],
    /// The contacts tried at each interface, in the order tried: the first
    /// `n_options` (three for an interface of `zero`, its kept contact
    /// alone for the others).
    options: [[Contact; 3]; MAX_BODIES],
    n_options: [usize; MAX_BODIES],
    /// The interfaces in `zero` with a contact to choose (bit j).
    zero_ifaces: u32,
}

/// A cluster being built: its bottom body, its mass so far, and the
/// absolute acceleration of the closed cluster below it.
#[derive(Clone, Copy)]
struct Open {
    bottom: usize,
    accel_below: f64,
}

impl<'a> Walk<'a> {
    fn new(sys: &'a System, req: &'a ResolveRequest) -> Walk<'a> {
        let mut index = [usize::MAX; MAX_BODIES];
        let mut k = 0;
        for (j, slot) in index.iter_mut().enumerate().take(sys.n + 1).skip(1) {
            if req.zero & (1 << j) != 0 && !sys.is_free(j) {
                *slot = k;
                k += 1;
            }
        }
        let (mut remaining, mut remaining_kept) = ([0; MAX_BODIES + 1], [0; MAX_BODIES + 1]);
        let mut remaining_unbroken = [[0; 2]; MAX_BODIES + 1];
        for j in (1..sys.n + 1).rev() {
            let in_zero = index[j] != usize::MAX;
            remaining[j] = remaining[j + 1] + i32::from(in_zero);
            let kept = in_zero && req.was_stuck & (1 << j) != 0;
            remaining_kept[j] = remaining_kept[j + 1] + i32::from(kept);
            let unbroken = req.must_break & (1 << j) == 0;
            let [u, k] = remaining_unbroken[j + 1];
            remaining_unbroken[j] = [
                u + i32::from(in_zero && unbroken),
                k + i32::from(kept && unbroken),
            ];
        }
        // The order changes only how soon the best is found (then the
        // bound drops most branches), never which it is (the key decides).
        // A stick that must break is tried slipping first, the way its
        // force drives it first; a slip that has just stopped, stuck first,
        // then the other way.
        // The force is that with every interface of `zero` stuck: a slip
        // that has just stopped is tried slipping first where it exceeds
        // the static limit there.
        use Contact::{SlipBackward as Back, SlipForward as Fwd, Stuck};
        let mut options = [[Stuck, Fwd, Back]; MAX_BODIES];
        let mut n_options = [3; MAX_BODIES];
        let zero_ifaces = (1..sys.n + 1)
            .filter(|&j| index[j] != usize::MAX)
            .fold(0, |m, j| m | (1 << j));
        let mut all_stuck = req.mode;
        for (j, c) in all_stuck.contact.iter_mut().enumerate() {
            if zero_ifaces & (1 << j) != 0 {
                *c = Stuck;
            }
        }
        for j in 1..sys.n + 1 {
            if index[j] == usize::MAX {
                (options[j][0], n_options[j]) = (req.mode.contact[j], 1);
                continue;
            }
            let breaks = req.must_break & (1 << j) != 0;
            let stopped = !breaks && req.was_stuck & (1 << j) == 0;
            if !(breaks || stopped) {
                continue;
            }
            let mode = if breaks { &req.mode } else { &all_stuck };
            let force = stuck_force_up(sys, mode, req.load0, j, &mut (0, 0.0));
            let slips = breaks || force.abs() > sys.mus[j] * sys.normal[j];
            options[j] = match (slips, force > 0.0) {
                (true, true) => [Back, Fwd, Stuck],
                (true, false) => [Fwd, Back, Stuck],
                (false, _) => [Stuck, Fwd, Back],
            };
        }
        Walk {
            sys,
            req,
            index,
            remaining,
            remaining_kept,
            remaining_unbroken,
            options,
            n_options,
            zero_ifaces,
        }
    }

    /// Walks the assignments: `bound`, and at most `limit` consistent ones.
    fn search(&self, bound: bool, limit: u32) -> Search {
        let mut search = Search {
            mode: self.req.mode,
            best: None,
            count: 0,
            bound,
            limit,
            tries: 0,
        };
        let open = Open {
            bottom: 0,
            accel_below: 0.0,
        };
        self.choose(1, open, (0, 0, false), &mut search);
        search
    }

    /// Whether every completion of a branch at interface `j` (`stuck` and
    /// `kept` so far below it, `broken`) ranks after the best found on the
    /// rule's first three criteria: it has at most `remaining` more stuck
    /// interfaces, at most `remaining_kept` more that were stuck before,
    /// and `broken` can only be lost.
    #[inline]
    fn beaten(&self, j: usize, (stuck, kept, broken): (i32, i32, bool), search: &Search) -> bool {
        match (search.bound, &search.best) {
            (true, Some((best, _))) => {
                // A best that keeps no stick of `must_break`: a branch that
                // keeps none either can gain only the other interfaces.
                let [more, more_kept] = if !broken && !best.0 {
                    self.remaining_unbroken[j]
                } else {
                    [self.remaining[j], self.remaining_kept[j]]
                };
                let most = (broken, -(stuck + more), -(kept + more_kept));
                most > (best.0, best.1, best.2)
            }
            _ => false,
        }
    }

    /// Chooses the contact of interface `j` (kept where it is not in
    /// `zero`); a stuck one extends the open cluster, any other closes it.
    /// `(stuck, kept, broken)`: the interfaces of `zero` stuck below `j`,
    /// those of them that were stuck before, and whether one of them is in
    /// `must_break`.
    fn choose(
        &self,
        j: usize,
        open: Open,
        (stuck, kept, broken): (i32, i32, bool),
        search: &mut Search,
    ) {
        if search.count >= search.limit {
            return;
        }
        // No completion beats the best on the first three criteria.
        if self.beaten(j, (stuck, kept, broken), search) {
            return;
        }
        let n = self.sys.n;
        if j > n {
            search.tries += 1;
            if self.close(open, n + 1, &search.mode).is_some() {
                search.count += u32::from(!self.req.keeps_breaking(self.sys, &search.mode));
                let key = self.key(&search.mode);
                if search.best.is_none_or(|(b, _)| key < b) {
                    search.best = Some((key, search.mode));
                }
            }
            return;
        }
        let in_zero = self.index[j] != usize::MAX;
        for &c in &self.options[j][..self.n_options[j]] {
            search.mode.contact[j] = c;
            if c == Contact::Stuck {
                let breaks = in_zero && self.req.must_break & (1 << j) != 0;
                let was = in_zero && self.req.was_stuck & (1 << j) != 0;
                let counted = (
                    stuck + i32::from(in_zero),
                    kept + i32::from(was),
                    broken || breaks,
                );
                self.choose(j + 1, open, counted, search);
            } else if self.beaten(j + 1, (stuck, kept, broken), search) {
                // The bound of the next interface, before the cluster is
                // closed: the branch is dropped as it would be there.
                continue;
            } else if let Some(accel) = {
                search.tries += 1;
                self.close(open, j, &search.mode)
            } {
                let next = Open {
                    bottom: j,
                    accel_below: accel,
                };
                self.choose(j + 1, next, (stuck, kept, broken), search);
            }
        }
        search.mode.contact[j] = self.req.mode.contact[j];
    }

    /// Closes the cluster from `open.bottom` to body `end - 1`: its
    /// absolute acceleration if it satisfies the contact law
    /// ([`cluster_law`]), `None` otherwise.
    #[inline(always)]
    fn close(&self, open: Open, end: usize, mode: &Mode) -> Option<f64> {
        let ends = [open.bottom, end];
        let (accel, worst) = cluster_law(
            self.sys,
            mode,
            self.zero_ifaces,
            self.req.load0,
            ends,
            open.accel_below,
            CONSISTENCY_TOL,
        );
        (worst <= CONSISTENCY_TOL).then_some(accel)
    }

    fn key(&self, mode: &Mode) -> Key {
        let (mut stuck_bits, mut signs, mut stuck_ifaces, mut s) = (0u32, 0u32, 0u32, 0);
        for j in 1..self.sys.n + 1 {
            let k = self.index[j];
            if k == usize::MAX {
                continue;
            }
            match mode.contact[j] {
                Contact::Stuck => {
                    stuck_bits |= 1 << k;
                    stuck_ifaces |= 1 << j;
                }
                c => {
                    if c == Contact::SlipBackward {
                        signs |= 1 << s;
                    }
                    s += 1;
                }
            }
        }
        (
            stuck_ifaces & self.req.must_break != 0,
            -(stuck_bits.count_ones() as i32),
            -((stuck_ifaces & self.req.was_stuck).count_ones() as i32),
            stuck_bits,
            signs,
        )
    }
}

/// [`resolve`] by enumerating every assignment, from the largest stick set
/// down: the selection rule's order written out, and the least violating
/// assignment where none is consistent.
pub fn resolve_by_enumeration(sys: &System, req: &ResolveRequest) -> Resolved {
    let req = &req.with_tied_breaks_lowest(sys);
    let mut zero_list = [0usize; MAX_BODIES];
    let mut k = 0;
    for j in 1..=sys.n {
        if req.zero & (1 << j) != 0 && !sys.is_free(j) {
            zero_list[k] = j;
            k += 1;
        }
    }
    let zero = &zero_list[..k];
    let mut fallback: Option<(f64, Mode)> = None;
    let mut tries = 0;
    for allow_breaking in [false, true] {
        for size in (0..=k).rev() {
            let mut best: Option<(u32, Mode)> = None;
            for stuck_bits in subsets_of_size(k, size) {
                let stuck_ifaces = bits_to_ifaces(stuck_bits, zero);
                if !allow_breaking && stuck_ifaces & req.must_break != 0 {
                    continue;
                }
                let kept = (stuck_ifaces & req.was_stuck).count_ones();
                if best.is_some_and(|(b, _)| b >= kept) {
                    continue;
                }
                let n_slip = k - size;
                for signs in 0u32..(1 << n_slip) {
                    let mut mode = req.mode;
                    let mut s = 0;
                    for (bit, &j) in zero.iter().enumerate() {
                        mode.contact[j] = if stuck_bits & (1 << bit) != 0 {
                            Contact::Stuck
                        } else {
                            s += 1;
                            if signs & (1 << (s - 1)) == 0 {
                                Contact::SlipForward
                            } else {
                                Contact::SlipBackward
                            }
                        };
                    }
                    let v = violation(sys, &mode, req.zero, req.load0);
                    tries += 1;
                    if v <= CONSISTENCY_TOL {
                        best = Some((kept, mode));
                        break;
                    }
                    if fallback.is_none_or(|(fv, _)| v < fv) {
                        fallback = Some((v, mode));
                    }
                }
            }
            if let Some((_, mode)) = best {
                let (count, count_tries) = consistent_count_and_tries(sys, req);
                return Resolved {
                    mode,
                    consistent: true,
                    ambiguous: count > 1,
                    tries: tries + count_tries,
                };
            }
        }
    }
    Resolved {
        mode: fallback.map_or(req.mode, |(_, m)| m),
        consistent: false,
        ambiguous: false,
        tries,
    }
}

/// Number of rivals ([`Resolved::ambiguous`]) among the assignments of the
/// interfaces in `req.zero`, by enumeration: the oracle of the tests. Only
/// mus > muk can make it exceed one: the 3^k modes are skipped otherwise.
pub fn consistent_count(sys: &System, req: &ResolveRequest) -> u32 {
    consistent_count_and_tries(sys, req).0
}

/// [`consistent_count`] and the assignments it tried (its work).
pub fn consistent_count_and_tries(sys: &System, req: &ResolveRequest) -> (u32, u32) {
    let mut list = [0usize; MAX_BODIES];
    let mut k = 0;
    for j in (1..=sys.n).filter(|&j| req.zero & (1 << j) != 0 && !sys.is_free(j)) {
        list[k] = j;
        k += 1;
    }
    let zero = &list[..k];
    if sys.equal_friction(req.zero) {
        return (1, 0);
    }
    let mut count = 0;
    let tries = 3u32.pow(k as u32);
    for code in 0..tries {
        let mut mode = req.mode;
        let mut rest = code;
        for &j in zero {
            mode.contact[j] =
                [Contact::Stuck, Contact::SlipForward, Contact::SlipBackward][(rest % 3) as usize];
            rest /= 3;
        }
        let v = violation(sys, &mode, req.zero, req.load0);
        count += u32::from(v <= CONSISTENCY_TOL && !req.keeps_breaking(sys, &mode));
    }
    (count, tries)
}

/// The `size`-element subsets of `k` items as bit masks, in increasing
/// numeric order (Gosper's hack): the order of a scan of `0..2^k` that keeps
/// the masks with `size` bits set, without scanning all of them.
fn subsets_of_size(k: usize, size: usize) -> impl Iterator<Item = u32> {
    let end = 1u32 << k;
    let mut next = Some(if size == 0 { 0 } else { (1u32 << size) - 1 });
    std::iter::from_fn(move || {
        let x = next?;
        next = if x == 0 {
            None
        } else {
            let low = x & x.wrapping_neg();
            let ripple = x + low;
            let y = (((ripple ^ x) >> 2) / low) | ripple;
            (y < end).then_some(y)
        };
        Some(x)
    })
}

/// Maps bit b of `bits` to interface `list[b]` as a bit mask over interfaces.
fn bits_to_ifaces(bits: u32, list: &[usize]) -> u32 {
    list.iter()
        .enumerate()
        .filter(|(b, _)| bits & (1 << b) != 0)
        .fold(0, |acc, (_, &j)| acc | (1 << j))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subsets_come_in_the_order_of_a_full_scan() {
        // Expected: the masks of 0..2^k with `size` bits set, in order.
        for k in 0..=8usize {
            for size in 0..=k {
                let scan: Vec<u32> = (0u32..1 << k)
                    .filter(|b| b.count_ones() as usize == size)
                    .collect();
                assert_eq!(
                    subsets_of_size(k, size).collect::<Vec<_>>(),
                    scan,
                    "{k} {size}"
                );
            }
        }
    }
}
