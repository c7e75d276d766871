//! The clusters above the structure's over the substeps of one piece, for
//! the loops of runs of substeps (`folded`): their exact motion, with the
//! terms that are constant over the piece collected once.

use super::upper_cluster_step;
use crate::physics::mode::Dynamics;

/// The clusters above the structure's over the substeps of one piece: the
/// exact polynomials in time that RK4 gives them ([`upper_cluster_step`]),
/// with the terms that are constant over the piece collected once.
pub(super) struct UpperClusters<const NC: usize> {
    h: f64,
    half_h: f64,
    ag_rate: f64,
    /// Per cluster: absolute acceleration and mass (for steps of other
    /// lengths and the work), and the parts of the velocity change and of
    /// the displacement over a step that are constant over the piece.
    accel: [f64; NC],
    mass: [f64; NC],
    dv: [f64; NC],
    du: [f64; NC],
}

impl<const NC: usize> UpperClusters<NC> {
    pub(super) fn new(d: &Dynamics, h: f64, ag_rate: f64) -> Self {
        let accel: [f64; NC] = std::array::from_fn(|c| d.accel_const[c]);
        let (h2, h3) = (h * h, h * h * h);
        UpperClusters {
            h,
            half_h: 0.5 * h,
            ag_rate,
            accel,
            mass: std::array::from_fn(|c| d.mass[c]),
            dv: accel.map(|a| h * a - 0.5 * h2 * ag_rate),
            du: accel.map(|a| 0.5 * h2 * a - h3 * ag_rate / 6.0),
        }
    }

    /// Clusters 1.. over a substep of length `hs` from velocities `vel`,
    /// where the ground acceleration starts at `ag0`: their displacement
    /// increments and end velocities into `du` and `v_end`.
    #[inline(always)]
    pub(super) fn step(
        &self,
        vel: &[f64; NC],
        ag0: f64,
        hs: f64,
        du: &mut [f64; NC],
        v_end: &mut [f64; NC],
    ) {
        if hs != self.h {
            // A piece's last substep, longer or shorter by rounding.
            for c in 1..NC {
                let [dc, vc, _] =
                    upper_cluster_step(vel[c], self.accel[c], self.mass[c], ag0, self.ag_rate, hs);
                (du[c], v_end[c]) = (dc, vc);
            }
            return;
        }
        let h_ag = self.h * ag0;
        let half_h2_ag = self.half_h * h_ag;
        for c in 1..NC {
            let v = vel[c];
            du[c] = self.h * v - half_h2_ag + self.du[c];
            v_end[c] = v - h_ag + self.dv[c];
        }
    }

    /// Absolute acceleration of cluster `c` (constant in the mode).
    #[inline(always)]
    pub(super) fn accel(&self, c: usize) -> f64 {
        self.accel[c]
    }

    /// Input work on clusters 1.. from `(t, ag, vel)` (a time, the ground
    /// acceleration and the cluster velocities then) to `t_end`, under one
    /// piece: the closed form of `upper_cluster_step`, exact over any
    /// length.
    pub(super) fn work(&self, (t, ag, vel): (f64, f64, [f64; NC]), t_end: f64) -> f64 {
        let length = t_end - t;
        if length <= 0.0 {
            return 0.0;
        }
        (1..NC)
            .map(|c| {
                upper_cluster_step(
                    vel[c],
                    self.accel[c],
                    self.mass[c],
                    ag,
                    self.ag_rate,
                    length,
                )[2]
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::mode::{Contact, Mode};
    use crate::physics::params::Params;
    use crate::physics::system::System;

    /// A 2-block scene with block 1 sliding forward on the structure, so
    /// that the structure's cluster carries a constant friction load.
    fn sliding_scene() -> (System, Dynamics) {
        let sys = System::new(&Params::default()).unwrap();
        let mut mode = Mode::all_stuck(&sys);
        mode.contact[1] = Contact::SlipForward;
        let d = Dynamics::new(&sys, &mode);
        assert!(d.slip_load[0] != 0.0 && d.n_clusters == 2);
        (sys, d)
    }

    fn close(a: f64, b: f64, scale: f64) -> bool {
        (a - b).abs() <= 1e-13 * scale
    }

    #[test]
    fn upper_clusters_move_as_their_exact_polynomials() {
        // Expected values: `upper_cluster_step`, the closed form the general
        // path uses.
        let (_, d) = sliding_scene();
        let (h, ag_rate, ag0) = (1.25e-3, 75.0, -1.2);
        let upper = UpperClusters::<2>::new(&d, h, ag_rate);
        let mut vel = [0.1, -0.25];
        for hs in [h, h * (1.0 + 1e-12)] {
            let (mut du, mut v_end) = ([0.0; 2], [0.0; 2]);
            upper.step(&vel, ag0, hs, &mut du, &mut v_end);
            let [du1, v1, _] =
                upper_cluster_step(vel[1], d.accel_const[1], d.mass[1], ag0, ag_rate, hs);
            assert!(close(du[1], du1, 1e-3) && close(v_end[1], v1, 1.0));
        }
        // The work over a run of steps equals the sum of the steps' works.
        let start = (0.0, ag0, vel);
        let mut sum = 0.0;
        for k in 0..4 {
            let ag = ag0 + ag_rate * k as f64 * h;
            let [_, v1, w] =
                upper_cluster_step(vel[1], d.accel_const[1], d.mass[1], ag, ag_rate, h);
            sum += w;
            vel[1] = v1;
        }
        let work = upper.work(start, 4.0 * h);
        assert!(close(work, sum, 10.0), "{work} {sum}");
    }
}
