"""The co-simulation master library sll.cosim (issue #22): a stack of blocks
(StackOnFloor.fmu) on a floor of another model, coupled by the Jacobi,
Gauss-Seidel and interface-Jacobian masters.

Where the expected values come from:
- blocks that cannot slip (mu = 50): the stack is a rigid mass on the floor, so
  the coupled system is the linear building with the blocks' mass added to
  that floor, which tests/python/linear_floors.py solves exactly (matrix
  exponential over each linear piece of the inputs);
- a one-storey partner with a sliding stack: the storey FMU StackedLiveLoad.fmu
  carrying the same stack is that very system solved in one model (exact
  stick/slip switches; checked against exact references by the Rust suite);
- the misconfigurations: the messages the masters give.
Records and buildings are generated fresh from seeds (broadband_record)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import sll
from linear_floors import LinearFloors
from sll.cosim import CoSimulation, ConfigurationError, FMUPartner, OpenSeesPartner
from sll.coupling import broadband_record, observed_order, write_record_csv

ROOT = Path(__file__).resolve().parents[2]
STACK2 = ROOT / "target" / "fmu" / "StackOnFloor.fmu"
STACK3 = ROOT / "target" / "fmu" / "fmi3" / "StackOnFloor.fmu"
LINKS = [("stack.floorForce", "frame.floor2.force", +1, "N"), ("frame.floor2.accel", "stack.ag", +1, "m/s2")]


@pytest.fixture(scope="module")
def fmus():
    if not STACK2.exists():
        try:
            sll.build_fmu()
        except Exception as e:  # noqa: BLE001
            pytest.skip(f"StackOnFloor.fmu could not be built: {e}")
    if not STACK2.exists():
        pytest.skip("target/fmu/StackOnFloor.fmu is not built (scripts/build_fmu.sh)")
    return STACK2, STACK3


def building(seed: int, n: int = 3):
    """n floors, masses 800-1200 kg, storey periods giving a first mode of
    0.2-0.6 s, 2-5 % stiffness-proportional damping."""
    rng = np.random.default_rng(seed)
    m = rng.uniform(800, 1200, n)
    k = rng.uniform(2e6, 5e6, n)
    zeta = rng.uniform(0.02, 0.05)
    w1 = math.sqrt(np.min(np.linalg.eigvals(np.linalg.solve(np.diag(m), LinearFloors("x", m, k, k, ([0, 1], [0, 0])).K)).real))
    return m, k, 2 * zeta / w1 * k


def stack_params(masses, mu=None, seed: int | None = None) -> dict:
    """Two blocks; mu None: sliding (seeded: mus1 0.15-0.25 > muk1, mu2 0.1-0.15)."""
    p = {"nBlocks": 2, "m[1]": float(masses[0]), "m[2]": float(masses[1])}
    if mu is not None:
        p.update({"mus[1]": mu, "muk[1]": mu, "mus[2]": mu, "muk[2]": mu})
    else:
        rng = np.random.default_rng(seed)
        mu1, mu2 = rng.uniform(0.15, 0.25), rng.uniform(0.1, 0.15)
        p.update({"mus[1]": 1.2 * mu1, "muk[1]": mu1, "mus[2]": mu2, "muk[2]": mu2})
    return p


def relative(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(b)))


def couple(frame, stack, H, master, stop, extrapolation="linear", events="auto", record=(), consistent=False):
    """Jacobi and Gauss-Seidel exchange once per point here (consistent=False):
    the plain explicit coupling whose added-mass behaviour is tested."""
    sim = CoSimulation([frame, stack], LINKS)
    return sim.run(stop, H, master=master, extrapolation=extrapolation, events=events,
                   order=["frame", "stack"], record=list(record), consistent=consistent)


def monolithic(m, k, c, M, rec, stop, floor=1):
    masses = np.array(m, float)
    masses[floor] += M
    mono = LinearFloors("mono", masses, k, c, rec)
    return CoSimulation([mono], []).run(stop, 0.0005, record=[f"mono.floor{i}.disp" for i in (1, 2, 3)])


def test_interface_jacobian_master_equals_the_monolithic_building_when_blocks_cannot_slip(fmus):
    # The attached mass is the whole stack and the sliding force 0: the
    # partner integrates exactly the monolithic building (1e-9: the FMU's own
    # integration of the blocks does not enter the floor at all).
    rec = broadband_record(101, duration=5.0)
    m, k, c = building(102)
    blocks = (0.15 * m[1], 0.10 * m[1])
    ref = monolithic(m, k, c, sum(blocks), rec, 5.0)
    for fmu in fmus:
        stack = FMUPartner("stack", fmu, stack_params(blocks, mu=50.0))
        for H in (0.0005, 0.005, 0.02):
            run = couple(LinearFloors("frame", m, k, c, rec), stack, H, "interface-jacobian", 5.0,
                         record=["frame.floor1.disp", "stack.slip[1]", "stack.attachedMass"])
            got = run["frame.floor1.disp"]
            want = np.interp(run["time"], ref["time"], ref["mono.floor1.disp"])
            assert relative(got, want) < 1e-9, (fmu.parent.name, H)
            assert np.all(run["stack.attachedMass"] == sum(blocks)) and np.max(np.abs(run["stack.slip[1]"])) == 0
        stack.close()


def test_gauss_seidel_and_jacobi_converge_to_the_monolithic_building(fmus):
    # Explicit coupling of the same rigid stack (25 % of the floor's mass):
    # Gauss-Seidel (frame first, linear extrapolation) converges at second
    # order, Jacobi with held inputs at first order; the interface-Jacobian
    # master is exact at every H.
    rec = broadband_record(111, duration=5.0)
    m, k, c = building(112)
    blocks = (0.15 * m[1], 0.10 * m[1])
    ref = monolithic(m, k, c, sum(blocks), rec, 5.0)
    stack = FMUPartner("stack", fmus[0], stack_params(blocks, mu=50.0))
    steps = (0.004, 0.002, 0.001)
    orders = {}
    for master, ex in (("gauss-seidel", "linear"), ("jacobi", "constant")):
        errors = []
        for H in steps:
            run = couple(LinearFloors("frame", m, k, c, rec), stack, H, master, 5.0, ex, record=["frame.floor1.disp"])
            errors.append(relative(run["frame.floor1.disp"], np.interp(run["time"], ref["time"], ref["mono.floor1.disp"])))
        orders[master] = observed_order(steps, errors)
        print(master, ex, errors, orders[master])
    stack.close()
    assert 1.8 <= orders["gauss-seidel"] <= 2.2
    assert 0.8 <= orders["jacobi"] <= 1.3


def test_jacobi_diverges_where_the_interface_jacobian_master_is_stable(fmus):
    # Added mass: blocks of 50 % of the floor's mass under Jacobi with linear
    # extrapolation (the floor's acceleration feeds the stack's force, which
    # feeds the floor's acceleration, one step late) is unstable at every H
    # from 0.5 to 20 ms: the oscillation grows until the floor's acceleration
    # reaches 50 g, where blocks that cannot slip in the real system (mu = 50)
    # do slip, which caps it; the drift is wrong by 87 % to 690 % of its peak
    # (measured). With 25 % the same happens at H <= 10 ms; at 20 ms Jacobi
    # is stable there (13 % error): the bound depends on H against the periods.
    # The interface-Jacobian master stays exact (1e-9).
    rec = broadband_record(121, duration=4.0)
    m, k, c = building(122)
    blocks = (0.30 * m[1], 0.20 * m[1])
    cap = 50.0 * 9.81 * sum(blocks)
    ref = monolithic(m, k, c, sum(blocks), rec, 4.0)
    stack = FMUPartner("stack", fmus[0], stack_params(blocks, mu=50.0))
    for H in (0.0005, 0.001, 0.002, 0.005, 0.01, 0.02):
        for master in ("jacobi", "interface-jacobian"):
            run = couple(LinearFloors("frame", m, k, c, rec), stack, H, master, 4.0, "linear",
                         record=["frame.floor1.disp", "stack.floorForce"])
            want = np.interp(run["time"], ref["time"], ref["mono.floor1.disp"])
            err = relative(run["frame.floor1.disp"], want)
            force = np.max(np.abs(run["stack.floorForce"]))
            print(master, H, err, force / cap)
            if master == "jacobi":
                assert err > 0.1 and force > 0.99 * cap, (H, err, force / cap)
            else:
                assert err < 1e-9 and force < 0.05 * cap, (H, err)
    stack.close()


def test_consistent_sweeps_iterate_the_loop_and_fail_above_the_floor_mass(fmus):
    # consistent=True sweeps the exchange at a communication point until no
    # value changes, at most partners + 1 = 3 times: on the stack's algebraic
    # loop (floorForce depends on ag, the floor's acceleration on its force)
    # that is a fixed-point iteration, whose error shrinks as (M/m) per sweep.
    # Measured here: blocks of 50 % of the floor's mass, Jacobi with linear
    # extrapolation becomes stable and converges (1.3e-4 of the peak drift at
    # H = 0.5 ms); at 150 % the sweeps diverge (an error of 1.3 at 0.5 ms).
    rec = broadband_record(121, duration=4.0)
    m, k, c = building(122)
    for ratio, bound in ((0.5, lambda e: e < 1e-3), (1.5, lambda e: e > 0.5)):
        blocks = (0.6 * ratio * m[1], 0.4 * ratio * m[1])
        ref = monolithic(m, k, c, sum(blocks), rec, 4.0)
        stack = FMUPartner("stack", fmus[0], stack_params(blocks, mu=50.0))
        run = couple(LinearFloors("frame", m, k, c, rec), stack, 0.0005, "jacobi", 4.0, "linear",
                     record=["frame.floor1.disp"], consistent=True)
        err = relative(run["frame.floor1.disp"], np.interp(run["time"], ref["time"], ref["mono.floor1.disp"]))
        stack.close()
        assert bound(err), (ratio, err)


def storey_reference(tmp_path, rec, mp, tp, zeta, params, stop, dt):
    """The storey FMU carrying the stack: the exact coupled system."""
    csv = write_record_csv(*rec, tmp_path / "ground.csv")
    storey = FMUPartner("storey", sll.FMU_PATH, {
        "recordFile": str(csv), "nBlocks": 2, "mp": mp, "Tp": tp, "zeta": zeta,
        "alpha[1]": params["m[1]"] / mp, "alpha[2]": params["m[2]"] / mp,
        **{f"{q}[{j}]": params[f"{q}[{j}]"] for q in ("mus", "muk") for j in (1, 2)}})
    out = CoSimulation([storey], []).run(stop, dt, record=["storey.up", "storey.slip[1]", "storey.slip[2]"])
    peaks = [storey.get(f"peakSlip[{j}]") for j in (1, 2)]
    storey.close()
    return out, peaks


def one_storey(mp=1000.0, tp=0.4, zeta=0.05):
    k = mp * (2 * math.pi / tp) ** 2
    return [mp], [k], [2 * zeta * math.sqrt(k * mp)]


@pytest.mark.parametrize("which,events", [("fmi2", "rollback"), ("fmi2", "stack-first"), ("fmi3", "rollback"), ("fmi3", "stack-first")])
def test_a_sliding_stack_on_a_one_storey_partner_equals_the_storey_fmu(fmus, tmp_path, which, events):
    # Targets of the issue at H = 5 ms: peak drift within 1e-3 and peak slip
    # within 1e-2 (relative); order >= 1 as H halves (4, 2, 1 ms).
    stop, mp, tp, zeta = 6.0, 1000.0, 0.4, 0.05
    rec = broadband_record(131, duration=stop)
    params = stack_params((250.0, 150.0), seed=132)
    ref, ref_peaks = storey_reference(tmp_path, rec, mp, tp, zeta, params, stop, 0.001)
    fmu = fmus[0] if which == "fmi2" else fmus[1]
    stack = FMUPartner("stack", fmu, params, early_return=which == "fmi3")
    links = [("stack.floorForce", "frame.floor1.force", +1, "N"), ("frame.floor1.accel", "stack.ag", +1, "m/s2")]
    errors, peak_errors = [], []
    for H in (0.005, 0.004, 0.002, 0.001):
        sim = CoSimulation([LinearFloors("frame", *one_storey(mp, tp, zeta), rec), stack], links)
        run = sim.run(stop, H, master="interface-jacobian", events=events, record=["frame.floor1.disp"])
        grid = run["on_grid"]
        drift = run["frame.floor1.disp"][grid]
        want = np.interp(run["time"][grid], ref["time"], ref["storey.up"])
        peaks = [stack.get(f"peakSlip[{j}]") for j in (1, 2)]
        peak_slip = max(abs(p - q) / q for p, q in zip(peaks, ref_peaks))
        print(which, events, H, relative(drift, want), abs(np.max(np.abs(drift)) / np.max(np.abs(want)) - 1),
              peak_slip, run["landings"])
        if H == 0.005:
            assert abs(np.max(np.abs(drift)) / np.max(np.abs(want)) - 1) < 1e-3
            assert peak_slip < 1e-2
            assert run["landings"] > 5, "the scene must slide"
        else:
            errors.append(relative(drift, want))
            peak_errors.append(peak_slip)
    stack.close()
    order = observed_order((0.004, 0.002, 0.001), errors)
    print("order", order)
    if which == "fmi2":
        assert order >= 1.0
    else:
        # FMI 3.0 has no input derivatives: the stack holds the floor's
        # acceleration over each of the master's 4 pieces per step, so a stuck
        # block breaks loose at a piece's start (an error of up to H/4 in the
        # switch time), and the error is erratic in H (measured orders 1.17
        # with rollback, 0.44 stack-first); it stays below 1e-3 of the peak.
        assert max(errors) < 1e-3


@pytest.mark.parametrize("events", ["rollback", "stack-first"])
def test_a_block_that_comes_to_rest_and_sticks_keeps_the_stick(fmus, tmp_path, events):
    """Issue #22's hard case: one block with mus 0.08 > muk 0.05 as heavy as a
    one-storey partner (1000 kg, T = 0.5 s, 5 %), seeded record 171 (6 s, PGA
    3 m/s2). At t = 3.9709 s the block, slipping backward, comes to
    rest, and both sticking and slipping forward are consistent (an ambiguous
    switch, counted by the storey's nAmbiguous); the monolithic model sticks
    for 3.9 ms. The coupled run must stick too: before the fix, the rollback
    landing gave the stack the floor's old-mode acceleration first, which broke
    the stick, and the drift history error stayed at 5.0e-2 at every H.
    Expected values: the storey FMU carrying the same block (exact; 3
    ambiguous switches in the 6 s). Bounds: the issue's target, order >= 1 as
    H halves (measured 1.68 rollback, 1.51 stack-first; drift history errors
    2.9e-4, 7.2e-5, 2.1e-5, 9.2e-6 and 2.0e-4, 5.0e-5, 1.7e-5, 9.0e-6 at
    H = 5, 2.5, 1.25, 0.625 ms, docs/stack-on-a-floor.md), and at 0.625 ms
    below 5e-5: five times the measured error, a thousand times below the
    other continuation's 5e-2. Runtime about 5 s."""
    stop, mp, tp, zeta = 6.0, 1000.0, 0.5, 0.05
    rec = broadband_record(171, duration=stop, pga=3.0)
    params = {"nBlocks": 1, "m[1]": 1000.0, "mus[1]": 0.08, "muk[1]": 0.05}
    csv = write_record_csv(*rec, tmp_path / "ground.csv")
    storey = FMUPartner("storey", sll.FMU_PATH, {"recordFile": str(csv), "nBlocks": 1, "mp": mp, "Tp": tp,
                                                 "zeta": zeta, "alpha[1]": 1.0, "mus[1]": 0.08, "muk[1]": 0.05})
    ref = CoSimulation([storey], []).run(stop, 0.0005, record=["storey.up"])
    ambiguous = int(storey.get("nAmbiguous"))
    storey.close()
    assert ambiguous >= 1, "the record must contain an ambiguous switch"
    links = [("stack.floorForce", "frame.floor1.force", +1, "N"), ("frame.floor1.accel", "stack.ag", +1, "m/s2")]
    Hs, errors = (0.005, 0.0025, 0.00125, 0.000625), []
    for H in Hs:
        stack = FMUPartner("stack", fmus[0], params)
        sim = CoSimulation([LinearFloors("frame", *one_storey(mp, tp, zeta), rec), stack], links)
        run = sim.run(stop, H, master="interface-jacobian", events=events, record=["frame.floor1.disp"])
        stack.close()
        grid = run["on_grid"]
        want = np.interp(run["time"][grid], ref["time"], ref["storey.up"])
        errors.append(relative(run["frame.floor1.disp"][grid], want))
    order = observed_order(Hs, errors)
    print(events, ambiguous, errors, order)
    assert order >= 1.0, (errors, order)
    assert errors[-1] < 5e-5, errors


def test_misconfigurations_are_refused_with_the_reason(fmus, tmp_path):
    rec = broadband_record(141, duration=1.0)
    m, k, c = building(142)
    stack = FMUPartner("stack", fmus[0], stack_params((100.0, 100.0), mu=0.2))
    frame = LinearFloors("frame", m, k, c, rec)
    storey = FMUPartner("frame", sll.FMU_PATH, {"nBlocks": 0})

    def refused(partners, links, match, **kw):
        with pytest.raises(ConfigurationError, match=match):
            CoSimulation(partners, links).run(1.0, 0.01, **kw)

    # The storey FMU's mass is a parameter: no add_mass, no interface-Jacobian master.
    refused([storey, stack], [("stack.floorForce", "frame.Fext", 1), ("frame.apAbs", "stack.ag", 1)],
            "cannot add mass", master="interface-jacobian")
    refused([frame, stack], [("stack.floorForce", "frame.floor2.force", -1), ("frame.floor2.accel", "stack.ag", 1)],
            "gain -1", master="interface-jacobian")
    refused([frame, stack], [("stack.floorForce", "frame.floor2.force", 1)], "no accel connection",
            master="interface-jacobian")
    refused([frame, stack], LINKS, "master = 'newton'", master="newton")
    with pytest.raises(ConfigurationError, match="no partner 'fram'"):
        CoSimulation([frame, stack], [("stack.floorForce", "fram.floor2.force", 1)])
    with pytest.raises(ConfigurationError, match="early return needs an FMI 3.0"):
        FMUPartner("s2", fmus[0], early_return=True)
    if fmus[1].exists():
        early = FMUPartner("stack", fmus[1], stack_params((100.0, 100.0), mu=0.2), early_return=True)
        refused([frame, early], LINKS, "may return early", master="jacobi")
        early.close()
    if _opensees() is None:
        import openseespy.opensees as ops

        def build():
            ops.model("basic", "-ndm", 1, "-ndf", 1)
            ops.node(0, 0.0)
            ops.fix(0, 1)
            ops.node(1, 0.0, "-mass", 1000.0)
            ops.uniaxialMaterial("Elastic", 1, 4e6, 4e3)
            ops.element("zeroLength", 1, 0, 1, "-mat", 1, "-dir", 1)

        os_frame = OpenSeesPartner("frame", build, {"floor1": 1}, ground=rec)
        links1 = [("stack.floorForce", "frame.floor1.force", 1), ("frame.floor1.accel", "stack.ag", 1)]
        refused([os_frame, stack], links1, "frame cannot roll back", master="interface-jacobian", events="rollback")
    storey.close()
    stack.close()


def _opensees():
    from sll import opensees_block

    return opensees_block.available()


def test_the_opensees_example_at_one_step(fmus, tmp_path):
    """scripts/stack_on_opensees.py's pieces on the first 5 s of El Centro at
    H = 5 ms, interface-Jacobian master (events: stack-first, OpenSees cannot
    roll back). Expected: (1) blocks that cannot slip on the 3-storey frame
    equal the monolithic OpenSees frame with their mass on floor 2 (the same
    analysis steps: 1e-9); (2) the stack on a one-storey OpenSees frame equals
    the storey FMU carrying it (exact) within the issue's targets: peak drift
    1e-3, peak slip 1e-2 (OpenSees' Newmark at 0.1 ms is part of the error)."""
    reason = _opensees()
    if reason is not None:
        pytest.skip(f"openseespy does not import: {reason}")
    import stack_on_opensees as ex

    if not ex.RECORD.exists():
        pytest.skip(f"{ex.RECORD} is not there (../shared/ground_motions)")
    t, ag = sll.read_record(ex.RECORD)
    ground = (t[t <= 5.0], ag[t <= 5.0])
    rigid = {**ex.STACK, **{f"{q}[{j}]": 50.0 for q in ("mus", "muk") for j in (1, 2)}}
    mono = ex.frame_partner(ground, False, added=rigid["m[1]"] + rigid["m[2]"])
    ref = CoSimulation([mono], []).run(5.0, 0.005, record=ex.RECORDED[:3])
    mono.close()
    run = ex.couple(ground, False, "interface-jacobian", "linear", 0.005, rigid)
    assert run["failed"] == ""
    assert relative(ex.drifts(run), ex.drifts(ref)) < 1e-9
    # One storey against the storey FMU.
    k, c = ex.shear_frame(1, ex.FLOOR_MASS, ex.T1, ex.ZETA)
    csv = write_record_csv(*ground, tmp_path / "ground.csv")
    storey = FMUPartner("storey", sll.FMU_PATH, {
        "recordFile": str(csv), "nBlocks": 2, "mp": ex.FLOOR_MASS, "Tp": ex.T1, "zeta": ex.ZETA,
        "alpha[1]": ex.STACK["m[1]"] / ex.FLOOR_MASS, "alpha[2]": ex.STACK["m[2]"] / ex.FLOOR_MASS,
        **{f"{q}[{j}]": ex.STACK[f"{q}[{j}]"] for q in ("mus", "muk") for j in (1, 2)}})
    exact = CoSimulation([storey], []).run(5.0, 0.005, record=["storey.up"])
    exact_slips = [storey.get(f"peakSlip[{j}]") for j in (1, 2)]
    storey.close()
    frame = OpenSeesPartner("frame", ex.builder(1, [ex.FLOOR_MASS], k, 2 * ex.ZETA * math.sqrt(k * ex.FLOOR_MASS)),
                            {"floor1": 1}, ground=ground, dt_max=ex.DT_FRAME)
    stack = FMUPartner("stack", fmus[0], ex.STACK)
    sim = CoSimulation([frame, stack], [("stack.floorForce", "frame.floor1.force", +1, "N"),
                                        ("frame.floor1.accel", "stack.ag", +1, "m/s2")])
    with pytest.raises(ConfigurationError, match="frame cannot roll back"):
        sim.run(5.0, 0.005, master="interface-jacobian", events="rollback")
    r = sim.run(5.0, 0.005, master="interface-jacobian", record=["frame.floor1.disp"])
    slips = [stack.get(f"peakSlip[{j}]") for j in (1, 2)]
    stack.close()
    frame.close()
    peak, want = np.max(np.abs(r["frame.floor1.disp"])), np.max(np.abs(exact["storey.up"]))
    slip_error = max(abs(p - q) for p, q in zip(slips, exact_slips)) / max(exact_slips)
    print("one storey: peak drift", peak / want - 1, "peak slip", slip_error, "landings", r["landings"])
    assert r["landings"] > 5 and max(exact_slips) > 0.01, "the scene must slide"
    assert abs(peak / want - 1) < 1e-3
    assert slip_error < 1e-2


def test_stacks_on_two_floors(fmus):
    # Two stacks (FMI 2.0 and FMI 3.0 instances) on floors 1 and 3, blocks
    # that cannot slip: the interface-Jacobian master equals the monolithic
    # building with both stacks' masses on their floors (2e-14 measured; 1e-9
    # asked), with either event handling.
    rec = broadband_record(161, duration=3.0)
    m, k, c = building(162)
    lower, upper = (0.1 * m[0], 0.1 * m[0]), (0.2 * m[2], 0.1 * m[2])
    masses = np.array(m, float)
    masses[0] += sum(lower)
    masses[2] += sum(upper)
    mono = LinearFloors("mono", masses, k, c, rec)
    ref = CoSimulation([mono], []).run(3.0, 0.001, record=["mono.floor1.disp", "mono.floor3.disp"])
    for events in ("rollback", "stack-first"):
        a = FMUPartner("a", fmus[0], stack_params(lower, mu=50.0))
        b = FMUPartner("b", fmus[1], stack_params(upper, mu=50.0), early_return=True)
        sim = CoSimulation([LinearFloors("frame", m, k, c, rec), a, b], [
            ("a.floorForce", "frame.floor1.force", 1, "N"), ("frame.floor1.accel", "a.ag", 1, "m/s2"),
            ("b.floorForce", "frame.floor3.force", 1, "N"), ("frame.floor3.accel", "b.ag", 1, "m/s2")])
        run = sim.run(3.0, 0.005, master="interface-jacobian", events=events,
                      record=["frame.floor1.disp", "frame.floor3.disp"])
        for f in ("floor1", "floor3"):
            want = np.interp(run["time"], ref["time"], ref[f"mono.{f}.disp"])
            assert relative(run[f"frame.{f}.disp"], want) < 1e-9, (events, f)
        a.close()
        b.close()


@pytest.mark.parametrize("events", ["rollback", "stack-first"])
def test_a_stick_near_its_capacity_holds_after_a_landing(fmus, events):
    """The OpenSees example's stack on the same 3-storey frame, here the exact
    linear partner, El Centro: at t = 5.4802 s block 2 comes to rest on block 1
    and reverses; with the new mode's floor acceleration (-3.910 m/s2) block
    1's stick needs 73 359 N of its 73 575 N (99.7 %) and holds until 5.6255 s
    (the rollback and stack-first runs at H = 0.1 ms agree, 5.0e-7 of the peak
    drift; docs/stack-on-a-floor.md). Before the fix, the FMU's look for a switch
    just past a landing re-referenced the support's law with the held ag, the
    old mode's floor acceleration (-4.166 m/s2, 77 197 N), so the stack showed
    block 1 slipping and every run at H >= 0.5 ms broke the stick."""
    import stack_on_opensees as ex

    if not ex.RECORD.exists():
        pytest.skip(f"{ex.RECORD} is not there (../shared/ground_motions)")
    t, ag = sll.read_record(ex.RECORD)
    stop = 5.7
    rec = (t[t <= stop + 0.1], ag[t <= stop + 0.1])
    k, c = ex.shear_frame(3, ex.FLOOR_MASS, ex.T1, ex.ZETA)
    stack = FMUPartner("stack", fmus[0], ex.STACK)
    sim = CoSimulation([LinearFloors("frame", [ex.FLOOR_MASS] * 3, [k] * 3, [c] * 3, rec), stack], LINKS)
    run = sim.run(stop, 0.001, master="interface-jacobian", events=events,
                  record=["stack.attachedMass", "stack.slidingForce"])
    stack.close()
    time, mass, sliding = run["time"], run["stack.attachedMass"], run["stack.slidingForce"]
    before = (time > 5.475) & (time < 5.480)
    after = (time > 5.4802) & (time < 5.62)
    assert np.all(mass[before] == ex.STACK["m[1]"]) and np.all(sliding[before] < 0), "block 2 slides backward"
    assert np.all(mass[after] == ex.STACK["m[1]"]), "block 1 must stay stuck"
    assert np.all(sliding[after] > 0), "block 2 reverses"
