"""Issue #5: the theory behind the accuracy/speed chart and the stability map,
pinned through the FMU (the same code paths the scripts use), so that the
chart cannot silently lie. Expected values come from RK4's stability function
and the methods' orders (../shared/RESEARCH.md §2); the reference is solver 1 at
maxStep 1e-5 s, which the Rust suite checks against exact solutions."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
import accuracy_speed  # noqa: E402
import sll  # noqa: E402
from sll import opensees_block  # noqa: E402
import stability  # noqa: E402

SINGLE = accuracy_speed.SCENES["single"]


@pytest.fixture(scope="module")
def model():
    sll.build_fmu()
    with sll.Model() as m:
        yield m


@pytest.fixture(scope="module")
def harmonic(tmp_path_factory) -> Path:
    return accuracy_speed.harmonic_record(tmp_path_factory.mktemp("records"))


def test_solver_3_stays_below_its_rk4_stability_bound_whatever_maxstep(model):
    # With mu = 0 and zeta = 0, solver 3 is RK4 on the bare oscillator, whose
    # amplification per step is |R(i y)| = sqrt(1 - y^6/72 + y^8/576): 0.93 at
    # y = h omega = 2.80, 1.08 at 2.86 (plain RK4 diverges there: 1.08^300 = 1e10,
    # pinned in tests/regularized.rs). Issue 13: the FMU's solver 3 never steps
    # above 2.5 / omega, so a maxStep beyond the limit stays bounded too.
    tp = 1.0
    omega = 2 * math.pi / tp
    for y in (2.80, 2.86, 10.0):
        h = y / omega
        ag = np.zeros(300)
        ag[0] = 1.0  # one kick, then free vibration
        params = {"nBlocks": 1, "Tp": tp, "zeta": 0.0, "mus[1]": 0.0, "muk[1]": 0.0,
                  "solver": 3, "maxStep": h}
        r = model.run_input(ag, h, params)
        early = float(np.max(np.abs(r["up"][1:6])))  # about the amplitude
        late = float(np.max(np.abs(r["up"][-20:])))
        # Undamped free vibration: RK4 at h omega <= 2.5 only damps it a
        # little, so the late swings stay below the early ones (not 1e10 times).
        assert not r["failed"] and late < 2 * early, (y, early, late)


def test_automatic_steps_stay_within_1e6_of_the_reference_for_every_communication_step(model):
    # Every communication step of the map (1e-4 s to 1 s), at the shortest, a
    # middle and the longest period of the map; held input as a master gives it.
    event = {"event (auto)": stability.METHODS["event (auto)"]}
    for tp in (0.01, 0.3, 10.0):
        for h in stability.STEPS:
            duration = 1.0 if h < 1e-3 else 3.0
            (row,) = stability.cell(model, tp, float(h), duration, event)
            assert row["bounded"], row
            assert row["err_peak_drift"] < 1e-6, row
            assert row["err_history"] < 1e-6, row


def test_the_default_is_exact_at_any_max_step_and_step_end_is_first_order(model, harmonic):
    ref = model.run(harmonic, dict(SINGLE, maxStep=1e-5))
    ref_hist = model.run(harmonic, dict(SINGLE, maxStep=1e-5), dt=0.005)["up"]
    peak = ref["peaks"]["peakUp"]

    def history_error(solver, h):
        up = model.run(harmonic, dict(SINGLE, solver=solver, maxStep=h), dt=0.005)["up"]
        return np.max(np.abs(up - ref_hist)) / peak

    # The exact default (solver 1): maxStep only shortens its substeps, the
    # history stays within 1e-10 of the peak at every value.
    for h in (0.01, 0.0025, 0.00125):
        assert history_error(1, h) < 1e-10, h
    # Step-end switching: about first order; fit over four halvings because a
    # switch missed by a fraction of a step makes single ratios noisy.
    hs = [0.0025 / 2 ** k for k in range(4)]
    errs = [history_error(2, h) for h in hs]
    order = np.polyfit(np.log(hs), np.log(errs), 1)[0]  # error ~ h^order
    assert 0.6 < order < 1.5, (hs, errs, order)


def test_regularized_friction_has_an_error_floor_that_scales_with_eps(model, harmonic):
    # Drift-history error over the reference peak (the peak alone can be lucky).
    ref = model.run(harmonic, dict(SINGLE, maxStep=1e-5), dt=0.005)
    peak = ref["peaks"]["peakUp"]

    def error(params):
        return np.max(np.abs(model.run(harmonic, params, dt=0.005)["up"] - ref["up"])) / peak

    floors = []
    for eps in (1e-2, 1e-3):
        # A step well inside the stable range (half the explicit limit), and
        # half that: the step's own error is far below the floor.
        h = 0.5 * accuracy_speed.tanh_stable_step(SINGLE, eps)
        floors.append(error(dict(SINGLE, solver=3, frictionEps=eps, maxStep=h)))
        half = error(dict(SINGLE, solver=3, frictionEps=eps, maxStep=h / 2))
        assert abs(half - floors[-1]) < 0.01 * floors[-1], "a floor: a smaller step does not help"
    # Measured 6.2e-3 and 9.0e-4: about tenfold per decade of eps.
    assert 3 < floors[0] / floors[1] < 30, floors
    assert error(SINGLE) < 1e-4 * floors[1], floors


def test_the_chart_script_writes_its_csv_png_and_a_front(tmp_path):
    accuracy_speed.main(["--out", str(tmp_path), "--quick", "--repeats", "1"])
    with open(tmp_path / "accuracy_speed.csv") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0].keys()) == accuracy_speed.COLUMNS
    methods = {r["method"] for r in rows}
    assert {"exact", "step-end"} <= methods and any(m.startswith("tanh") for m in methods)
    if opensees_block.available() is None:
        assert any(m.startswith("opensees") for m in methods)
    assert (tmp_path / "accuracy_speed.png").stat().st_size > 10_000
    summary = (tmp_path / "summary.txt").read_text()
    assert "on the efficient front: yes" in summary, summary


def test_time_to_reach_ignores_lucky_points_and_floors():
    # error, seconds: a lucky 5e-7 at 2 s, then 3e-6 at 4 s: not reached at 2 s.
    pts = [(1e-3, 1.0), (5e-7, 2.0), (3e-6, 4.0), (8e-7, 8.0)]
    assert accuracy_speed.time_to_reach(pts, 1e-6) == (8.0, False)
    floor = [(1e-3, 1.0), (1e-3, 2.0), (1e-3, 4.0)]
    assert math.isinf(accuracy_speed.time_to_reach(floor, 1e-6)[0])
    # First order: error = 1e-3 / seconds, 1e-6 at 1000 s.
    trend = [(1e-3 / s, s) for s in (1.0, 2.0, 4.0, 8.0)]
    s, extrapolated = accuracy_speed.time_to_reach(trend, 1e-6)
    assert extrapolated and abs(s - 1000.0) < 1e-6


@pytest.mark.skipif(opensees_block.available() is not None, reason="openseespy does not import here")
def test_opensees_single_block_approaches_the_reference_as_its_stick_stiffens(model, harmonic):
    ref = model.run(harmonic, SINGLE)["peaks"]
    t, a = sll.read_record(harmonic)
    errs = []
    for k_stick in (1e6, 1e8):
        o = opensees_block.run(a, t[1] - t[0], 0.001, 1000.0, 0.5, 0.05, 0.5, 0.1, 9.81, k_stick)
        assert o["converged"]
        errs.append(abs(o["peakSlip"] - ref["peakSlip[1]"]) / ref["peakSlip[1]"])
    # RESEARCH.md §4: a few percent; a stiffer stick is closer to Coulomb's law.
    assert errs[1] < errs[0] and errs[1] < 0.05, errs
