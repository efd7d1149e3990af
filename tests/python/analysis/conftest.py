"""Fixtures of the analysis tests (helpers in analysis_helpers.py)."""

from __future__ import annotations

import pytest

pytest.importorskip("gearsim")
pytest.importorskip("scipy")

from analysis_helpers import base_model, measurement  # noqa: E402


@pytest.fixture
def gear_csv(tmp_path):
    """A small gear measurement CSV and its starting model file (for CLI tests)."""
    from gearsim.analysis import write_measurement

    meas = measurement("simple_gear", ("coulomb_friction",), samples=4000)
    csv = tmp_path / "gear.csv"
    write_measurement(csv, meas)
    model = tmp_path / "model.toml"
    base_model("simple_gear").save(model)
    return csv, model
