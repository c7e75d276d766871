"""scripts/speed_on_records.py (issue #21: the default's speed on records it
was never tuned on): it runs `examples/ratio` and reads its lines, so the two
must agree on the format. One record, two scenes, one round: the rows carry
what the example printed (a bare structure never switches; the paper's two
blocks on Loma Prieta do), and the CSV and the chart are written."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
import speed_on_records  # noqa: E402

RECORD = "RSN787_LOMAP_SLC270"


def test_a_line_of_the_example_parses():
    line = "shipped  n2           79.3 us / floor     11.8 us = 6.73x, 68 switches, 4001 samples\n"
    row = speed_on_records.parse(line)
    assert row == {"record": "shipped", "scene": "n2", "engine_us": 79.3, "floor_us": 11.8,
                   "ratio": 6.73, "switches": 68, "samples": 4001}


@pytest.mark.skipif(not (speed_on_records.RECORDS / f"{RECORD}.AT2").exists(),
                    reason="needs ../shared/ground_motions")
def test_one_record_two_scenes(tmp_path):
    subprocess.run([sys.executable, str(ROOT / "scripts" / "speed_on_records.py"), "--out",
                    str(tmp_path), "--rounds", "1", "--scenes", "n0", "n2", "--records", RECORD],
                   check=True, cwd=ROOT, timeout=900)
    rows = list(csv.DictReader(open(tmp_path / "speed_on_records.csv")))
    assert [(r["record"], r["scene"]) for r in rows] == [(RECORD, "n0"), (RECORD, "n2")]
    # The first 20 s at 0.005 s; the bare structure has no contact to switch.
    assert all(int(r["samples"]) == 4001 for r in rows)
    assert int(rows[0]["switches"]) == 0 and int(rows[1]["switches"]) > 0
    assert all(float(r["ratio"]) > 0 and float(r["floor_us"]) > 0 for r in rows)
    assert (tmp_path / "speed_on_records.png").stat().st_size > 10_000
