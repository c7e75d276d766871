"""The binaries each FMU carries for other platforms, run here under emulation
(issue #23): the x86-64 Windows DLL under wine and the aarch64 Linux library
under qemu-user, each driven by the same small C harness
(tests/c/platform_harness.c: both ABIs, a record, 200 steps, a state rollback,
FMI 3.0 early returns), whose printed numbers must equal those of the x86-64
Linux library digit for digit (%.17g).

Where a cross compiler or an emulator is missing (scripts/setup.sh installs
them where it can) the test is skipped with the reason (pytest -rs shows it),
never passed silently."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
import sll  # noqa: E402

HARNESS = ROOT / "tests" / "c" / "platform_harness.c"
SHIM = ROOT / "tests" / "c" / "bcryptprimitives_shim.c"
RECORD = ROOT / "resources" / "default_record.csv"
FMI3 = ROOT / "target" / "fmu" / "fmi3" / "StackedLiveLoad.fmu"
# (FMI 2.0 folder, FMI 3.0 folder) of each platform.
FOLDERS = {"linux": ("linux64", "x86_64-linux"), "windows": ("win64", "x86_64-windows"),
           "arm": ("aarch64-linux", "aarch64-linux")}


def guid() -> str:
    text = (ROOT / "src" / "fmi" / "c_api" / "mod.rs").read_text()
    return re.search(r'GUID: &str = "(\{[0-9a-f-]+\})"', text).group(1)


@pytest.fixture(scope="module")
def fmus() -> dict[int, Path]:
    fmi2 = sll.build_fmu()  # builds both, with the cross builds it can
    return {2: fmi2, 3: FMI3}


def extract(fmu: Path, folder: str, tmp: Path) -> Path | None:
    with zipfile.ZipFile(fmu) as z:
        names = [n for n in z.namelist() if n.startswith(f"binaries/{folder}/")]
        assert not any("bcryptprimitives" in n.lower() for n in z.namelist()), \
            "the FMU must never ship a shim"
        if not names:
            return None
        z.extract(names[0], tmp)
        return tmp / names[0]


def cc(compiler: str, out: Path, *args: str) -> None:
    subprocess.run([compiler, "-std=gnu11", "-Wall", "-Werror", "-I", str(ROOT / "include"),
                    str(HARNESS), *args, "-o", str(out)], check=True)


def run(cmd: list[str], env: dict | None = None) -> str:
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=600, env=env)
    assert out.returncode == 0, f"{cmd}: exit {out.returncode}\n{out.stdout}\n{out.stderr}"
    return out.stdout.replace("\r\n", "\n")


@pytest.fixture(scope="module")
def native(tmp_path_factory) -> str:
    tmp = tmp_path_factory.mktemp("native")
    cc("cc", tmp / "harness", "-ldl")
    return run([str(tmp / "harness"), str(ROOT / "target" / "release" / "libstacked_live_load.so"),
                guid(), str(RECORD)])


def check_same(name: str, got: str, native: str) -> None:
    assert "fmi2 rollback bit-identical" in got
    n_early = int(re.search(r"early returns (\d+)", got).group(1))
    assert n_early >= 1, "the harness's scene switches"
    assert got == native, f"{name} differs from x86-64 Linux:\n{got}\n---\n{native}"
    print(f"{name}: {len(got.splitlines())} lines identical to x86-64 Linux, {n_early} early returns")


def test_native_library_in_both_fmus_is_the_built_one(fmus, native):
    for version, fmu in fmus.items():
        with zipfile.ZipFile(fmu) as z:
            lib = z.read(f"binaries/{FOLDERS['linux'][version - 2]}/StackedLiveLoad.so")
        assert lib == (ROOT / "target" / "release" / "libstacked_live_load.so").read_bytes()
    assert "fmi2 rollback bit-identical" in native


@pytest.mark.parametrize("version", [2, 3])
def test_windows_dll_under_wine(fmus, native, version, tmp_path):
    wine = shutil.which("wine64") or shutil.which("wine") or (
        "/usr/lib/wine/wine64" if Path("/usr/lib/wine/wine64").exists() else None)
    mingw = shutil.which("x86_64-w64-mingw32-gcc")
    if not (wine and mingw):
        pytest.skip("wine64 or x86_64-w64-mingw32-gcc not installed (scripts/setup.sh installs "
                    "Debian's wine64 and gcc-mingw-w64-x86-64 where apt works)")
    dll = extract(fmus[version], FOLDERS["windows"][version - 2], tmp_path)
    if dll is None:
        pytest.skip("the FMU carries no Windows DLL: the cross build was left out "
                    "(rustup target x86_64-pc-windows-gnu and mingw needed, see scripts/setup.sh)")
    # Wine 8.0 lacks bcryptprimitives.dll (Rust's std imports ProcessPrng from
    # it): a test-only shim beside the harness, never in the FMU.
    cc(mingw, tmp_path / "harness.exe")
    subprocess.run([mingw, "-shared", "-O2", "-o", str(tmp_path / "bcryptprimitives.dll"),
                    str(SHIM), "-ladvapi32"], check=True)
    shutil.copy(RECORD, tmp_path / "record.csv")
    shutil.copy(RECORD, tmp_path / "default_record.csv")
    win = lambda p: "Z:" + str(p).replace("/", "\\")  # noqa: E731  (wine maps / to Z:)
    env = dict(os.environ, WINEPREFIX=str(tmp_path / "prefix"), WINEDEBUG="-all")
    # FMI 3.0 reads the record relative to resourcePath (a native Windows
    # path); FMI 2.0 by its absolute path (its resource URI's Windows forms
    # are issue #24's parser).
    resources = win(tmp_path) + "\\"
    got = run([wine, str(tmp_path / "harness.exe"), win(dll), guid(), win(tmp_path / "record.csv"),
               resources], env=env)
    check_same(f"FMI {version}.0 Windows DLL under wine", got, native)


@pytest.mark.parametrize("version", [2, 3])
def test_aarch64_library_under_qemu(fmus, native, version, tmp_path):
    qemu = shutil.which("qemu-aarch64") or shutil.which("qemu-aarch64-static")
    gcc = shutil.which("aarch64-linux-gnu-gcc")
    sysroot = Path("/usr/aarch64-linux-gnu")
    if not (qemu and gcc and sysroot.exists()):
        pytest.skip("qemu-aarch64 or aarch64-linux-gnu-gcc not installed (scripts/setup.sh "
                    "installs Debian's qemu-user and gcc-aarch64-linux-gnu where apt works)")
    lib = extract(fmus[version], FOLDERS["arm"][version - 2], tmp_path)
    if lib is None:
        pytest.skip("the FMU carries no aarch64 library: the cross build was left out "
                    "(rustup target aarch64-unknown-linux-gnu and gcc-aarch64-linux-gnu needed)")
    cc(gcc, tmp_path / "harness", "-ldl")
    got = run([qemu, "-L", str(sysroot), str(tmp_path / "harness"), str(lib), guid(), str(RECORD)])
    check_same(f"FMI {version}.0 aarch64 library under qemu", got, native)


# StackOnFloor: the same library under the model's name, in both FMUs.
FLOOR_FMUS = {2: ROOT / "target" / "fmu" / "StackOnFloor.fmu",
              3: ROOT / "target" / "fmu" / "fmi3" / "StackOnFloor.fmu"}
RUN_FLOOR = ROOT / "tests" / "c" / "run_floor.c"


def floor_guid() -> str:
    text = (ROOT / "src" / "fmi" / "c_api" / "mod.rs").read_text()
    return re.search(r'FLOOR_GUID: &str = "(\{[0-9a-f-]+\})"', text).group(1)


def test_stack_on_floor_fmus_carry_the_same_binaries(fmus):
    for version, fmu in fmus.items():
        def binaries(path: Path) -> dict[str, bytes]:
            with zipfile.ZipFile(path) as z:
                return {n: z.read(n) for n in z.namelist()
                        if n.startswith("binaries/") and not n.endswith("/")}
        storey = binaries(fmu)
        expected = {n.replace("/StackedLiveLoad.", "/StackOnFloor."): b for n, b in storey.items()}
        assert binaries(FLOOR_FMUS[version]) == expected


def test_stack_on_floor_under_qemu(fmus, tmp_path):
    """tests/c/run_floor.c (StackOnFloor through the FMI 2.0 ABI, %.17g per
    step) on the aarch64 library of StackOnFloor.fmu prints what it prints on
    x86-64 Linux, digit for digit."""
    qemu = shutil.which("qemu-aarch64") or shutil.which("qemu-aarch64-static")
    gcc = shutil.which("aarch64-linux-gnu-gcc")
    sysroot = Path("/usr/aarch64-linux-gnu")
    if not (qemu and gcc and sysroot.exists()):
        pytest.skip("qemu-aarch64 or aarch64-linux-gnu-gcc not installed (scripts/setup.sh)")
    lib = extract(FLOOR_FMUS[2], FOLDERS["arm"][0], tmp_path)
    if lib is None:
        pytest.skip("the FMU carries no aarch64 library: the cross build was left out")

    def build(compiler: str, out: Path) -> None:
        subprocess.run([compiler, "-std=gnu11", "-Wall", "-Werror", "-I", str(ROOT / "include"),
                        str(RUN_FLOOR), "-ldl", "-o", str(out)], check=True)

    build("cc", tmp_path / "native")
    native = run([str(tmp_path / "native"),
                  str(ROOT / "target" / "release" / "libstacked_live_load.so"), floor_guid()])
    build(gcc, tmp_path / "arm")
    got = run([qemu, "-L", str(sysroot), str(tmp_path / "arm"), str(lib), floor_guid()])
    assert len(native.splitlines()) == 300
    assert got == native
