//! What the FMU shows a coupling master at a communication point
//! (docs/coupling-ports.md): the outputs as the next step starts them, with
//! the inputs set for that step in force, and their time derivatives there.

use crate::fmi::variables::Id;
use crate::physics::engine::{Excitation, Outputs, SimError, Simulator};
use crate::physics::mode::{stick_capacity, Contact, Dynamics};
use crate::physics::system::System;
use crate::solver::{Solver, Stepper};

/// How far [`at_step_start`] looks ahead for a switch at the very start of
/// the next step (s): a switch located again along other internal steps
/// moves by up to 8e-12 s (measured), so 1e-10 s.
pub const SWITCH_LOOKAHEAD: f64 = 1e-10;

/// Applies the inputs set for the next step at the current instant, as the
/// next step (and the outputs before it) takes them: the support's mobility
/// first (the mode resolution of a prescribed support takes it; a structure
/// keeps it unused), then, if an input that can change the mode changed,
/// that input at the instant, where the engine acts on a jump of it (a jump
/// of `Fext` can break a stick; on a prescribed support a jump of `ag` can
/// too, and nowhere else can `ag`).
pub fn take_inputs(sim: &mut Solver, exc: &Excitation, mobility: f64) -> Result<(), SimError> {
    sim.set_support_mobility(mobility)
        .map_err(|e| SimError::BadInput {
            name: "supportMobility",
            value: e.value,
        })?;
    if mode_inputs_changed(sim, exc) {
        let now = sim.time();
        sim.advance(now, exc)?;
    }
    Ok(())
}

/// Whether `exc` changes an input that can change the mode at an instant
/// (the ones the engine checks for a jump as a piece begins): `Fext`, and
/// `ag` on a prescribed support (only the exact engine has one).
fn mode_inputs_changed(sim: &Solver, exc: &Excitation) -> bool {
    exc.fext != sim.fext_now()
        || matches!(sim, Solver::Exact(s) if s.system().prescribed() && exc.ag != s.ag_now())
}

/// The solver as the next step starts: the inputs set for it applied at the
/// current instant ([`take_inputs`]), and a switch that the next step takes
/// at its very start taken. (A step that ends on a switch, as when a master
/// lands on `tSwitch`, may leave it, within rounding, to the next step: the
/// solver is then taken SWITCH_LOOKAHEAD ahead, past it, which changes a
/// state of frequency w by a relative w 1e-10.) Both models: the storey
/// (whose `mobility` is 0, unused) and StackOnFloor.
pub fn at_step_start(sim: &Solver, exc: &Excitation, mobility: f64) -> Result<Solver, SimError> {
    Ok(match sim {
        Solver::Exact(s) => Solver::Exact(exact_at_step_start(s, exc, mobility)?),
        // The regularized method has no switches: only the jump to apply.
        Solver::Regularized(_) => {
            let mut next = sim.clone();
            take_inputs(&mut next, exc, mobility)?;
            next
        }
    })
}

/// [`at_step_start`] for the exact engine.
pub fn exact_at_step_start(
    sim: &Simulator,
    exc: &Excitation,
    mobility: f64,
) -> Result<Simulator, SimError> {
    let mut next = Solver::Exact(sim.clone());
    take_inputs(&mut next, exc, mobility)?;
    let Solver::Exact(next) = next else {
        unreachable!("an exact solver stays exact")
    };
    let mut shown = next;
    if switch_may_be_imminent(&shown, exc, 100.0 * SWITCH_LOOKAHEAD) {
        let now = shown.time();
        let mut ahead = shown.clone();
        ahead.watch_switches();
        // Under the law of the step that ended here (its reference mode): the
        // inputs held are the old mode's, and a new reference would break a
        // stick the step's law made consistent (docs/stack-on-a-floor.md).
        ahead.advance_keeping_reference(now + SWITCH_LOOKAHEAD, exc)?;
        if !ahead.first_switch().is_nan() {
            shown = ahead;
        }
    }
    Ok(shown)
}

/// Absolute acceleration of the structure's cluster (body 0's: the
/// structure's, or a prescribed support's) and its first two time
/// derivatives, in the mode of `d`, at the state `o` and the inputs `exc` (at
/// the instant, with their slopes; linear over a step). The engine's rules:
/// the acceleration is [`Dynamics::accel0`] of [`Dynamics::load0`]; forces
/// move it by their rate over `M0` (`inv_mass0`: `Fext`, the spring and the
/// damper of a structure) and `ag` by its share `ag_gain`
/// ([`Dynamics::accel0_rate`]). On a structure `ag_gain = 0`; on a
/// prescribed support `k = c = inv_mass0 = 0`, so the acceleration follows
/// `ag`: `ag`, `der(ag)`, 0.
fn structure_accel(s: &System, d: &Dynamics, o: &Outputs, exc: &Excitation) -> [f64; 3] {
    let (k, c) = (s.k, s.c);
    let acc0 = d.accel0(Dynamics::load0(s, o.up, o.vp, exc.ag, exc.fext));
    let rel0 = acc0 - exc.ag;
    let acc0_1 = d.accel0_rate(s, [o.vp, acc0, exc.ag], [exc.ag_rate, exc.fext_rate]);
    let rel0_1 = acc0_1 - exc.ag_rate;
    let acc0_2 = (-k * rel0 - c * rel0_1) * d.inv_mass0;
    [acc0, acc0_1, acc0_2]
}

/// Whether a guard of the current mode could reach zero within `horizon`
/// seconds, from its value and rate now: a cheap screen that spares the
/// lookahead (which takes a step) at nearly every communication point.
/// Guards as the engine's: `mus N - |F|` for a stuck interface, `s v_rel`
/// for one slipping in direction `s`.
fn switch_may_be_imminent(next: &Simulator, exc: &Excitation, horizon: f64) -> bool {
    let (s, mode) = (next.system(), next.mode());
    let d = Dynamics::new(s, mode);
    let o = next.outputs();
    // The structure's cluster: absolute acceleration and its rate (as in
    // `derivatives`); every other cluster's is constant.
    let [a0, jerk0, _] = structure_accel(s, &d, &o, exc);
    let velocity = |i: usize| if i == 0 { o.vp } else { o.vb[i - 1] };
    let accel = |i: usize| match d.cluster_of[i] {
        0 => a0,
        c => d.accel_const[c],
    };
    (1..=s.n).any(|j| match mode.contact[j] {
        Contact::Free => false,
        Contact::Stuck => {
            let rate = if d.cluster_of[j] == 0 { jerk0 } else { 0.0 };
            let force_rate = d.force_affine(j, mode).0 * rate;
            stick_capacity(s, j) - o.force[j - 1].abs() <= force_rate.abs() * horizon
        }
        slipping => {
            let (v_rel, a_rel) = (velocity(j) - velocity(j - 1), accel(j) - accel(j - 1));
            slipping.slip_sign() * v_rel <= a_rel.abs() * horizon
        }
    })
}

/// The outputs as the next step starts (see [`at_step_start`]); the switch
/// counters are those of the steps taken, which have not seen the new inputs.
pub fn outputs_at_step_start(
    sim: &Solver,
    exc: &Excitation,
    mobility: f64,
) -> Result<Outputs, SimError> {
    let mut o = at_step_start(sim, exc, mobility)?.outputs();
    let taken = sim.outputs();
    o.n_events = taken.n_events;
    o.n_ambiguous = taken.n_ambiguous;
    Ok(o)
}

/// Right derivatives of a running peak `max |x|` where `x` has derivatives
/// `x1`, `x2`: the peak follows `|x|` while `|x|` is at it and rising, and
/// is flat otherwise. `|x|` within `slack` of the peak counts as at it: the
/// peak was taken from the same values by another rounding path (a slip, as
/// a difference of displacements, carries their rounding).
pub(crate) fn running_peak(peak: f64, x: f64, x1: f64, x2: f64, slack: f64) -> [f64; 2] {
    if x.abs() < peak - slack {
        return [0.0, 0.0];
    }
    // The sign of x just after now: that of its first non-zero derivative.
    let s = [x, x1, x2]
        .into_iter()
        .find(|&y| y != 0.0)
        .map_or(0.0, f64::signum);
    let (a1, a2) = (s * x1, s * x2);
    if a1 > 0.0 || (a1 == 0.0 && a2 > 0.0) {
        [a1, a2]
    } else {
        [0.0, 0.0]
    }
}

/// First and second time derivatives of every continuous output of `next`
/// (a simulator from [`at_step_start`], so in the mode the next step starts
/// in), under the excitation of that step: `exc` holds the inputs at the
/// current instant and their slopes. Entries that are not derivatives of
/// continuous outputs (`stuck`, counters) are left at their defaults.
///
/// Both models: in a mode, every cluster but the structure's (body 0's) has
/// a constant absolute acceleration; the structure's is `(F_slip + load) /
/// M0` with `load = Fext - k u0 - c v0` on a structure, `ag` on a prescribed
/// support (StackOnFloor: `up`, `vp` and the structure's outputs are 0
/// there), whose derivatives follow from the state and the inputs
/// (`structure_accel`; the inputs are linear over a step). `floorForce =
/// slidingForce - attachedMass A0` follows body 0's cluster while
/// interface 1 is stuck (else `attachedMass = 0`); `attachedMass` and
/// `slidingForce` are constant in a mode.
pub fn derivatives(next: &Simulator, exc: &Excitation) -> [Outputs; 2] {
    let s = next.system();
    let mode = next.mode();
    let d = Dynamics::new(s, mode);
    let o = next.outputs();
    let (k, c, n) = (s.k, s.c, s.n);
    let (ag, ag1) = (exc.ag, exc.ag_rate);

    // The structure's cluster: absolute acceleration and its derivatives.
    let [acc0, acc0_1, acc0_2] = structure_accel(s, &d, &o, exc);
    let rel0 = acc0 - ag;
    let rel0_1 = acc0_1 - ag1;
    // Every body i = 0..=n: velocity relative to the support, absolute
    // acceleration and its two derivatives.
    let velocity = |i: usize| if i == 0 { o.vp } else { o.vb[i - 1] };
    let accel = |i: usize| match d.cluster_of[i] {
        0 => [acc0, acc0_1, acc0_2],
        cl => [d.accel_const[cl], 0.0, 0.0],
    };

    let (mut d1, mut d2) = (Outputs::default(), Outputs::default());
    [d1.up, d2.up] = [o.vp, rel0];
    [d1.vp, d2.vp] = [rel0, rel0_1];
    [d1.ap_abs, d2.ap_abs] = [acc0_1, acc0_2];
    [d1.base_shear, d2.base_shear] = [k * o.vp + c * rel0, k * rel0 + c * rel0_1];
    [d1.e_strain, d2.e_strain] = [k * o.up * o.vp, k * (o.vp * o.vp + o.up * rel0)];
    [d1.e_viscous, d2.e_viscous] = [c * o.vp * o.vp, 2.0 * c * o.vp * rel0];
    // A running peak is taken in continuous time between steps, to the
    // engine's accuracy (peaks within 1e-9 of exact): |x| within that of the
    // peak counts as at it.
    const ROUNDING: f64 = 1e-9;
    let slack = ROUNDING * o.peak_up;
    [d1.peak_up, d2.peak_up] = running_peak(o.peak_up, o.up, o.vp, rel0, slack);
    let slack = ROUNDING * o.peak_ap_abs;
    [d1.peak_ap_abs, d2.peak_ap_abs] = running_peak(o.peak_ap_abs, o.ap_abs, acc0_1, acc0_2, slack);

    // Momentum and kinetic energy in relative coordinates.
    let (mut p, mut p1, mut ek1, mut ek2) = (0.0, 0.0, 0.0, 0.0);
    for i in 0..=n {
        let (m, v, a) = (s.mass[i], velocity(i), accel(i));
        let (rel, rel1) = (a[0] - ag, a[1] - ag1);
        p += m * v;
        p1 += m * rel;
        ek1 += m * v * rel;
        ek2 += m * (rel * rel + v * rel1);
    }
    [d1.e_kinetic, d2.e_kinetic] = [ek1, ek2];
    d1.e_input = exc.fext * o.vp - ag * p;
    d2.e_input = exc.fext_rate * o.vp + exc.fext * rel0 - ag1 * p - ag * p1;

    for j in 1..=n {
        let b = j - 1;
        let (a, below) = (accel(j), accel(j - 1));
        let (v_rel, a_rel) = (velocity(j) - velocity(j - 1), a[0] - below[0]);
        [d1.ub[b], d2.ub[b]] = [velocity(j), a[0] - ag];
        [d1.vb[b], d2.vb[b]] = [a[0] - ag, a[1] - ag1];
        [d1.slip[b], d2.slip[b]] = [v_rel, a_rel];
        [d1.ab_abs[b], d2.ab_abs[b]] = [a[1], a[2]];
        // A stuck interface carries M_above A + const; a slipping one a constant.
        let mass_above = if s.is_free(j) {
            0.0
        } else {
            d.force_affine(j, mode).0
        };
        [d1.force[b], d2.force[b]] = [mass_above * a[1], mass_above * a[2]];
        // Friction power -F v_rel (zero on a stuck interface: v_rel = a_rel = 0).
        let f = o.force[b];
        d1.e_friction_of[b] = -f * v_rel;
        d2.e_friction_of[b] = -(d1.force[b] * v_rel + f * a_rel);
        let body = |i: usize| if i == 0 { o.up } else { o.ub[i - 1] };
        let slack = ROUNDING * (o.peak_slip[b] + body(j).abs() + body(j - 1).abs());
        [d1.peak_slip[b], d2.peak_slip[b]] =
            running_peak(o.peak_slip[b], o.slip[b], v_rel, a_rel, slack);
    }
    d1.e_friction = d1.e_friction_of.iter().sum();
    d2.e_friction = d2.e_friction_of.iter().sum();
    [d1.floor_force, d2.floor_force] = [-o.attached_mass * acc0_1, -o.attached_mass * acc0_2];
    [d1, d2]
}

/// Derivative of output `unknown` with respect to input `known` within the
/// mode of `next` (a simulator from [`exact_at_step_start`]), whose outputs at
/// the communication point are `o`; `None` if `unknown` is not a Real output
/// or `known` not an input. One rule for both models:
///
/// An input moves only the structure's (or support's) cluster at once: by
/// `1/M0` per newton of `Fext` on a storey (`inv_mass0`), by 1 per m/s2 of
/// `ag` on a prescribed support (`ag_gain`; on a storey `ag` moves no absolute
/// acceleration, docs/coupling-ports.md). With that cluster's share `a`:
/// `d apAbs = a` (the storey's `1/M0` is the mobility of its floor, which a
/// StackOnFloor on it takes as `supportMobility`), `d abAbs[j] = a` for a
/// block of the cluster, `d F[j] = M_above,j a` for a stuck interface in it,
/// `d floorForce = -attachedMass a`; `d peakApAbs = sign(apAbs) a` while
/// `|apAbs|` is the running peak (the branch of the max that holds it);
/// `supportMobility` only enters the choice of a mode at a switch (0);
/// every other output (state, constant in a mode): 0.
pub fn directional(next: &Simulator, o: &Outputs, unknown: Id, known: Id) -> Option<f64> {
    let (s, mode) = (next.system(), next.mode());
    let d = Dynamics::new(s, mode);
    let share = match known {
        Id::Fext => d.inv_mass0,
        Id::Ag => d.ag_gain,
        Id::SupportMobility => 0.0,
        _ => return None,
    };
    let in_structure = |j: usize| j <= s.n && d.cluster_of[j] == 0;
    Some(match unknown {
        Id::ApAbs => share,
        Id::PeakApAbs if o.ap_abs.abs() >= o.peak_ap_abs => o.ap_abs.signum() * share,
        Id::AbAbs(j) if in_structure(j) => share,
        Id::F(j) if in_structure(j) && mode.is_stuck(j) => d.force_affine(j, mode).0 * share,
        Id::FloorForce => -d.attached_mass(mode) * share,
        Id::Up
        | Id::Vp
        | Id::BaseShear
        | Id::PeakUp
        | Id::PeakApAbs
        | Id::Einput
        | Id::Ekinetic
        | Id::Estrain
        | Id::Eviscous
        | Id::Efriction
        | Id::TSwitch
        | Id::AttachedMass
        | Id::SlidingForce
        | Id::AbAbs(_)
        | Id::F(_)
        | Id::Ub(_)
        | Id::Vb(_)
        | Id::Slip(_)
        | Id::PeakSlip(_) => 0.0,
        _ => return None,
    })
}
