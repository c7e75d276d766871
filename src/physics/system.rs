//! Physical constants derived from validated [`Params`]: masses, stiffness,
//! damping and the normal force of every interface.

use crate::physics::params::{ParamError, Params, Support, MAX_BODIES};
use std::f64::consts::PI;

/// Body 0 is the structure; bodies 1..=n are blocks. Interface arrays are indexed by interface
/// number j = 1..=n (index 0 unused): interface j lies between body j-1 and body j.
///
/// On a prescribed support ([`Support::Prescribed`]) body 0 is the support, whose absolute
/// acceleration follows the input `ag`: `k = c = 0`, `mass[0] = 0` (the support's own mass is its
/// model's business; [`System::mobility`] stands for it, see [`crate::physics::mode::support_law`])
/// and `omega_p = 0` (no spring: the substeps do not follow from it, see `Simulator::map_step`).
#[derive(Clone, Debug)]
pub struct System {
    /// Number of blocks.
    pub n: usize,
    /// Mass of each body (kg): structure at 0, block j at j.
    pub mass: [f64; MAX_BODIES],
    /// Structure stiffness (N/m).
    pub k: f64,
    /// Structure damping coefficient (N s/m).
    pub c: f64,
    /// Gravitational acceleration (m/s2).
    pub g: f64,
    /// Normal force of interface j: g times the mass of blocks j..=n.
    pub normal: [f64; MAX_BODIES],
    /// Static friction coefficient of interface j.
    pub mus: [f64; MAX_BODIES],
    /// Kinetic friction coefficient of interface j.
    pub muk: [f64; MAX_BODIES],
    /// Interfaces (bit j) with no static friction ([`System::is_free`]).
    pub free: u32,
    /// Interfaces (bit j) whose static and kinetic friction differ.
    unequal: u32,
    /// Interfaces (bit j) whose static friction another interface has too, to 1e-9 (where
    /// sticks can reach their limits together: `ResolveRequest`'s rule for ties; `0.1 + 0.2` and
    /// `0.3` are one μs there).
    pub(crate) shared_mus: u32,
    /// Circular frequency of the bare structure, sqrt(k / mp); 0 on a prescribed support.
    pub omega_p: f64,
    /// What block 1 rests on.
    pub support: Support,
    /// The support's mobility `d(floor acceleration) / d(floor force)` (1/kg) of a prescribed
    /// support, in its law of motion ([`crate::physics::mode::support_law`]); 0 unless
    /// `Simulator::set_support_mobility` set it.
    pub mobility: f64,
    /// The reference mode of a prescribed support's law: the mass of its cluster on the support
    /// (`M_ref`, kg; the blocks stuck to it) and the constant load on that cluster (`s_ref`, N) in
    /// the mode in force when the master last set the inputs
    /// ([`crate::physics::mode::support_law`]). Set by the simulator; 0 until then.
    pub ref_mass: f64,
    /// See [`System::ref_mass`].
    pub ref_load: f64,
    /// `[a][e]`: mass of bodies a..e summed upwards from 0, in the order
    /// [`crate::physics::mode::Dynamics::clusters`] adds a cluster's mass.
    pub mass_up: [[f64; MAX_BODIES + 1]; MAX_BODIES],
    /// `[i][e]`: mass of bodies i..e summed downwards from body e - 1, in
    /// the order the mass above a stuck interface is added.
    pub mass_down: [[f64; MAX_BODIES + 1]; MAX_BODIES],
}

impl System {
    /// Validates `p` and derives the constants.
    pub fn new(p: &Params) -> Result<System, ParamError> {
        p.validate()?;
        let n = p.n_blocks;
        let prescribed = p.support == Support::Prescribed;
        let omega_p = if prescribed { 0.0 } else { 2.0 * PI / p.tp };
        let k = p.mp * omega_p * omega_p;
        let mut mass = [0.0; MAX_BODIES];
        let mut mus = [0.0; MAX_BODIES];
        let mut muk = [0.0; MAX_BODIES];
        mass[0] = if prescribed { 0.0 } else { p.mp };
        for j in 1..=n {
            mass[j] = p.alpha[j - 1] * p.mp;
            mus[j] = p.mus[j - 1];
            muk[j] = p.muk[j - 1];
        }
        let mut normal = [0.0; MAX_BODIES];
        let mut above = 0.0;
        for j in (1..=n).rev() {
            above += mass[j];
            normal[j] = p.g * above;
        }
        let mut mass_up = [[0.0; MAX_BODIES + 1]; MAX_BODIES];
        let mut mass_down = [[0.0; MAX_BODIES + 1]; MAX_BODIES];
        for (a, up) in mass_up.iter_mut().enumerate().take(n + 1) {
            let mut sum = 0.0;
            for e in a + 1..=n + 1 {
                sum += mass[e - 1];
                up[e] = sum;
            }
        }
        // Summed from `e - 1` down (its rounding is the masses' below `e`).
        #[allow(clippy::needless_range_loop)]
        for e in 1..=n + 1 {
            let mut sum = 0.0;
            for i in (0..e).rev() {
                sum += mass[i];
                mass_down[i][e] = sum;
            }
        }
        Ok(System {
            mass_up,
            mass_down,
            n,
            mass,
            k,
            c: if prescribed {
                0.0
            } else {
                2.0 * p.zeta * (k * p.mp).sqrt()
            },
            g: p.g,
            normal,
            free: (1..=n).fold(0, |m, j| m | u32::from(mus[j] == 0.0) << j),
            unequal: (1..=n).fold(0, |m, j| m | u32::from(mus[j] != muk[j]) << j),
            shared_mus: (1..=n).fold(0, |m, j| {
                let near = |i: usize| (mus[i] - mus[j]).abs() <= 1e-9 * mus[i].max(mus[j]);
                m | u32::from((1..=n).any(|i| i != j && near(i))) << j
            }),
            mus,
            muk,
            omega_p,
            support: p.support,
            mobility: 0.0,
            ref_mass: 0.0,
            ref_load: 0.0,
        })
    }

    /// Whether μs = μk at every interface of `zero` (free ones: both 0): then
    /// one assignment at most is consistent, and none is ambiguous.
    pub fn equal_friction(&self, zero: u32) -> bool {
        zero & self.unequal == 0
    }

    /// Every interface of the stack (bit j, 1..=n).
    pub fn interfaces(&self) -> u32 {
        (2u32 << self.n) - 2
    }

    /// An interface with no static friction transmits no force and never sticks.
    pub fn is_free(&self, j: usize) -> bool {
        self.free & (1 << j) != 0
    }

    /// Whether body 0 is a support whose acceleration is the input `ag`.
    #[inline(always)]
    pub fn prescribed(&self) -> bool {
        self.support == Support::Prescribed
    }

    /// Mass of the structure and all blocks (kg).
    pub fn total_mass(&self) -> f64 {
        self.mass[..=self.n].iter().sum()
    }
}
