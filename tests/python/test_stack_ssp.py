"""The two-FMU building as an SSP file (issue #22, item 4): written by
scripts/stack_ssp.py (sll.cosim.ssp), read back with fmpy's SSP reader (which
validates it against the SSP 1.0 schema), and run by fmpy's SSP simulator.

Where the expected values come from: the components, connections, units and
parameters are those the script was asked to write; the run of fmpy's
simulate_ssp (a Jacobi master with held inputs, reading every output once after the step
and applying the connections after
every component has stepped, so the system's input reaches the storey one step
late) is compared with sll.cosim's Jacobi master configured the same way on the
same two FMUs: the same calls in the same order, so equal to rounding."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmpy.ssp.simulation import simulate_ssp
from fmpy.ssp.ssd import Parameter, ParameterSet, read_ssd

import sll
from sll.cosim import CoSimulation, FMUPartner, Partner
from sll.coupling import broadband_record

ROOT = Path(__file__).resolve().parents[2]
STACK = ROOT / "target" / "fmu" / "StackOnFloor.fmu"


@pytest.fixture(scope="module")
def ssp(tmp_path_factory):
    if not STACK.exists():
        sll.build_fmu()
    if not STACK.exists():
        pytest.skip("target/fmu/StackOnFloor.fmu is not built (scripts/build_fmu.sh)")
    out = tmp_path_factory.mktemp("ssp")
    subprocess.run([sys.executable, str(ROOT / "scripts" / "stack_ssp.py"), "--out", str(out)], check=True,
                   capture_output=True)
    return out / "StackOnStorey.ssp"


def bindings(component) -> dict:
    return {p.name: (p.type, p.value) for b in component.parameterBindings
            for s in b.parameterValues for p in s.parameters}


def test_the_ssd_holds_the_two_fmus_their_links_units_and_parameters(ssp):
    import stack_ssp

    ssd = read_ssd(str(ssp))  # validates against SystemStructureDescription.xsd
    system = ssd.system
    components = {c.name: c for c in system.elements}
    assert {n: c.source for n, c in components.items()} == {"storey": "resources/storey.fmu",
                                                            "stack": "resources/stack.fmu"}
    links = {(c.startElement, c.startConnector, c.endElement, c.endConnector) for c in system.connections}
    assert ("storey", "apAbs", "stack", "ag") in links
    assert ("stack", "floorForce", "storey", "Fext") in links
    assert (None, "ag", "storey", "ag") in links
    # Gain +1: no transformation on any connection.
    assert all(getattr(c, "linearTransformation", None) is None for c in system.connections)
    units = {u.name: (u.kg, u.m, u.s) for u in ssd.units}
    assert units["N"] == (1, 1, -2) and units["m/s2"] == (0, 1, -2) and units["m"] == (0, 1, 0)
    # Connector units (fmpy does not read them: from the XML).
    import zipfile
    from lxml import etree

    root = etree.fromstring(zipfile.ZipFile(ssp).read("SystemStructure.ssd"))
    ns = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
          "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon"}
    unit_of = {(c.getparent().getparent().get("name"), c.get("name")): c.find("ssc:Real", ns).get("unit")
               for c in root.iter("{%s}Connector" % ns["ssd"])}
    assert unit_of[("storey", "apAbs")] == unit_of[("stack", "ag")] == "m/s2"
    assert unit_of[("stack", "floorForce")] == unit_of[("storey", "Fext")] == "N"
    storey, stack = bindings(components["storey"]), bindings(components["stack"])
    assert storey["nBlocks"] == ("Integer", "0")
    assert float(storey["mp"][1]) == stack_ssp.STOREY["mp"]
    assert float(stack["supportMobility"][1]) == 1.0 / stack_ssp.STOREY["mp"]
    for name, value in stack_ssp.STACK.items():
        assert float(stack[name][1]) == value, name
    # The FMUs inside are the built ones.
    with zipfile.ZipFile(ssp) as z:
        assert z.getinfo("resources/stack.fmu").file_size == STACK.stat().st_size


class Delayed(Partner):
    """The ground as a partner whose output at t is ag(t - H): what fmpy's SSP
    simulator gives the storey (system inputs reach components a step late)."""

    def __init__(self, name, f, H):
        super().__init__(name)
        self.f, self.H = f, H

    def start(self, t0=0.0, stop=None):
        self.t = t0

    def get(self, port):
        return self.f(self.t - self.H) if self.t > 0 else 0.0

    def step(self, t, h):
        self.t = t + h
        return self.t


def test_fmpy_simulates_the_ssp_as_sll_cosim_does(ssp):
    import stack_ssp

    t, ag = broadband_record(151, duration=2.0)
    f = lambda x: float(np.interp(x, t, ag))  # noqa: E731
    H, stop = 0.005, 2.0
    ssd = read_ssd(str(ssp))
    params = ParameterSet(parameters=[])
    for c in ssd.system.elements:
        for name, (kind, value) in bindings(c).items():
            p = Parameter(name=f"{c.name}.{name}")
            p.value = int(value) if kind == "Integer" else float(value)
            params.parameters.append(p)
    res = simulate_ssp(str(ssp), stop_time=stop, step_size=H, parameter_set=params, input={"ag": f})
    storey = FMUPartner("storey", sll.FMU_PATH, {**stack_ssp.STOREY, "nBlocks": 0})
    stack = FMUPartner("stack", STACK, {**stack_ssp.STACK, "supportMobility": 1.0 / stack_ssp.STOREY["mp"]})
    ground = Delayed("ground", f, H)
    sim = CoSimulation([storey, stack, ground], [
        ("ground.ag", "storey.ag", 1, "m/s2"), ("storey.apAbs", "stack.ag", 1, "m/s2"),
        ("stack.floorForce", "storey.Fext", 1, "N")])
    run = sim.run(stop, H, master="jacobi", extrapolation="constant", consistent=False,
                  record=["storey.up", "stack.floorForce"])
    storey.close()
    stack.close()
    # fmpy's row k holds the outputs after the step from k H (time column k H);
    # it takes one step more than stop / H (its time is summed in floats).
    n = len(run["time"]) - 1
    assert len(res) >= n
    res = res[:n]
    drift = run["storey.up"][1:]
    assert np.max(np.abs(res["drift"] - drift)) <= 1e-12 * np.max(np.abs(drift))
    assert np.max(np.abs(drift)) > 1e-4 and math.isfinite(float(np.max(np.abs(res["floorForce"]))))
    np.testing.assert_allclose(res["floorForce"], run["stack.floorForce"][1:], rtol=0, atol=1e-9)
