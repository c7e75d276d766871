//! Property tests of the mode resolution over thousands of random states
//! (N = 1..8, random masses and frictions, some interfaces at zero relative
//! velocity), against an independent projected Gauss–Seidel (PGS) solution
//! of the box-constrained problem (RESEARCH.md §1).

mod common;
use common::Rng;
use stacked_live_load::physics::mode::{self, Contact, Dynamics, Guard, Mode, ResolveRequest};
use stacked_live_load::physics::system::System;
use stacked_live_load::Params;

struct Case {
    sys: System,
    req: ResolveRequest,
}

fn random_case(rng: &mut Rng, static_factor: (f64, f64)) -> Case {
    let (lo, hi) = static_factor;
    random_request(rng, |rng| rng.uniform(lo, hi), false)
}

/// A random request: N = 1..8, random masses, a tenth of the interfaces
/// frictionless, `mus = muk` times `static_factor`'s draw; on a prescribed
/// support (`prescribed`) most with a mobility and a reference mode of
/// their own.
fn random_request(
    rng: &mut Rng,
    mut static_factor: impl FnMut(&mut Rng) -> f64,
    prescribed: bool,
) -> Case {
    let mut p = Params {
        n_blocks: 1 + rng.below(8),
        ..Params::default()
    };
    if prescribed {
        p.support = stacked_live_load::Support::Prescribed;
    }
    for j in 0..p.n_blocks {
        p.alpha[j] = rng.uniform(0.05, 1.5);
        let mu = if rng.next_f64() < 0.1 {
            0.0
        } else {
            rng.uniform(0.02, 0.6)
        };
        p.muk[j] = mu;
        p.mus[j] = mu * static_factor(rng);
    }
    let mut sys = System::new(&p).unwrap();
    if prescribed && rng.next_f64() < 0.7 {
        sys.mobility = rng.uniform(0.0, 2.0) / p.mp;
        sys.ref_mass = rng.uniform(0.0, 1.0) * sys.mass_up[1][sys.n + 1];
        sys.ref_load = rng.uniform(-1.0, 1.0) * sys.normal[1] * 0.6;
    }
    let mut mode = Mode::all_stuck(&sys);
    let (mut zero, mut was_stuck) = (0u32, 0u32);
    for j in 1..=sys.n {
        if sys.is_free(j) {
            continue;
        }
        if rng.next_f64() < 0.5 {
            zero |= 1 << j;
            if rng.next_f64() < 0.5 {
                was_stuck |= 1 << j;
            }
        } else {
            mode.contact[j] = if rng.next_f64() < 0.5 {
                Contact::SlipForward
            } else {
                Contact::SlipBackward
            };
        }
    }
    // Spring, damper and external force on the structure: up to a few times
    // the friction capacity, so that both sticking and slipping occur (on a
    // support, its acceleration, m/s2, to a few times the friction's).
    let load0 = if prescribed {
        rng.uniform(-3.0, 3.0) * 0.6 * sys.g
    } else {
        rng.uniform(-3.0, 3.0) * sys.normal[1] * 0.6
    };
    Case {
        sys,
        req: ResolveRequest {
            mode,
            zero,
            must_break: 0,
            was_stuck,
            load0,
        },
    }
}

/// Delassus matrix entry W_ab of the chain (RESEARCH.md §1).
fn w(sys: &System, a: usize, b: usize) -> f64 {
    if a == b {
        1.0 / sys.mass[a - 1] + 1.0 / sys.mass[a]
    } else if a + 1 == b {
        -1.0 / sys.mass[a]
    } else if b + 1 == a {
        -1.0 / sys.mass[b]
    } else {
        0.0
    }
}

/// Interface forces by PGS: the zero-velocity interfaces solve the box QP
/// min ½ fᵀW f + qᵀf, |f_j| <= mu_j N_j; the others carry kinetic friction.
fn pgs(case: &Case) -> Vec<f64> {
    let sys = &case.sys;
    let n = sys.n;
    let mut f = vec![0.0; n + 1];
    // j is the interface: a bit of `zero` and an entry of four arrays.
    #[allow(clippy::needless_range_loop)]
    for j in 1..=n {
        if case.req.zero & (1 << j) == 0 {
            f[j] = -sys.muk[j] * sys.normal[j] * case.req.mode.contact[j].slip_sign();
        }
    }
    let b = |j: usize| {
        if j == 1 {
            -case.req.load0 / sys.mass[0]
        } else {
            0.0
        }
    };
    for _sweep in 0..200_000 {
        let mut change = 0.0f64;
        for j in 1..=n {
            if case.req.zero & (1 << j) == 0 {
                continue;
            }
            let r: f64 = b(j) + (1..=n).map(|l| w(sys, j, l) * f[l]).sum::<f64>();
            let limit = sys.mus[j] * sys.normal[j];
            let new = (f[j] - r / w(sys, j, j)).clamp(-limit, limit);
            change = change.max((new - f[j]).abs());
            f[j] = new;
        }
        if change <= 1e-16 * sys.normal[1] {
            break;
        }
    }
    f
}

fn forces(case: &Case, mode: &Mode) -> Vec<f64> {
    let d = Dynamics::new(&case.sys, mode);
    (0..=case.sys.n)
        .map(|j| {
            if j == 0 || case.sys.is_free(j) {
                0.0
            } else {
                d.force(j, mode, case.req.load0)
            }
        })
        .collect()
}

#[test]
fn equal_static_and_kinetic_friction_matches_projected_gauss_seidel() {
    let mut rng = Rng(0x9E3779B97F4A7C15);
    let mut worst = 0.0f64;
    let (mut stuck_seen, mut slip_started) = (0, 0);
    for i in 0..5000 {
        let case = random_case(&mut rng, (1.0, 1.0));
        let res = mode::resolve(&case.sys, &case.req);
        assert!(res.consistent, "case {i}: no consistent mode");
        let got = forces(&case, &res.mode);
        let expected = pgs(&case);
        for j in 1..=case.sys.n {
            // Tolerance 1e-12 of the largest friction capacity (the bottom
            // interface's normal force) on every interface force.
            let err = (got[j] - expected[j]).abs() / case.sys.normal[1];
            worst = worst.max(err);
            assert!(
                err < 1e-12,
                "case {i}, interface {j}: {} vs {}",
                got[j],
                expected[j]
            );
            if case.req.zero & (1 << j) != 0 {
                match res.mode.contact[j] {
                    Contact::Stuck => stuck_seen += 1,
                    _ => slip_started += 1,
                }
            }
        }
    }
    eprintln!(
        "worst force difference {worst:.1e}; {stuck_seen} stuck, {slip_started} starting to slip"
    );
    assert!(
        stuck_seen > 1000 && slip_started > 1000,
        "both outcomes must be exercised"
    );
}

/// Every assignment of the zero-velocity interfaces, with its violation.
fn all_assignments(case: &Case) -> Vec<(Mode, f64)> {
    let zero: Vec<usize> = (1..=case.sys.n)
        .filter(|&j| case.req.zero & (1 << j) != 0)
        .collect();
    let mut out = vec![];
    for code in 0..3usize.pow(zero.len() as u32) {
        let mut mode = case.req.mode;
        let mut c = code;
        for &j in &zero {
            mode.contact[j] = [Contact::Stuck, Contact::SlipForward, Contact::SlipBackward][c % 3];
            c /= 3;
        }
        out.push((
            mode,
            mode::violation(&case.sys, &mode, case.req.zero, case.req.load0),
        ));
    }
    out
}

fn stuck_count(mode: &Mode, mask: u32) -> u32 {
    (1..=mode.n)
        .filter(|&j| mask & (1 << j) != 0 && mode.is_stuck(j))
        .count() as u32
}

#[test]
fn static_above_kinetic_friction_follows_the_selection_rule() {
    // With mus > muk several assignments can be consistent (RESEARCH.md §1);
    // the resolver must return one of them, with the largest stick set, and
    // among those the most of the previously stuck interfaces.
    let mut rng = Rng(0xD1B54A32D192ED03);
    let mut ambiguous = 0;
    for i in 0..3000 {
        let case = random_case(&mut rng, (1.05, 2.0));
        let res = mode::resolve(&case.sys, &case.req);
        let candidates = all_assignments(&case);
        let consistent: Vec<&(Mode, f64)> = candidates
            .iter()
            .filter(|(_, v)| *v <= mode::CONSISTENCY_TOL)
            .collect();
        assert!(
            !consistent.is_empty(),
            "case {i}: brute force finds no consistent mode"
        );
        assert!(res.consistent, "case {i}: resolver found none");
        if consistent.len() > 1 {
            ambiguous += 1;
        }
        // The engine's statistic (nAmbiguous) counts the same assignments.
        assert_eq!(
            mode::consistent_count(&case.sys, &case.req) as usize,
            consistent.len(),
            "case {i}: consistent_count"
        );
        let all = u32::MAX;
        let best_stuck = consistent
            .iter()
            .map(|(m, _)| stuck_count(m, all))
            .max()
            .unwrap();
        assert_eq!(
            stuck_count(&res.mode, all),
            best_stuck,
            "case {i}: largest stick set"
        );
        let best_kept = consistent
            .iter()
            .filter(|(m, _)| stuck_count(m, all) == best_stuck)
            .map(|(m, _)| stuck_count(m, case.req.was_stuck))
            .max()
            .unwrap();
        assert_eq!(
            stuck_count(&res.mode, case.req.was_stuck),
            best_kept,
            "case {i}: keep stuck"
        );
    }
    eprintln!("{ambiguous} of 3000 states had more than one consistent mode");
    assert!(ambiguous > 100, "the rule must actually be exercised");
}

#[test]
fn an_interface_at_its_static_limit_breaks() {
    // One block on a structure pushed so that the stick force is just above
    // mus N: the resolver must let it slip when told it must break, and the
    // slip direction must oppose the force.
    let mut p = Params {
        n_blocks: 1,
        ..Params::default()
    };
    p.mus[0] = 0.3;
    p.muk[0] = 0.2;
    let sys = System::new(&p).unwrap();
    let stuck = Mode::all_stuck(&sys);
    // Stuck force F = m1 * load0 / (m0 + m1); choose load0 so that F = mus N.
    let limit = sys.mus[1] * sys.normal[1];
    let load0 = limit * (sys.mass[0] + sys.mass[1]) / sys.mass[1];
    let req = ResolveRequest {
        mode: stuck,
        zero: 1 << 1,
        must_break: 1 << 1,
        was_stuck: 1 << 1,
        load0,
    };
    let res = mode::resolve(&sys, &req);
    assert!(res.consistent);
    // Positive force on the block means it lags: it slides backwards.
    assert_eq!(res.mode.contact[1], Contact::SlipBackward);
    // Without the break request the same instant may stay stuck (prefer sticking).
    let res = mode::resolve(
        &sys,
        &ResolveRequest {
            must_break: 0,
            ..req
        },
    );
    assert_eq!(res.mode.contact[1], Contact::Stuck);
}

/// Case `i`, with the stuck interfaces at zero made to break three times in
/// ten: the walk's resolution, asserted the same as the enumeration's
/// (mode, consistency, ambiguity).
fn decided_as_the_enumeration(rng: &mut Rng, case: &mut Case, i: usize) -> mode::Resolved {
    if rng.next_f64() < 0.3 {
        case.req.must_break = case.req.zero & case.req.was_stuck;
    }
    let walk = mode::resolve(&case.sys, &case.req);
    let all = mode::resolve_by_enumeration(&case.sys, &case.req);
    assert_eq!(walk.mode, all.mode, "case {i}: {:?}", case.req);
    assert_eq!(walk.consistent, all.consistent, "case {i}: {:?}", case.req);
    assert_eq!(walk.ambiguous, all.ambiguous, "case {i}: {:?}", case.req);
    walk
}

#[test]
fn the_walk_decides_exactly_as_the_enumeration_of_every_assignment() {
    // `mode::resolve` walks the stack and drops inconsistent branches;
    // `mode::resolve_by_enumeration` tries all 3^k assignments in the
    // selection rule's order. Both apply the one contact law
    // (`mode::violation`, cluster by cluster), which the PGS test above and
    // the exact reference check independently; this checks the walk's
    // search, bound and ranking. Expected: the same mode and the same
    // ambiguity flag (consistent_count > 1 where some mus > muk), over
    // random requests with equal and unequal friction, some interfaces
    // that must break.
    let mut rng = Rng(0x3a1f_77c5_9e21_0b4d);
    let (mut ambiguous, mut breaking) = (0, 0);
    for i in 0..6000 {
        let factor = if i % 2 == 0 { (1.0, 1.0) } else { (1.05, 2.5) };
        let mut case = random_case(&mut rng, factor);
        let walk = decided_as_the_enumeration(&mut rng, &mut case, i);
        ambiguous += usize::from(walk.ambiguous);
        breaking += usize::from(case.req.must_break != 0);
    }
    assert!(ambiguous > 300 && breaking > 1000, "{ambiguous} {breaking}");
}

#[test]
fn the_walk_decides_as_the_enumeration_on_supports_and_mixed_friction() {
    // As the test above, on what its cases lack (found by a review): stacks
    // mixing μs = μk and μs > μk interfaces, and prescribed supports with a
    // mobility and a reference mode of their own (the support's law is
    // part of every cluster's contact law there). Expected: the same mode,
    // consistency and ambiguity flag from the walk (with its cascade and
    // its shortcuts) and from the enumeration of every assignment.
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let (mut ambiguous, mut on_support) = (0, 0);
    for i in 0..4000 {
        let prescribed = i % 2 == 1;
        // Each interface μs = μk or μs > μk.
        let mixed = |rng: &mut Rng| {
            if rng.next_f64() < 0.5 {
                1.0
            } else {
                rng.uniform(1.05, 2.5)
            }
        };
        let mut case = random_request(&mut rng, mixed, prescribed);
        let walk = decided_as_the_enumeration(&mut rng, &mut case, i);
        ambiguous += usize::from(walk.ambiguous);
        on_support += usize::from(prescribed && walk.ambiguous);
    }
    assert!(
        ambiguous > 100 && on_support > 30,
        "{ambiguous} {on_support}"
    );
}

#[test]
fn the_ambiguity_count_does_not_flip_with_rounding() {
    // At a stick break the assignment that keeps the breaking stick stuck
    // violates the law by about CONSISTENCY_TOL itself (the guard fires at
    // mus N (1 + tol)); it is no rival (rule 1 leaves it), else the count
    // of ambiguous switches turns on where the event lands within its
    // tolerance. Expected: every shared record and the same record scaled by
    // (1 + 2^-52) give the same nAmbiguous, on the tall stack with static
    // above kinetic friction and on the paper's two blocks. (Before the
    // fix, 10 of the 20 shared records flipped on the tall stack.)
    use stacked_live_load::{ground::record, GroundMotion, Settings, Simulator};
    let dir = common::shared_record("");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.to_lowercase().ends_with(".at2"))
        .collect();
    names.sort();
    assert!(!names.is_empty(), "no records in {}", dir.display());
    let count = |p: &Params, gm: &GroundMotion| {
        let mut sim = Simulator::new(p, &Settings::default()).unwrap();
        record::run(&mut sim, gm, 1.0).unwrap();
        sim.outputs().n_ambiguous
    };
    let (mut flips, mut ambiguous) = (vec![], 0);
    let scenes = [
        common::graded_stack_static_above_kinetic(),
        common::graded_stack(2),
    ];
    for (s, p) in scenes.iter().enumerate() {
        for name in &names {
            let gm = common::truncate(&common::read_shared(name, 9.81), 20.0);
            let mut up = gm.clone();
            up.accel.iter_mut().for_each(|a| *a *= 1.0 + f64::EPSILON);
            let (a, b) = (count(p, &gm), count(p, &up));
            ambiguous += a;
            if a != b {
                flips.push(format!("scene {s} {name}: {a} -> {b}"));
            }
        }
    }
    assert!(flips.is_empty(), "{flips:#?}");
    assert!(ambiguous > 0, "the count must be exercised");
}

#[test]
fn a_breaking_stick_that_another_slip_relieves_is_a_rival() {
    // A review's case (graded stack, KJM000 at 10.44 s): interface 1 reaches
    // mus N (must break); the rule slips it, but interface 2 slipping
    // instead leaves it stuck well inside its capacity, a second solution
    // of the contact law (only the state just left, at the limit, is no
    // rival). Two blocks, muk2 in [muk1, mus1): |F1| = 0.92 mus N there.
    let mut p = Params {
        n_blocks: 2,
        ..Params::default()
    };
    (p.mus[0], p.muk[0], p.mus[1], p.muk[1]) = (0.3, 0.2, 0.4, 0.25);
    let sys = System::new(&p).unwrap();
    let limit = sys.mus[1] * sys.normal[1];
    let load0 = limit * (sys.mass[0] + sys.mass[1] + sys.mass[2]) / (sys.mass[1] + sys.mass[2]);
    let req = ResolveRequest {
        mode: Mode::all_stuck(&sys),
        zero: 0b110,
        must_break: 0b10,
        was_stuck: 0b110,
        load0,
    };
    let res = mode::resolve(&sys, &req);
    assert_eq!(
        res.mode.contact[1..3],
        [Contact::SlipBackward, Contact::Stuck]
    );
    let mut rival = req.mode;
    rival.contact[2] = Contact::SlipBackward;
    assert!(mode::violation(&sys, &rival, req.zero, load0) < -0.05);
    assert_eq!(mode::consistent_count(&sys, &req), 2);
    assert!(res.ambiguous && mode::resolve_by_enumeration(&sys, &req).ambiguous);
}

// (Moved from src/physics/mode.rs: they use its public items only.)

#[test]
fn clusters_follow_the_stuck_interfaces() {
    let p = Params {
        n_blocks: 3,
        ..Params::default()
    };
    let sys = System::new(&p).unwrap();
    let mut mode = Mode::all_stuck(&sys);
    mode.contact[2] = Contact::SlipForward;
    let d = Dynamics::new(&sys, &mode);
    assert_eq!(d.n_clusters, 2);
    assert_eq!(d.cluster_of[..4], [0, 0, 1, 1]);
    // Cluster 1 (blocks 2, 3) is pushed back by friction muk2 N2.
    let expected = -sys.muk[2] * sys.normal[2];
    assert_eq!(d.slip_load[1], expected);
    assert_eq!(d.slip_load[0], -expected);
}

#[test]
fn the_stick_band_is_inside_every_stick() {
    // Expected: at the band's edges every stuck guard is still positive,
    // and just beyond them (1e-9 relative) one is negative.
    let sys = System::new(&Params::default()).unwrap();
    let d = Dynamics::new(&sys, &Mode::all_stuck(&sys));
    let guards = &d.guards[..d.n_guards];
    assert_eq!(guards.len(), 2);
    let fires = |a: f64| {
        guards.iter().any(|g| match *g {
            Guard::Stuck {
                mass_above,
                f_top,
                cap,
            } => cap - (mass_above * a + f_top).abs() < 0.0,
            Guard::Slip { .. } => false,
        })
    };
    let (lo, hi) = mode::safe_accel_band(guards);
    assert!(lo < 0.0 && hi > 0.0);
    assert!(!fires(lo) && !fires(hi));
    assert!(fires(hi * (1.0 + 1e-9)) && fires(lo * (1.0 + 1e-9)));
}
