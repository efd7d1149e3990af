"""Fixtures of the fleet tests (helpers in fleet_helpers.py).

The 200-unit line is generated once per session (the independent generator,
two processes, about 25 s on an idle two-core machine) and analysed once on a
local Dask cluster; the tests read that run's outputs.
"""

from __future__ import annotations

import pytest

pytest.importorskip("gearsim")
pytest.importorskip("scipy")
pytest.importorskip("matplotlib")
pytest.importorskip("dask")
pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

import fleet_helpers as H  # noqa: E402

LINE_UNITS = 200


@pytest.fixture(scope="session")
def line(tmp_path_factory):
    """(specs, manifest, model file) of the 200-unit line."""
    root = tmp_path_factory.mktemp("line")
    specs = H.unit_specs(LINE_UNITS, H.defect_map(LINE_UNITS))
    manifest = H.write_fleet(root / "logs", specs)
    model = root / "start.toml"
    H.start_model().save(model)
    return specs, manifest, model


@pytest.fixture(scope="session")
def line_run(line, tmp_path_factory):
    """The line analysed on a local cluster of two workers (gearsim.fleet)."""
    from gearsim.fleet import FleetOptions, run_fleet

    specs, manifest, model = line
    out = tmp_path_factory.mktemp("line-out")
    res = run_fleet(
        manifest=str(manifest),
        model=str(model),
        out=str(out),
        options=FleetOptions(effects=H.EFFECTS),
        workers=2,
        quiet=True,
    )
    return res
