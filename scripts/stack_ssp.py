"""Writes the two-FMU building as an SSP file: a storey (StackedLiveLoad.fmu,
nBlocks = 0: the floor) carrying a stack of blocks (StackOnFloor.fmu), with
stack.ag <- storey.apAbs and storey.Fext <- +stack.floorForce
(docs/stack-on-a-floor.md, sll/cosim/ssp.py).

    python scripts/stack_ssp.py [--out out/ssp]    # -> out/ssp/StackOnStorey.ssp
"""

from __future__ import annotations

import argparse
from pathlib import Path

import use_venv  # noqa: F401  (re-runs this script under the repository's .venv if needed)

from sll import ROOT, fmu_path  # noqa: E402
from sll.cosim.ssp import write_building_ssp  # noqa: E402

STOREY = {"mp": 1000.0, "Tp": 0.5, "zeta": 0.05}
STACK = {"nBlocks": 2, "m[1]": 150.0, "m[2]": 100.0, "mus[1]": 0.2, "muk[1]": 0.15,
         "mus[2]": 0.15, "muk[2]": 0.12}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="out/ssp")
    args = ap.parse_args()
    storey = fmu_path()  # builds both FMUs if missing
    stack = ROOT / "target" / "fmu" / "StackOnFloor.fmu"
    path = write_building_ssp(Path(args.out) / "StackOnStorey.ssp", storey, stack, STOREY, STACK)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
