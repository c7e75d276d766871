"""The FMU's coupling ports through the C ABI under fmpy (issue #12, items 1-3;
docs/coupling-ports.md): the declared dependencies as an importer reads them,
output derivatives against the closed form of the bare structure, and
tSwitch. The physics behind each is tested in detail in tests/coupling_ports.rs."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from fmpy import read_model_description

ROOT = Path(__file__).resolve().parents[2]
import sll  # noqa: E402


@pytest.fixture(scope="module")
def model():
    with sll.Model(sll.build_fmu()) as m:
        yield m


def test_outputs_declare_fext_feedthrough_only_where_the_equations_have_it():
    md = read_model_description(str(sll.build_fmu()))
    assert md.coSimulation.maxOutputDerivativeOrder == 2
    declared = {u.variable.name: [d.name for d in u.dependencies] for u in md.outputs}
    feedthrough = {"apAbs", "peakApAbs"} | {f"{q}[{j}]" for q in ("abAbs", "F", "stuck")
                                            for j in range(1, 9)}
    for name, deps in declared.items():
        # From MODEL.md's equations written in absolute accelerations: only the
        # structure's load (Fext - k u - c v) enters at the same instant.
        assert deps == (["Fext"] if name in feedthrough else []), name
    assert "tSwitch" in declared
    # An importer's view of the two-storey loop upper.ag <- lower.apAbs <-
    # lower.Fext <- upper.baseShear: baseShear depends on no input.
    assert declared["baseShear"] == [] and declared["apAbs"] == ["Fext"]


def test_derivatives_and_t_switch_through_the_c_interface(model):
    # Bare SDOF from rest under constant ag = a: u = -(a / w^2) (1 - cos w t)
    # undamped, so at t: u' = -(a / w) sin w t, u'' = -a cos w t,
    # u''' = a w sin w t. apAbs = u'' + a.
    s = model.slave
    tp, a = 0.5, 2.0
    w = 2 * math.pi / tp
    model.start({"nBlocks": 0, "zeta": 0.0, "Tp": tp, "maxStep": 1e-4}, stop=1.0)
    vr = [model.vr(n) for n in ("up", "vp", "apAbs")]
    t, h = 0.0, 0.01
    for _ in range(37):
        s.setReal([model.vr("ag")], [a])
        s.doStep(t, h)
        t += h
        assert s.getReal([model.vr("tSwitch")])[0] == t  # no switch without blocks
    s.setReal([model.vr("ag")], [a])
    d1 = s.getRealOutputDerivatives(vr, [1, 1, 1])
    d2 = s.getRealOutputDerivatives(vr, [2, 2, 2])
    sn, cs = math.sin(w * t), math.cos(w * t)
    expected1 = [-(a / w) * sn, -a * cs, a * w * sn]
    expected2 = [-a * cs, a * w * sn, a * w * w * cs]
    for got, want, scale in zip(d1 + d2, expected1 + expected2,
                                [a / w, a, a * w, a, a * w, a * w * w]):
        assert abs(got - want) < 1e-9 * scale
    with pytest.raises(Exception):
        s.getRealOutputDerivatives([model.vr("tSwitch")], [1])
