"""The bundled fleet of scripts/fleet_demo.sh: the files are what
examples/make_fleet_data.py writes, and the README's account of the run
holds (three planted faults found by their parameters, the Coulomb
friction's drift, the truncated log an error row)."""

from __future__ import annotations

import filecmp
import subprocess
import sys

import fleet_helpers as H

from gearsim.fleet import FleetOptions, run_fleet

DATA = H.REPO / "examples" / "data"


def test_bundled_fleet_is_what_the_script_writes(tmp_path):
    out = subprocess.run(
        [sys.executable, str(H.REPO / "examples" / "make_fleet_data.py"), "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    names = sorted(p.name for p in (DATA / "fleet").iterdir())
    assert names == sorted(p.name for p in (tmp_path / "fleet").iterdir())
    match, mismatch, errors = filecmp.cmpfiles(
        DATA / "fleet", tmp_path / "fleet", names, shallow=False
    )
    assert mismatch == [] and errors == []
    assert filecmp.cmp(DATA / "fleet_start.toml", tmp_path / "fleet_start.toml", shallow=False)
    size = sum(p.stat().st_size for p in (DATA / "fleet").iterdir())
    assert size < 3e6


def test_demo_run_finds_the_planted_faults(tmp_path):
    res = run_fleet(
        manifest=str(DATA / "fleet" / "manifest.csv"),
        model=str(DATA / "fleet_start.toml"),
        out=str(tmp_path / "out"),
        options=FleetOptions(effects=("coulomb_friction", "meshing_efficiency", "load_offset")),
        workers=2,
        quiet=True,
        report=False,
    )
    assert res.counts["units"] == 40 and res.counts["ok"] == 39
    assert [u for u, _ in res.errors] == ["gbx-33"] and "gzip" in res.errors[0][1]
    by = {o["unit"]: o["by"] for o in res.outliers}
    assert by["gbx-07"] == "load_coulomb_friction"
    assert by["gbx-19"] == "efficiency_const"
    assert by["gbx-28"] == "load_offset"
    assert set(by) - {"gbx-07", "gbx-19", "gbx-28"} <= {"gbx-34"}  # the README's borderline unit
    assert res.population["drift"]["load_coulomb_friction"]["drifting"]
