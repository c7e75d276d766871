"""The shear building of sll/coupling.py as one FMU, assembled by fmucontainer
(PyPI fmu-manipulation-toolbox) from copies of this FMU, one per storey.

    from sll.building_container import build_container
    fmu = build_container(storeys, (t, ag), H=0.005, out_dir=DIR, sequential=False)
    fmpy.simulate_fmu(fmu, stop_time=t[-1], output_interval=0.005, output=["up1", "up2"])

The links are coupling.py's ports: storey i's `ag` <- `apAbs` of storey i-1,
storey i's `Fext` <- `baseShear` of storey i+1; storey 1 reads the ground from
`recordFile`, a CSV put into its copy's resources/. The container exposes
`up1`..`upN` (drifts) and `apAbs1`..`apAbsN`. It steps every storey every
`H` with the inputs held (zero order): in parallel (`sequential=False`: a
Jacobi master) or in the listed order, bottom up (`sequential=True`: Gauss-
Seidel, each storey taking the newest outputs of those below).
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

from fmpy import read_model_description

from sll import fmu_path
from sll.coupling import write_record_csv

GROUND = "ground.csv"


def fmucontainer() -> Path:
    """The fmucontainer command of the venv this Python runs in."""
    exe = Path(sys.executable).parent / "fmucontainer"
    if not exe.exists():
        raise FileNotFoundError(f"{exe} not found: pip install fmu-manipulation-toolbox (requirements.txt)")
    return exe


def typed_start(storeys: list[dict], fmu: Path) -> list[list]:
    """Start values as the variables' types want them (nBlocks is an Integer)."""
    kinds = {v.name: v.type for v in read_model_description(str(fmu)).modelVariables}
    cast = {"Real": float, "Integer": int, "Boolean": bool, "String": str}
    start = []
    for i, params in enumerate(storeys, 1):
        for name, value in params.items():
            if name not in kinds:
                raise ValueError(f"storey {i}: {name} is not a variable of the FMU")
            start.append([f"storey{i}.fmu", name, cast[kinds[name]](value)])
    return start


def build_container(storeys: list[dict], record, H: float, out_dir: Path,
                    sequential: bool = False, fmu: Path | None = None) -> Path:
    """Writes out_dir/building.fmu (and its JSON description) and returns its path."""
    fmu = Path(fmu) if fmu else fmu_path()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    write_record_csv(*record, out_dir / GROUND)
    n = len(storeys)
    names = [f"storey{i}.fmu" for i in range(1, n + 1)]
    for name in names:
        shutil.copy(fmu, out_dir / name)
    with zipfile.ZipFile(out_dir / names[0], "a") as z:
        z.write(out_dir / GROUND, f"resources/{GROUND}")
    links = [[names[i - 1], "apAbs", names[i], "ag"] for i in range(1, n)]
    links += [[names[i + 1], "baseShear", names[i], "Fext"] for i in range(n - 1)]
    outputs = [[names[i], "up", f"up{i + 1}"] for i in range(n)]
    outputs += [[names[i], "apAbs", f"apAbs{i + 1}"] for i in range(n)]
    start = typed_start(storeys, fmu) + [[names[0], "recordFile", GROUND]]
    description = {
        "name": "building.fmu", "step_size": H, "sequential": sequential, "mt": False,
        "auto_link": False, "auto_input": False, "auto_output": False, "auto_parameter": False,
        "fmu": names, "link": links, "output": outputs, "start": start,
    }
    (out_dir / "building.json").write_text(json.dumps(description, indent=1))
    done = subprocess.run([str(fmucontainer()), "-container", "building.json",
                           "-fmu-directory", str(out_dir)],
                          cwd=out_dir, capture_output=True, text=True, timeout=300)
    built = out_dir / "building.fmu"
    if done.returncode != 0 or not built.exists():
        raise RuntimeError(f"fmucontainer failed ({done.returncode}):\n{done.stdout}\n{done.stderr}")
    return built
