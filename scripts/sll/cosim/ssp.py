"""The two-FMU building as an SSP file (System Structure and
Parameterization 1.0): a storey FMU (StackedLiveLoad.fmu with nBlocks = 0: the
floor) and StackOnFloor.fmu standing on it (docs/stack-on-a-floor.md).

    write_building_ssp("out/ssp/StackOnStorey.ssp", storey_fmu, stack_fmu,
                       storey={"mp": 1000.0, "Tp": 0.5}, stack={"nBlocks": 2, ...})

The .ssp is a zip of SystemStructure.ssd and the two FMUs (resources/). In the
system:
- `stack.ag <- storey.apAbs` (m/s2, gain +1): the floor's absolute
  acceleration carries the stack;
- `storey.Fext <- stack.floorForce` (N, gain +1): the force the stack puts on
  the floor along +x is what the floor takes;
- the system's input `ag` (m/s2) drives the storey's support (the ground), its
  outputs `drift` (storey.up, m) and `floorForce` (N) show the result;
- parameter bindings: the storey's (nBlocks = 0 always) and the stack's, and
  the stack's `supportMobility` = 1/mp (the floor's mobility, 1/kg) as the
  start value of that input.
No LinearTransformation is written: every gain is +1 (SSP's identity).
"""

from __future__ import annotations

import zipfile
from pathlib import Path
from xml.sax.saxutils import quoteattr

from fmpy import read_model_description

UNITS = {  # name: SI base exponents
    "m": {"m": 1}, "m/s2": {"m": 1, "s": -2}, "N": {"kg": 1, "m": 1, "s": -2},
    "kg": {"kg": 1}, "1/kg": {"kg": -1}, "s": {"s": 1}, "1": {},
}
CONNECTIONS = [  # (start element, start connector, end element, end connector, unit)
    ("", "ag", "storey", "ag", "m/s2"),
    ("storey", "apAbs", "stack", "ag", "m/s2"),
    ("stack", "floorForce", "storey", "Fext", "N"),
    ("storey", "up", "", "drift", "m"),
    ("stack", "floorForce", "", "floorForce", "N"),
]


def _kind_unit(md, name: str) -> tuple[str, str, str]:
    """(kind, type, unit) of a variable of an FMU, for its SSD connector."""
    v = {x.name: x for x in md.modelVariables}[name]
    unit = v.unit or (v.declaredType.unit if v.declaredType is not None else None) or ""
    kind = {"input": "input", "output": "output", "parameter": "parameter"}.get(v.causality, "output")
    return kind, v.type, unit


def _real(unit: str) -> str:
    return f'<ssc:Real unit="{unit}"/>' if unit else "<ssc:Real/>"


def _value(name: str, value) -> str:
    if isinstance(value, bool):
        body = f'<ssv:Boolean value="{str(value).lower()}"/>'
    elif isinstance(value, int):
        body = f'<ssv:Integer value="{value}"/>'
    elif isinstance(value, float):
        body = f'<ssv:Real value="{value!r}"/>'
    else:
        body = f"<ssv:String value={quoteattr(str(value))}/>"
    return f'          <ssv:Parameter name={quoteattr(name)}>{body}</ssv:Parameter>'


def write_building_ssp(path: str | Path, storey_fmu: str | Path, stack_fmu: str | Path,
                       storey: dict, stack: dict) -> Path:
    """Writes the .ssp and returns its path. `storey`: the storey FMU's
    parameters (nBlocks is forced to 0); `stack`: StackOnFloor's parameters."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    mds = {"storey": read_model_description(str(storey_fmu)), "stack": read_model_description(str(stack_fmu))}
    storey = {**storey, "nBlocks": 0}
    mp = float(storey.get("mp", {v.name: v for v in mds["storey"].modelVariables}["mp"].start))
    stack = {**stack, "supportMobility": 1.0 / mp}
    params = {"storey": storey, "stack": stack}
    for comp, values in params.items():
        names = {v.name for v in mds[comp].modelVariables}
        unknown = sorted(set(values) - names)
        if unknown:
            raise ValueError(f"{comp}: the FMU has no variable {', '.join(unknown)}")
    used = {"storey": set(), "stack": set()}
    for a, ac, b, bc, _ in CONNECTIONS:
        if a:
            used[a].add(ac)
        if b:
            used[b].add(bc)
    units = set()
    components = []
    for comp, fmu in (("storey", storey_fmu), ("stack", stack_fmu)):
        connectors = []
        for name in sorted(used[comp]):
            kind, _, unit = _kind_unit(mds[comp], name)
            units.add(unit)
            connectors.append(f'        <ssd:Connector name="{name}" kind="{kind}">{_real(unit)}</ssd:Connector>')
        values = "\n".join(_value(n, v) for n, v in params[comp].items())
        components.append(f'''    <ssd:Component name="{comp}" type="application/x-fmu-sharedlibrary" source="resources/{comp}.fmu">
      <ssd:Connectors>
{chr(10).join(connectors)}
      </ssd:Connectors>
      <ssd:ParameterBindings>
        <ssd:ParameterBinding>
          <ssd:ParameterValues>
        <ssv:ParameterSet version="1.0" name="{comp}">
          <ssv:Parameters>
{values}
          </ssv:Parameters>
        </ssv:ParameterSet>
          </ssd:ParameterValues>
        </ssd:ParameterBinding>
      </ssd:ParameterBindings>
    </ssd:Component>''')
    system_connectors = [
        '      <ssd:Connector name="ag" kind="input"><ssc:Real unit="m/s2"/></ssd:Connector>',
        '      <ssd:Connector name="drift" kind="output"><ssc:Real unit="m"/></ssd:Connector>',
        '      <ssd:Connector name="floorForce" kind="output"><ssc:Real unit="N"/></ssd:Connector>',
    ]
    units |= {"m/s2", "m", "N"}
    connections = []
    for a, ac, b, bc, _unit in CONNECTIONS:
        start = f' startElement="{a}"' if a else ""
        end = f' endElement="{b}"' if b else ""
        connections.append(f'      <ssd:Connection{start} startConnector="{ac}"{end} endConnector="{bc}"/>')
    unit_xml = []
    for u in sorted(units - {""}):
        base = " ".join(f'{k}="{e}"' for k, e in UNITS[u].items())
        unit_xml.append(f'    <ssc:Unit name="{u}"><ssc:BaseUnit {base}/></ssc:Unit>')
    ssd = f'''<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"
    version="1.0" name="StackOnStorey" generationTool="StackedLiveLoad scripts/stack_ssp.py">
  <ssd:System name="building" description="A storey (StackedLiveLoad.fmu, nBlocks = 0) carrying a stack of blocks (StackOnFloor.fmu): stack.ag = storey.apAbs, storey.Fext = +stack.floorForce">
    <ssd:Connectors>
{chr(10).join(system_connectors)}
    </ssd:Connectors>
    <ssd:Elements>
{chr(10).join(components)}
    </ssd:Elements>
    <ssd:Connections>
{chr(10).join(connections)}
    </ssd:Connections>
  </ssd:System>
  <ssd:Units>
{chr(10).join(unit_xml)}
  </ssd:Units>
</ssd:SystemStructureDescription>
'''
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("SystemStructure.ssd", ssd)
        z.write(storey_fmu, "resources/storey.fmu")
        z.write(stack_fmu, "resources/stack.fmu")
    return path
