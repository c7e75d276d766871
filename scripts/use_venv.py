"""Lets `python scripts/NAME.py` work as the docs write it: imported first by the
command scripts, it re-runs the script under the repository's .venv/bin/python when
the interpreter that started it lacks the packages (fmpy, numpy). A no-op when they
import, and when this module is imported by something other than a script of this
folder (a test, a notebook): only a script run as a program is re-run."""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
VENV_PYTHON = HERE.parent / ".venv" / "bin" / "python"
FLAG = "SLL_REEXEC"


def ensure() -> None:
    script = getattr(sys.modules.get("__main__"), "__file__", None)
    if not script or Path(script).resolve().parent != HERE:
        return
    try:
        import fmpy  # noqa: F401
        import numpy  # noqa: F401
        return
    except ImportError:
        pass
    if VENV_PYTHON.exists() and not os.environ.get(FLAG):
        os.environ[FLAG] = "1"
        os.execv(str(VENV_PYTHON), [str(VENV_PYTHON), script, *sys.argv[1:]])
    sys.exit(f"{Path(script).name}: fmpy and numpy are missing; run `bash scripts/setup.sh` (creates .venv) and "
             "then `python scripts/...` or `.venv/bin/python scripts/...`")


ensure()
