//! The structure's cluster over one substep as its exact affine map: the
//! Taylor sum of exp(A h) to round-off.
//!
//! In one mode and one linear piece of excitation the structure's cluster is the linear system
//! `z' = A z` over `z = [u, v, p, p']`, where `p(τ)` is its forcing per unit mass relative to the
//! support (the mode's constant friction load and `Fext` over the cluster's mass, minus `ag`),
//! linear in time. `n` RK4 substeps of `h / n` compose into the matrix `T4(A h / n)^n` (`T4` the
//! degree-4 Taylor polynomial), which tends to `exp(A h)` as `n` grows; we take that limit
//! directly, as the Taylor sum of `exp(A h)` to round-off ([`degree`]: 15 at most where the substep
//! keeps `ω h <= 0.5` and ζ = 0.05). A substep is then one small matrix-vector product whatever the
//! accuracy asked.
//!
//! From the same Taylor terms, per mode and substep length: the integral of `u` (the input work is
//! bilinear in it and the inputs), the quadratic form of the viscous work `c ∫ v²`, and bounds on
//! the derivatives of `v` over the substep, which let the fast path prove that no guard changes
//! sign and that no peak is missed between the substep's ends.

use super::sweep::Rows;
use crate::physics::system::System;

/// Highest degree of the Taylor sum of `exp(A h)` ([`degree`]'s at
/// `ω h = 0.5` as ζ tends to 1, `ρ = 1.5`).
const MAX_DEGREE: usize = 21;
/// Extra terms kept for the derivative bounds (up to `v^(5)`).
const TERMS: usize = MAX_DEGREE + 6;
/// `1 / (n + 1)`, for the weights of `∫ v²`.
const RECIPROCALS: [f64; 2 * TERMS + 2] = {
    let mut r = [0.0; 2 * TERMS + 2];
    let mut n = 0;
    while n < r.len() {
        r[n] = 1.0 / (n + 1) as f64;
        n += 1;
    }
    r
};

/// `FALLING[m][k] = (k + 1) (k + 2) ... (k + m)`, for the derivative
/// bounds (exact integers: the products the build took one by one).
const FALLING: [[f64; TERMS + 1]; 6] = {
    let mut f = [[1.0; TERMS + 1]; 6];
    let mut m = 1;
    while m < 6 {
        let mut k = 0;
        while k <= TERMS {
            let mut x = k + 1;
            let mut p = 1.0;
            while x <= k + m {
                p *= x as f64;
                x += 1;
            }
            f[m][k] = p;
            k += 1;
        }
        m += 1;
    }
    f
};

/// Degree of the Taylor sum of `exp(A h) z`: the first `k >= 4` with `ρ^k / k! < 1e-16`,
/// `ρ = h max(ω + c/m, 1)`, at most `MAX_DEGREE`. In the energy's norm `|[ω u, v]|` the
/// oscillator's block of `A h` is at most `h (ω + c/m) <= ρ`, and the forcing enters as `h p` and
/// `h² p'`, so the terms past `k` sum to at most
/// `(2 + 2/ρ) Σ_(j>k) ρ^j / j! < 2e-16 (1 + ρ) / (k + 1 - ρ)`, about 4e-17, of
/// `max(|[ω u, v]|, (|p| + h |p'|) / (ω + c/m))` (the state and the forcing's static response over
/// the substep): below the rounding of the sums (1.1e-16). (`h (ω + c/m) <= 0.5 (1 + 2ζ) < 1.5`,
/// met by degree 21; a long substep of a slow structure, `ω + c/m < 1`, may take all 21 terms, more
/// than it needs.)
pub(super) fn degree(h: f64, w2: f64, cm: f64) -> usize {
    let rho = h * (w2.sqrt() + cm).max(1.0);
    let mut term = 1.0;
    for k in 1..MAX_DEGREE + 1 {
        term *= rho / k as f64;
        if term < 1e-16 && k >= 4 {
            return k;
        }
    }
    MAX_DEGREE
}
/// Largest `ω h` of a substep on the exact map (ω of the bare structure, the
/// highest of every mode).
pub(super) const MAP_H_OMEGA: f64 = 0.5;

/// Rounds `h` to 30 significant bits. Maps are built for the rounded length and the rest (at most
/// 1e-9 relative) carried to first order, so that the result does not depend on which pieces came
/// first (a restored saved state computes what the original run computed).
#[inline]
pub(super) fn canonical_length(h: f64) -> f64 {
    const DROP: u32 = 22;
    let bits = h.to_bits();
    f64::from_bits((bits + (1 << (DROP - 1))) & !((1u64 << DROP) - 1))
}

/// The exact map of the structure's cluster over a substep of length `h`.
#[derive(Clone, Debug)]
pub(super) struct ExactMap {
    /// The substep length it was built for (its cluster's mass is the cache's key).
    pub(super) h: f64,
    /// Degree of its Taylor sum ([`degree`]).
    pub(super) degree: usize,
    /// Rows over `z = [u, v, p, p']`: u and v at the end, and `∫ u dτ`.
    pub(super) u: [f64; 4],
    pub(super) v: [f64; 4],
    pub(super) int_u: [f64; 4],
    /// `∫ v² dτ = z^T Q z`, packed: Q00, Q11, Q22, Q33, then the doubled
    /// off-diagonal terms 2Q01, 2Q02, 2Q03, 2Q12, 2Q13, 2Q23.
    pub(super) quad: [f64; 10],
    /// `bound[m - 1] · |z|` bounds `|v^(m)(τ)|` over the substep, m = 1..=5.
    pub(super) bound: [[f64; 4]; 5],
    /// The largest ratio of the `v^(5)` bound to the `v'''` bound, term by
    /// term: `five_over_three * sup_v(3)` bounds `|v^(5)|` too (every term
    /// is non-negative), which saves computing both on every substep.
    pub(super) five_over_three: f64,
    /// The same for `|v'|` (`sup|u''|`), for the quick test of the peak of u,
    /// and for `|v''|`, for the quick test of the structure's slip guard.
    pub(super) one_over_three: f64,
    pub(super) two_over_three: f64,
    /// k / mass, c / mass, c.
    pub(super) w2: f64,
    pub(super) cm: f64,
    pub(super) c: f64,
    /// The driver's rows and work coefficients on this map, and their
    /// rates in the rest of a substep's length (`sweep::Rows::of_map`).
    pub(super) rows: Rows,
    pub(super) rows_rate: Rows,
}

crate::isa::copies! {
    /// [`ExactMap::build`], compiled three times.
    fn new_map / new_map_avx2, new_map_avx512 / ExactMap::build
        (sys: &System, mass: f64, h: f64) -> ExactMap
}

impl ExactMap {
    /// Builds the map of the cluster of mass `mass` over `h` (already canonical); compiled for
    /// each instruction set (`crate::isa`: a row's four terms to a register), the same operations.
    pub(super) fn new(sys: &System, mass: f64, h: f64) -> ExactMap {
        new_map(sys, mass, h)
    }

    #[inline(always)]
    fn build(sys: &System, mass: f64, h: f64) -> ExactMap {
        // A prescribed support has no spring, no damper, and its cluster
        // may have no mass: the map of no motion (w2 = cm = 0).
        let (w2, cm) = if sys.prescribed() {
            (0.0, 0.0)
        } else {
            (sys.k / mass, sys.c / mass)
        };
        // Rows u and v of the Taylor terms T_k = (A h)^k / k!: from T_k = T_(k-1) A h / k, a row x
        // goes to x A h / k, where x A = [-w2 x1, x0 - cm x1, x1, x2] (A is sparse).
        let degree = degree(h, w2, cm);
        let n_terms = degree + 6;
        let mut rows = [[[0.0; 4]; 2]; TERMS + 1];
        let mut row = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]];
        rows[0] = row;
        // (`row` carried in registers: read back from `rows`, each half of it spans two stores,
        // which the processor cannot forward.)
        for (k, next) in rows[1..n_terms + 1].iter_mut().enumerate() {
            let f = h / (k + 1) as f64;
            row = row.map(|x| [-w2 * x[1] * f, (x[0] - cm * x[1]) * f, x[1] * f, x[2] * f]);
            *next = row;
        }
        let (mut u, mut v, mut int_u) = ([0.0; 4], [0.0; 4], [0.0; 4]);
        // Sum the small terms first.
        for k in (0..degree + 1).rev() {
            for i in 0..4 {
                u[i] += rows[k][0][i];
                v[i] += rows[k][1][i];
                int_u[i] += h * rows[k][0][i] / (k + 1) as f64;
            }
        }
        // v(τ) = Σ_k r_k z (τ/h)^k with r_k the v row of T_k, so
        // ∫_0^h v² = h Σ_ij (r_i z)(r_j z) / (i + j + 1): the inner sums
        // over j first, w[i] = Σ_j r_j / (i + j + 1) (zipped slices: no bounds checks).
        let mut q = [[0.0; 4]; 4];
        for i in (0..degree + 1).rev() {
            let (mut w, inv) = ([0.0; 4], &RECIPROCALS[i..i + degree + 1]);
            for (row, inv) in rows[..degree + 1].iter().zip(inv).rev() {
                for (ws, r) in w.iter_mut().zip(row[1]) {
                    *ws += r * inv;
                }
            }
            for r in 0..4 {
                for s in r..4 {
                    q[r][s] += h * rows[i][1][r] * w[s];
                }
            }
        }
        let quad = [
            q[0][0],
            q[1][1],
            q[2][2],
            q[3][3],
            2.0 * q[0][1],
            2.0 * q[0][2],
            2.0 * q[0][3],
            2.0 * q[1][2],
            2.0 * q[1][3],
            2.0 * q[2][3],
        ];
        // v^(m)(τ) = Σ_k e_v A^(m+k) z τ^k / k!, and e_v A^(m+k) is the v row of T_(m+k) times
        // (m+k)! / h^(m+k): so over τ in [0, h] |v^(m)| <= h^-m Σ_i |z_i| Σ_k |T_(m+k)[v][i]|
        // (m+k)! / k!. The sum stops at `degree + 6 - m` terms (the rest is below [`degree`]'s
        // threshold of it); the factor covers rounding.
        let mut bound = [[0.0; 4]; 5];
        for (b, m) in bound.iter_mut().zip(1..=5usize) {
            for (row, falling) in rows[m..n_terms + 1].iter().zip(&FALLING[m]).rev() {
                for (bs, r) in b.iter_mut().zip(row[1]) {
                    *bs += r.abs() * falling;
                }
            }
            let scale = (1.0 + 1e-6) / h.powi(m as i32);
            for x in b.iter_mut() {
                *x *= scale;
            }
        }
        // The ratios below bound v', v'' and v^(5) by v''' where its bound has every term
        // positive (a structure). On a prescribed support v''' is 0 while a mobility drives v'
        // and v'': its bound is raised to theirs term by term (still a bound; 0/0 left out).
        if sys.prescribed() {
            bound[2] = std::array::from_fn(|i| bound[0][i].max(bound[1][i]));
        }
        let over_three = |m: usize| {
            (0..4)
                .filter(|&i| bound[2][i] > 0.0)
                .map(|i| bound[m - 1][i] / bound[2][i])
                .fold(0.0, f64::max)
        };
        let (five_over_three, one_over_three) = (over_three(5), over_three(1));
        let two_over_three = over_three(2);
        let mut map = ExactMap {
            degree,
            five_over_three,
            one_over_three,
            two_over_three,
            h,
            u,
            v,
            int_u,
            quad,
            bound,
            w2,
            cm,
            c: sys.c,
            rows: Rows::default(),
            rows_rate: Rows::default(),
        };
        [map.rows, map.rows_rate] = Rows::of_map(&map);
        map
    }

    /// `∫ v² dτ` over the substep from `z`.
    #[inline(always)]
    #[cfg(test)]
    pub(super) fn int_v2(&self, z: &[f64; 4]) -> f64 {
        let q = &self.quad;
        z[0] * (q[0] * z[0] + q[4] * z[1] + q[5] * z[2] + q[6] * z[3])
            + z[1] * (q[1] * z[1] + q[7] * z[2] + q[8] * z[3])
            + z[2] * (q[2] * z[2] + q[9] * z[3])
            + z[3] * q[3] * z[3]
    }

    /// Bound on `|v^(m)|` over the substep, m = 1..=5, from `|z|` (taken once for several
    /// bounds), in two lanes (a bound: its rounding is not the motion's).
    #[inline(always)]
    pub(super) fn sup_v_abs(&self, m: usize, z_abs: &[f64; 4]) -> f64 {
        let (b, z) = (&self.bound[m - 1], z_abs);
        (b[0] * z[0] + b[2] * z[2]) + (b[1] * z[1] + b[3] * z[3])
    }
}

#[inline(always)]
pub(super) fn dot(a: &[f64; 4], z: &[f64; 4]) -> f64 {
    a[0] * z[0] + a[1] * z[1] + a[2] * z[2] + a[3] * z[3]
}

/// The maps a run uses, by cluster mass and canonical substep length: a mode's structure cluster
/// has one of at most nine masses, and a record one or a few sample spacings.
#[derive(Clone, Debug, Default)]
pub(super) struct MapCache {
    maps: Vec<ExactMap>,
    /// Each map's mass and length, bit for bit (searched first: short).
    keys: Vec<[u64; 2]>,
    next: usize,
    /// The map found last.
    last: usize,
    /// Stretch lengths `lo..=hi` asked of [`MapCache::stretch_degree`] with
    /// one degree: every length between has it ([`degree`] grows with `h`).
    last_degree: ([f64; 2], usize),
    /// Substeps' rows with their maps, a slot per hash of mass and length
    /// (bit for bit: a master's few, differing by the times' rounding), keyed
    /// `[!mass, h]`: a zeroed slot matches no mass (it would be a NaN).
    rows: [([u64; 2], usize, Rows); 8],
}

/// How many maps are kept (then the oldest is replaced).
const CACHE_SIZE: usize = 16;

impl MapCache {
    /// Index of the map for `mass` and canonical `h`, built if missing.
    pub(super) fn index(&mut self, sys: &System, mass: f64, h: f64) -> usize {
        // The map of the previous call first: a mode's run and the next call of a master with a
        // fixed step ask for it again. Bit for bit: the same equality as `==` on these (finite,
        // positive) values.
        let key = [mass.to_bits(), h.to_bits()];
        if self.keys.get(self.last) == Some(&key) {
            return self.last;
        }
        if let Some(i) = self.keys.iter().position(|k| *k == key) {
            self.last = i;
            return i;
        }
        let map = ExactMap::new(sys, mass, h);
        self.rows.iter_mut().for_each(|r| r.0 = [0; 2]); // (rows of a replaced map)
        self.last = if self.maps.len() < CACHE_SIZE {
            if self.maps.is_empty() {
                // Room for every map at once (no copies as the vector grows).
                self.maps.reserve_exact(CACHE_SIZE);
                self.keys.reserve_exact(CACHE_SIZE);
            }
            self.maps.push(map);
            self.keys.push(key);
            self.maps.len() - 1
        } else {
            let i = self.next;
            self.maps[i] = map;
            self.keys[i] = key;
            self.next = (i + 1) % CACHE_SIZE;
            i
        };
        self.last
    }

    /// The map and rows ([`Rows::new`]) of a substep of `mass` and length `h`.
    #[inline(always)]
    pub(super) fn rows(&mut self, sys: &System, mass: f64, h: f64) -> (&ExactMap, &Rows) {
        let (_, i, rows) = &self.rows[self.rows_slot(sys, mass, h)];
        (&self.maps[*i], rows)
    }

    /// Where [`MapCache::rows`] keeps them.
    #[inline(always)]
    fn rows_slot(&mut self, sys: &System, mass: f64, h: f64) -> usize {
        let key = [!mass.to_bits(), h.to_bits()];
        // Fibonacci hashing: the lengths differ in their low bits.
        let hash = (key[0] ^ key[1]).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        let k = (hash >> (64 - self.rows.len().trailing_zeros())) as usize;
        if self.rows[k].0 != key {
            self.fill_rows(k, key, sys, mass, h);
        }
        k
    }

    /// Slot `k` for `key` (out of line: rare).
    #[cold]
    #[inline(never)]
    fn fill_rows(&mut self, k: usize, key: [u64; 2], sys: &System, mass: f64, h: f64) {
        let i = self.index(sys, mass, canonical_length(h));
        self.rows[k] = (key, i, Rows::new(&self.maps[i], h));
    }

    pub(super) fn get(&self, i: usize) -> &ExactMap {
        &self.maps[i]
    }

    /// The degree of the event path's Taylor polynomials over a stretch of length `h`: [`degree`]
    /// at the bare structure's rates (the highest of any mode), remembered for a range of lengths.
    pub(super) fn stretch_degree(&mut self, sys: &System, h: f64) -> usize {
        let ([lo, hi], last) = self.last_degree;
        if lo <= h && h <= hi {
            return last;
        }
        let deg = if sys.prescribed() {
            degree(h, 0.0, 0.0)
        } else {
            let inv_mass = 1.0 / sys.mass[0];
            degree(h, sys.k * inv_mass, sys.c * inv_mass)
        };
        let [lo, hi] = if deg == last { [lo, hi] } else { [h, h] };
        self.last_degree = ([lo.min(h), hi.max(h)], deg);
        deg
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::params::Params;

    #[test]
    fn the_map_is_the_exact_solution() {
        // Expected values: the Nigam–Jennings recurrence (src/physics/sdof.rs, exact
        // for a load linear over the step) on the bare structure.
        let p = Params::default();
        let sys = System::new(&p).unwrap();
        let h = canonical_length(0.005);
        let map = ExactMap::new(&sys, p.mp, h);
        let zeta = p.zeta;
        let (u0, v0, p0, p1) = (0.013, -0.21, 2.5, -310.0);
        let z = [u0, v0, p0, p1];
        let (u1, v1) = crate::physics::sdof::step(sys.omega_p, zeta, h, (u0, v0), p0, p0 + p1 * h);
        assert!(
            (dot(&map.u, &z) - u1).abs() < 1e-15,
            "{} {u1}",
            dot(&map.u, &z)
        );
        assert!((dot(&map.v, &z) - v1).abs() < 1e-14);
        // ∫ u and ∫ v²: against a 2000-point Simpson rule on the same
        // recurrence (error ~1e-13 relative).
        let n = 2000;
        let (mut iu, mut iv2) = (0.0, 0.0);
        for k in 0..=n {
            let tau = h * k as f64 / n as f64;
            let w = if k == 0 || k == n {
                1.0
            } else if k % 2 == 1 {
                4.0
            } else {
                2.0
            };
            let (u, v) = if k == 0 {
                (u0, v0)
            } else {
                crate::physics::sdof::step(sys.omega_p, zeta, tau, (u0, v0), p0, p0 + p1 * tau)
            };
            iu += w * u;
            iv2 += w * v * v;
        }
        let (iu, iv2) = (iu * h / (3 * n) as f64, iv2 * h / (3 * n) as f64);
        assert!((dot(&map.int_u, &z) - iu).abs() < 1e-12 * iu.abs());
        assert!((map.int_v2(&z) - iv2).abs() < 1e-12 * iv2);
    }

    #[test]
    fn derivative_bounds_hold_on_a_dense_grid() {
        // Expected: |v^(m)(τ)| <= sup_v(m, z) at every τ of a 400-point grid of the substep, the
        // derivatives taken from the exact state at τ (the map built for τ) through the equation of
        // motion; and the bounds of v^(5) and v' through `five_over_three`, `one_over_three`.
        // Several periods and dampings, states and forcings of every sign.
        let mut seed = 0x1234_5678_9abc_def0u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for (tp, zeta, mass_ratio) in [(0.5, 0.05, 1.0), (0.05, 0.2, 1.5), (4.0, 0.0, 3.0)] {
            let p = Params {
                tp,
                zeta,
                ..Params::default()
            };
            let sys = System::new(&p).unwrap();
            let mass = p.mp * mass_ratio;
            let h = canonical_length(MAP_H_OMEGA / sys.omega_p);
            let map = ExactMap::new(&sys, mass, h);
            for _ in 0..20 {
                let z = [0.05 * next(), 0.5 * next(), 5.0 * next(), 500.0 * next()];
                let mut worst = [0.0f64; 5];
                for k in 1..=400 {
                    let tau = canonical_length(h * k as f64 / 400.0);
                    let at = ExactMap::new(&sys, mass, tau);
                    let (u, v) = (dot(&at.u, &z), dot(&at.v, &z));
                    let pt = z[2] + z[3] * tau;
                    let d1 = pt - map.w2 * u - map.cm * v;
                    let d2 = z[3] - map.w2 * v - map.cm * d1;
                    let d3 = -map.w2 * d1 - map.cm * d2;
                    let d4 = -map.w2 * d2 - map.cm * d3;
                    let d5 = -map.w2 * d3 - map.cm * d4;
                    for (w, d) in worst.iter_mut().zip([d1, d2, d3, d4, d5]) {
                        *w = w.max(d.abs());
                    }
                }
                let z_abs = z.map(f64::abs);
                for m in 1..=5 {
                    assert!(worst[m - 1] <= map.sup_v_abs(m, &z_abs), "Tp {tp}: v^({m})");
                }
                assert!(worst[4] <= map.five_over_three * map.sup_v_abs(3, &z_abs));
                assert!(worst[0] <= map.one_over_three * map.sup_v_abs(3, &z_abs));
            }
        }
    }

    #[test]
    fn the_map_of_a_prescribed_support_is_free_motion_with_no_nan() {
        // Expected: w2 = cm = 0 and a cluster of no mass (the support with every block slipping):
        // the exact rows of u'' = p + p' t, u = [1, h, h²/2, h³/6] and v = [0, 1, h, h²/2] (to
        // rounding), every field finite, the ratios of the bounds 0.
        let p = Params {
            n_blocks: 2,
            mp: 1.0,
            support: crate::physics::params::Support::Prescribed,
            ..Params::default()
        };
        let sys = System::new(&p).unwrap();
        let h = canonical_length(0.02);
        let map = ExactMap::new(&sys, 0.0, h);
        let u = [1.0, h, h * h / 2.0, h * h * h / 6.0];
        let v = [0.0, 1.0, h, h * h / 2.0];
        for k in 0..4 {
            assert!((map.u[k] - u[k]).abs() <= 4e-16 * u[k].abs(), "u[{k}]");
            assert!((map.v[k] - v[k]).abs() <= 4e-16 * v[k].abs(), "v[{k}]");
        }
        let bound = map.bound.iter().flatten();
        let all = map.int_u.iter().chain(&map.quad).chain(bound);
        assert!(all.copied().all(f64::is_finite));
        assert_eq!((map.w2, map.cm, map.c), (0.0, 0.0, 0.0));
        let z = [0.0, 0.0, 2.0, -10.0]; // v' = p + p' τ, v'' = p': a mobility's drift
        let s3 = map.sup_v_abs(3, &z.map(f64::abs));
        assert!(map.one_over_three * s3 >= 2.0 + 10.0 * h);
        assert!(map.two_over_three * s3 >= 10.0);
    }

    #[test]
    fn the_rest_of_the_taylor_sum_is_below_rounding() {
        // Expected: [`degree`]'s bound of the rest, `(2 + 2/ρ) Σ_(j>k) ρ^j/j!`,
        // below half a unit round-off at every ρ from 1e-7 to ω h = 0.5 as
        // ζ tends to 1 (ρ = 1.5; w2 = 1, cm = 0 make ρ = h).
        for i in 0..=700 {
            let rho = 1.5 * 10f64.powf(-i as f64 / 100.0);
            let k = degree(rho, 1.0, 0.0);
            let (mut term, mut rest) = ((1..=k).fold(1.0, |t, j| t * rho / j as f64), 0.0);
            for j in k + 1..k + 40 {
                term *= rho / j as f64;
                rest += term;
            }
            assert!(
                (2.0 + 2.0 / rho) * rest < 0.25 * f64::EPSILON,
                "ρ {rho}: {rest:e}"
            );
        }
    }

    #[test]
    fn canonical_lengths_are_stable() {
        let h = canonical_length(0.005);
        assert_eq!(canonical_length(0.005 * (1.0 + 1e-15)), h);
        assert!((h - 0.005).abs() <= 1e-9 * 0.005);
    }
}
