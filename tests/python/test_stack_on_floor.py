"""StackOnFloor (issue #22), the binary's second model, under fmpy: both FMUs
(FMI 2.0 and 3.0) validate, ship the same library under the model's name,
declare the dependencies of the force on the floor, and simulate a stack on a
floor whose acceleration is a tabulated input.

Where expected values come from: the force the stack puts on the floor is
minus the sum of the blocks' momentum rates, `floorForce = -sum m_j abAbs[j]`
(Newton's law on the blocks, independent of how the FMU computes it), and
`slidingForce = floorForce + attachedMass ag` by definition; the bit-for-bit
agreement with the engine is checked in Rust (tests/stack_on_floor.rs,
tests/c_abi.rs)."""

from __future__ import annotations

import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))
import sll  # noqa: E402

FLOOR2 = ROOT / "target" / "fmu" / "StackOnFloor.fmu"
FLOOR3 = ROOT / "target" / "fmu" / "fmi3" / "StackOnFloor.fmu"
STOREY3 = ROOT / "target" / "fmu" / "fmi3" / "StackedLiveLoad.fmu"
MASSES = [400.0, 150.0, 75.0]
START = {"nBlocks": 3, "m[1]": 400.0, "m[2]": 150.0, "m[3]": 75.0,
         "mus[1]": 0.3, "mus[2]": 0.2, "mus[3]": 0.1,
         "muk[1]": 0.25, "muk[2]": 0.2, "muk[3]": 0.08}
OUT = ["floorForce", "attachedMass", "slidingForce", "abAbs[1]", "abAbs[2]", "abAbs[3]",
       "stuck[1]", "nEvents", "Efriction"]


@pytest.fixture(scope="session")
def fmus() -> dict[int, Path]:
    storey2 = sll.build_fmu()  # builds all four
    assert FLOOR2.exists() and FLOOR3.exists()
    return {2: FLOOR2, 3: FLOOR3, "storey": storey2}


def floor_input(stop: float = 4.0) -> np.ndarray:
    """A floor acceleration table: a 1.5 Hz shaking of 4 m/s2 under a 5 Hz
    ripple, sampled every 5 ms (fmpy interpolates it)."""
    t = np.arange(0.0, stop + 1e-9, 0.005)
    a = 4.0 * np.sin(2 * np.pi * 1.5 * t) + 0.8 * np.sin(2 * np.pi * 5.0 * t)
    return np.array(list(zip(t, a)), dtype=[("time", np.float64), ("ag", np.float64)])


def test_both_fmus_validate_and_carry_the_one_library_under_their_name(fmus):
    for version in (2, 3):
        assert validate_fmu(str(fmus[version])) == []
    md2, md3 = read_model_description(str(FLOOR2)), read_model_description(str(FLOOR3))
    storey = read_model_description(str(fmus["storey"]))
    assert md2.coSimulation.modelIdentifier == md3.coSimulation.modelIdentifier == "StackOnFloor"
    assert md2.guid == md3.instantiationToken != storey.guid
    assert md2.coSimulation.providesDirectionalDerivative
    # (fmpy does not read FMI 3.0's attribute: the XML itself.)
    xml3 = zipfile.ZipFile(FLOOR3).read("modelDescription.xml").decode()
    assert 'providesDirectionalDerivatives="true"' in xml3
    assert storey.coSimulation.providesDirectionalDerivative  # d apAbs/d Fext: the floor's mobility
    # The same platforms as StackedLiveLoad.fmu, the binary named after the model.
    for floor, storey_fmu in ((FLOOR2, fmus["storey"]), (FLOOR3, STOREY3)):
        names = {n for n in zipfile.ZipFile(floor).namelist() if n.startswith("binaries/")}
        storey_names = {n for n in zipfile.ZipFile(storey_fmu).namelist()
                        if n.startswith("binaries/")}
        assert names == {n.replace("StackedLiveLoad", "StackOnFloor") for n in storey_names}
        assert all("/StackOnFloor." in n for n in names if not n.endswith("/"))
    names = {v.name for v in md2.modelVariables}
    for storey_only in ["mp", "Tp", "zeta", "Fext", "up", "baseShear", "solver", "alpha[1]"]:
        assert storey_only not in names
    for needed in ["ag", "supportMobility", "floorForce", "attachedMass", "slidingForce",
                   "m[8]", "ub[1]", "peakSlip[8]", "stuck[8]", "Einput", "tSwitch", "nAmbiguous"]:
        assert needed in names


def test_declared_dependencies(fmus):
    md = read_model_description(str(FLOOR2))
    deps = {u.variable.name: sorted(v.name for v in u.dependencies) for u in md.outputs}
    for name in ["floorForce", "attachedMass", "slidingForce", "abAbs[3]", "F[1]", "stuck[2]"]:
        assert deps[name] == ["ag", "supportMobility"], name
    for name in ["ub[1]", "vb[1]", "slip[1]", "peakSlip[1]", "Einput", "Ekinetic",
                 "Efriction", "tSwitch", "nEvents", "nAmbiguous"]:
        assert deps[name] == [], name
    md3 = read_model_description(str(FLOOR3))
    deps3 = {u.variable.name: sorted(v.name for v in u.dependencies) for u in md3.outputs}
    assert deps3 == deps


@pytest.mark.parametrize("version", [2, 3])
def test_fmpy_simulates_a_stack_on_a_tabulated_floor(fmus, version):
    sig = floor_input()
    r = simulate_fmu(str(fmus[version]), stop_time=4.0, output_interval=0.005, input=sig,
                     start_values=START, output=OUT)
    momentum = sum(m * r[f"abAbs[{j}]"] for j, m in enumerate(MASSES, 1))
    scale = sum(m * np.abs(r[f"abAbs[{j}]"]) for j, m in enumerate(MASSES, 1)) + 1.0
    assert np.all(np.abs(r["floorForce"] + momentum) <= 1e-12 * scale)
    # slidingForce = floorForce + attachedMass ag, with ag as the FMU held it
    # at each output point: abAbs of an attached block is ag itself.
    attached = r["attachedMass"] > 0
    ag_held = r["abAbs[1]"]
    expected = r["floorForce"] + r["attachedMass"] * ag_held
    assert np.all(np.abs(r["slidingForce"][attached] - expected[attached])
                  <= 1e-9 * (np.abs(r["floorForce"][attached]) + 1.0))
    assert np.all(r["slidingForce"][~attached] == r["floorForce"][~attached])
    # Both regimes, and switches between them.
    assert attached.any() and (~attached).any()
    assert r["nEvents"][-1] > 5 and r["Efriction"][-1] > 0
    assert np.all(np.isfinite(r["floorForce"]))


def test_fmi2_and_fmi3_agree_without_early_return(fmus):
    sig = floor_input(2.0)
    runs = [simulate_fmu(str(fmus[v]), stop_time=2.0, output_interval=0.01, input=sig,
                         start_values=START, output=OUT, **({"early_return_allowed": False}
                                                            if v == 3 else {}))
            for v in (2, 3)]
    for name in ["floorForce", "attachedMass", "slidingForce", "Efriction"]:
        np.testing.assert_array_equal(runs[0][name], runs[1][name])


def test_directional_derivative_is_minus_the_attached_mass(fmus):
    md = read_model_description(str(FLOOR2))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipdir = extract(str(FLOOR2))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir,
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="dd")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    seen = set()
    t = 0.0
    for k in range(200):
        fmu.setReal([vr["ag"]], [3.5 * np.sin(0.1 * k)])
        fmu.doStep(t, 0.01)
        t += 0.01
        ff, attached = fmu.getReal([vr["floorForce"], vr["attachedMass"]])
        dd = fmu.getDirectionalDerivative([vr["floorForce"], vr["slidingForce"], vr["abAbs[2]"]],
                                          [vr["ag"]], [1.0])
        assert dd[0] == -attached and dd[1] == 0.0
        assert dd[2] in (0.0, 1.0)
        seen.add(attached)
    assert len(seen) > 1
    fmu.terminate()
    fmu.freeInstance()


def test_hostile_values_are_refused_without_a_crash(fmus):
    md = read_model_description(str(FLOOR3))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipdir = extract(str(FLOOR3))
    fmu = FMU3Slave(guid=md.instantiationToken, unzipDirectory=unzipdir,
                    modelIdentifier="StackOnFloor", instanceName="hostile")
    fmu.instantiate()
    for name, value in [("m[2]", -1.0), ("supportMobility", -1e-3), ("ag", float("nan")),
                        ("ag", 1e300)]:
        with pytest.raises(Exception):
            fmu.setFloat64([vr[name]], [value])
    for n in (0, 9):
        with pytest.raises(Exception):
            fmu.setInt32([vr["nBlocks"]], [n])
    fmu.setFloat64([vr["mus[1]"], vr["muk[1]"]], [0.1, 0.2])  # muk > mus
    fmu.enterInitializationMode()
    with pytest.raises(Exception):
        fmu.exitInitializationMode()
    fmu.freeInstance()
    # A token of neither model is refused at instantiation.
    bad = FMU3Slave(guid="{00000000-0000-0000-0000-000000000000}", unzipDirectory=unzipdir,
                    modelIdentifier="StackOnFloor", instanceName="bad")
    with pytest.raises(Exception):
        bad.instantiate()
