//! RK4's step for the structure's cluster as the affine map that it is for
//! a linear system under a force linear in time. The fast path
//! (`engine/lean.rs`) takes its steps with it: a few independent dot
//! products instead of four dependent stage evaluations, the same method
//! and the same result up to rounding (checked below against the general
//! path's stage-by-stage RK4).

use super::Excitation;
use crate::physics::mode::Dynamics;
use crate::physics::system::System;

/// The structure's cluster at the end of a fast-path step.
#[derive(Clone, Copy, Debug)]
pub(super) struct StepEnd {
    pub(super) u: f64,
    pub(super) v: f64,
    /// Input and viscous work over the step.
    pub(super) input: f64,
    pub(super) viscous: f64,
    /// Absolute acceleration and its time derivative.
    pub(super) accel: f64,
    pub(super) jerk: f64,
    /// The inputs at the end (at the step's nominal length).
    pub(super) inputs: Inputs,
}

/// The input force `fext - m ag` on the structure's cluster (N) and the
/// ground acceleration (m/s^2) at an instant: carried from step to step.
#[derive(Clone, Copy, Debug)]
pub(super) struct Inputs {
    pub(super) force: f64,
    pub(super) ag: f64,
}

/// RK4's step for the structure's cluster as the affine map that it is for
/// this linear ODE under a force linear in time: the stages of
/// `StructureRk4::step` evaluated once per mode and step length on unit
/// inputs, so that a step is a few independent dot products instead of four
/// dependent stage evaluations (same method, same result up to rounding).
/// With `f(τ) = f0 + f1 τ` the cluster's forcing per unit mass (τ from the
/// step start), the end state (u1, v1) and the stage velocities V2, V3, V4
/// are linear in (u, v, f0, f1); the work integrals are RK4's quadrature over
/// the stage velocities.
#[derive(Clone, Copy, Debug)]
pub(super) struct Rk4Map {
    /// Step length, half and a sixth of it (RK4's weights).
    pub(super) h: f64,
    half_h: f64,
    sixth_h: f64,
    /// For u1 - u, v1, V2, V3, V4, the outputs of `rk4_stages` in order
    /// (`step` takes V2 from the acceleration at the start instead): the
    /// coefficients of u, v and the input force
    /// `fext - m ag` at the step start.
    rows: [[f64; 3]; 5],
    /// The same outputs' terms from the slipping interfaces' constant load.
    load_terms: [f64; 5],
    /// Their coefficients of `f1`.
    slope_rows: [f64; 5],
    mass: f64,
    inv_mass: f64,
    /// Acceleration of the constant load alone, `slip_load / mass`.
    load_accel: f64,
    /// k / mass and c / mass of the cluster, and c.
    w2: f64,
    cm: f64,
    c: f64,
}

/// The parts of a step that are constant over a piece.
#[derive(Clone, Copy, Debug)]
pub(super) struct Forced {
    /// Ground acceleration at the piece start and its slope.
    ag: f64,
    ag_rate: f64,
    /// Input force `fext - m ag` at the piece start (N) and its slope (N/s).
    force: f64,
    force_rate: f64,
    /// Its increase over a step, and that of `ag`.
    step_force: f64,
    step_ag: f64,
    /// RK4's weight of the force's slope in the input work: `h^2 / 6` times it.
    input_slope: f64,
    /// Each output's terms from the constant load and the forcing's slope.
    constant_terms: [f64; 5],
    /// `fext_rate / mass`, the forcing's part of the jerk.
    jerk_forced: f64,
}

impl Rk4Map {
    pub(super) fn new(sys: &System, d: &Dynamics, h: f64) -> Rk4Map {
        let (w2, cm) = (sys.k * d.inv_mass0, sys.c * d.inv_mass0);
        let unit = |i: usize| {
            let e = |j: usize| if i == j { 1.0 } else { 0.0 };
            rk4_stages(w2, cm, h, [e(0), e(1), e(2), e(3)])
        };
        let columns = [unit(0), unit(1), unit(2), unit(3)];
        let load_accel = d.slip_load[0] * d.inv_mass0;
        Rk4Map {
            h,
            half_h: 0.5 * h,
            sixth_h: h / 6.0,
            rows: std::array::from_fn(|r| {
                [columns[0][r], columns[1][r], columns[2][r] * d.inv_mass0]
            }),
            load_terms: columns[2].map(|f0_coefficient| f0_coefficient * load_accel),
            slope_rows: columns[3],
            mass: d.mass[0],
            inv_mass: d.inv_mass0,
            load_accel,
            w2,
            cm,
            c: sys.c,
        }
    }

    #[inline]
    pub(super) fn forced(&self, exc: &Excitation) -> Forced {
        let force_rate = exc.fext_rate - self.mass * exc.ag_rate;
        let f1 = force_rate * self.inv_mass;
        Forced {
            ag: exc.ag,
            ag_rate: exc.ag_rate,
            force: exc.fext - self.mass * exc.ag,
            force_rate,
            step_force: self.h * force_rate,
            step_ag: self.h * exc.ag_rate,
            input_slope: self.sixth_h * self.h * force_rate,
            constant_terms: std::array::from_fn(|r| self.load_terms[r] + self.slope_rows[r] * f1),
            jerk_forced: exc.fext_rate * self.inv_mass,
        }
    }

    /// The inputs at `tau` into the piece.
    pub(super) fn inputs(&self, forced: &Forced, tau: f64) -> Inputs {
        Inputs {
            force: forced.force + forced.force_rate * tau,
            ag: forced.ag + forced.ag_rate * tau,
        }
    }

    /// The same where the input force is `force` and the ground acceleration `ag`.
    #[inline(always)]
    pub(super) fn accel_and_jerk_at(
        &self,
        forced: &Forced,
        force: f64,
        ag: f64,
        u: f64,
        v: f64,
    ) -> (f64, f64) {
        let relative = force * self.inv_mass + self.load_accel - self.w2 * u - self.cm * v;
        let jerk = forced.jerk_forced - self.w2 * v - self.cm * relative;
        (relative + ag, jerk)
    }

    /// One step of length `hs` from (u, v) where the inputs are `start` and
    /// the absolute acceleration `accel`. `hs` is
    /// `self.h` except on a piece's last substep, where it differs by
    /// rounding of the piece's end times (at most `lean::SAME_STEP` relative):
    /// that rest is carried to first order with the rates at the end.
    #[inline(always)]
    pub(super) fn step(
        &self,
        forced: &Forced,
        start: Inputs,
        accel: f64,
        hs: f64,
        u: f64,
        v: f64,
    ) -> StepEnd {
        let force = start.force;
        let out = |r: usize| {
            let row = &self.rows[r];
            row[0] * u + row[1] * v + row[2] * force + forced.constant_terms[r]
        };
        // The first stage's rate is the acceleration at the start, known
        // from the step before: V2 = v + h/2 a.
        let v2 = v + self.half_h * (accel - start.ag);
        let (du, v1, v3, v4) = (out(0), out(1), out(3), out(4));
        let u1 = u + du;
        let inputs = Inputs {
            force: force + forced.step_force,
            ag: start.ag + forced.step_ag,
        };
        let (force_end, ag_end) = (inputs.force, inputs.ag);
        let (accel, jerk) = self.accel_and_jerk_at(forced, force_end, ag_end, u1, v1);
        let mut end = StepEnd {
            u: u1,
            v: v1,
            // RK4's quadrature of (force v): with the force linear over the
            // step, `force du` plus the slope's share over the stages.
            input: force * du + forced.input_slope * (v2 + v3 + v4),
            viscous: self.sixth_h * self.c * (v * v + 2.0 * (v2 * v2 + v3 * v3) + v4 * v4),
            accel,
            jerk,
            inputs,
        };
        if hs != self.h {
            let delta = hs - self.h;
            end.u += delta * v1;
            end.v += delta * (accel - ag_end);
            end.input += delta * force_end * v1;
            end.viscous += delta * self.c * v1 * v1;
            end.accel += delta * jerk;
            let relative_jerk = jerk - forced.ag_rate;
            end.jerk -= delta * (self.w2 * (accel - ag_end) + self.cm * relative_jerk);
        }
        end
    }
}

/// RK4's stages for u' = v, v' = f0 + f1 τ - w2 u - cm v over one step `h`
/// from `[u, v, f0, f1]`: (u1 - u, v1, V2, V3, V4), linear in the four inputs.
fn rk4_stages(w2: f64, cm: f64, h: f64, [u, v, f0, f1]: [f64; 4]) -> [f64; 5] {
    let accel = |tau: f64, u: f64, v: f64| f0 + f1 * tau - w2 * u - cm * v;
    let a1 = accel(0.0, u, v);
    let (u2, v2) = (u + 0.5 * h * v, v + 0.5 * h * a1);
    let a2 = accel(0.5 * h, u2, v2);
    let (u3, v3) = (u + 0.5 * h * v2, v + 0.5 * h * a2);
    let a3 = accel(0.5 * h, u3, v3);
    let (u4, v4) = (u + h * v3, v + h * a3);
    let a4 = accel(h, u4, v4);
    let w = h / 6.0;
    [
        w * (v + 2.0 * (v2 + v3) + v4),
        v + w * (a1 + 2.0 * (a2 + a3) + a4),
        v2,
        v3,
        v4,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::engine::StructureRk4;
    use crate::physics::mode::{Contact, Mode};
    use crate::physics::params::Params;

    fn close(a: f64, b: f64, scale: f64) -> bool {
        (a - b).abs() <= 1e-13 * scale
    }

    #[test]
    fn the_affine_map_is_the_rk4_step() {
        // Expected values: the stage-by-stage RK4 of the general path, on a
        // 2-block scene with block 1 sliding, so that the structure's
        // cluster carries a constant friction load.
        let sys = System::new(&Params::default()).unwrap();
        let mut mode = Mode::all_stuck(&sys);
        mode.contact[1] = Contact::SlipForward;
        let d = Dynamics::new(&sys, &mode);
        assert!(d.slip_load[0] != 0.0);
        let exc = Excitation {
            ag: 2.5,
            ag_rate: -40.0,
            fext: 300.0,
            fext_rate: 5e3,
        };
        let (t_ref, h) = (0.3, 1.25e-3);
        let rk = StructureRk4::new(&sys, &d, &exc, t_ref);
        let map = Rk4Map::new(&sys, &d, h);
        let forced = map.forced(&exc);
        for (k, (u, v)) in [(0.0, 0.0), (0.012, -0.3), (-0.04, 0.7)]
            .into_iter()
            .enumerate()
        {
            let t0 = t_ref + k as f64 * h;
            // Whole steps, and a last substep longer by rounding-sized rests.
            for hs in [h, h * (1.0 + 1e-12), h * (1.0 - 4e-10)] {
                let want = rk.step(t0, u, v, hs);
                let (a1, jerk1) = rk.accel_and_jerk(t0 + hs, want[0], want[1]);
                let start = map.inputs(&forced, t0 - t_ref);
                let (a0, _) = map.accel_and_jerk_at(&forced, start.force, start.ag, u, v);
                let got = map.step(&forced, start, a0, hs, u, v);
                assert!(close(got.u, want[0], 0.1), "u {} {}", got.u, want[0]);
                assert!(close(got.v, want[1], 1.0), "v {} {}", got.v, want[1]);
                assert!(
                    close(got.input, want[2], 10.0),
                    "input {} {}",
                    got.input,
                    want[2]
                );
                assert!(close(got.viscous, want[3], 10.0));
                assert!(close(got.accel, a1, 10.0), "accel {} {a1}", got.accel);
                assert!(close(got.jerk, jerk1, 1e3), "jerk {} {jerk1}", got.jerk);
            }
            let (a0, jerk0) = rk.accel_and_jerk(t0, u, v);
            let start = map.inputs(&forced, t0 - t_ref);
            let (a, jerk) = map.accel_and_jerk_at(&forced, start.force, start.ag, u, v);
            assert!(close(a, a0, 10.0) && close(jerk, jerk0, 1e3));
        }
    }
}
