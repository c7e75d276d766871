#!/usr/bin/env bash
# Creates .venv/ (if missing) with the Python packages, and builds the FMU.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ ! -x .venv/bin/python ]; then
  python3 -m venv .venv
fi
if ! .venv/bin/python -c "import fmpy, numpy, scipy, matplotlib, pytest, reqpy_M, dask, distributed, openseespy, fmu_manipulation_toolbox" 2>/dev/null; then
  .venv/bin/pip install --quiet --disable-pip-version-check -r requirements.txt
fi
# The sll package (scripts/sll, pyproject.toml), editable: anything run with .venv's
# python imports this checkout's copy, without editing sys.path.
if [ "$(.venv/bin/python -c 'import pathlib, sll; print(pathlib.Path(sll.__file__).resolve().parents[2])' 2>/dev/null)" != "$(pwd -P)" ]; then
  .venv/bin/pip install --quiet --disable-pip-version-check --no-deps -e . \
    || echo "setup: could not install the sll package (pip install -e .); the scripts find it beside them and pytest through pyproject.toml's pythonpath" >&2
fi
# openseespy's binary needs the system BLAS/LAPACK (Debian: libblas3, liblapack3).
# Without them the OpenSees points of the accuracy chart are left out, with a notice.
if ! ldconfig -p | grep -q "libblas.so.3"; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo -n"
  { $SUDO apt-get install -y -qq libblas3 liblapack3 >/dev/null 2>&1 \
    || { $SUDO apt-get update -qq >/dev/null 2>&1 && $SUDO apt-get install -y -qq libblas3 liblapack3 >/dev/null 2>&1; }; } \
    || echo "setup: could not install libblas3/liblapack3; OpenSees comparisons will be skipped" >&2
fi
# Cross builds (Windows x86-64 and aarch64 Linux binaries in both FMUs) and the
# emulators that test them (wine64, qemu-user). SLL_CROSS=0 skips them; where
# anything cannot be installed the FMUs carry fewer platforms and the platform
# tests say they were skipped and why.
if [ "${SLL_CROSS:-1}" != 0 ]; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo -n"
  # Bounded in time: a registry that does not answer must not stall the tests.
  timeout 300 rustup target add x86_64-pc-windows-gnu aarch64-unknown-linux-gnu >/dev/null 2>&1 \
    || echo "setup: rustup could not add the cross targets; the FMUs will carry fewer platforms" >&2
  need=()
  command -v x86_64-w64-mingw32-gcc >/dev/null || need+=(gcc-mingw-w64-x86-64)
  command -v aarch64-linux-gnu-gcc >/dev/null || need+=(gcc-aarch64-linux-gnu libc6-dev-arm64-cross)
  command -v qemu-aarch64 >/dev/null || need+=(qemu-user)
  { [ -x /usr/lib/wine/wine64 ] || command -v wine64 >/dev/null; } || need+=(wine64)
  if [ ${#need[@]} -gt 0 ]; then
    { timeout 300 $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive timeout 900 $SUDO apt-get install -y -qq \
        --no-install-recommends "${need[@]}"; } >/dev/null 2>&1 \
      || echo "setup: could not install ${need[*]}; those platforms are left out or not tested" >&2
  fi
fi
bash scripts/build_fmu.sh >/dev/null
