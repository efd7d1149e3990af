"""The walkthrough (the README's main command) on the bundled demo data finds
the hidden effects and writes the report; the bundled data matches its
generator."""

from __future__ import annotations

import os
import subprocess
import sys

from analysis_helpers import REPO


def test_walkthrough_demo(tmp_path):
    out = tmp_path / "report"
    p = subprocess.run(
        [
            sys.executable,
            os.path.join(REPO, "examples", "walkthrough.py"),
            "--out",
            str(out),
            "--no-emps",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 0, p.stderr
    # the hidden viscous friction and efficiency, then the torque-sensor offset
    # (which a model can only hold as a load offset), then the stop line
    found = "effects found, in order: viscous_friction, meshing_efficiency, load_offset"
    assert found in p.stdout
    assert "nothing left that helps" in p.stdout
    html = (out / "report.html").read_text()
    assert "data:image/png;base64," in html and "error fall" in html
    assert (out / "error_fall.png").exists()


def test_demo_starting_model_fails_a_regime():
    # the starting model lacks a strong viscous friction: its error in the
    # high-speed regime is above the failing threshold (ratio to the overall
    # rms residual, computed here from the residual itself)
    sys.path.insert(0, os.path.join(REPO, "examples"))
    import make_demo_data
    import numpy as np

    from gearsim import Model
    from gearsim.analysis import compare, load_measurement
    from gearsim.analysis.regimes import FAILING_RATIO

    model = Model.load(make_demo_data.START)
    meas = load_measurement(make_demo_data.CSV, "simple_gear")
    c = compare(model, meas)
    r = meas["base_torque"] - c.sim.outputs["base_torque"]
    high = {reg.name: reg.mask for reg in c.regime_masks}["high_speed"]
    ratio = np.sqrt(np.mean(r[high] ** 2)) / np.sqrt(np.mean(r**2))
    assert ratio >= FAILING_RATIO
    assert "high_speed" in [x["regime"] for x in c.failing_regimes]


def test_demo_data_matches_generator():
    sys.path.insert(0, os.path.join(REPO, "examples"))
    import make_demo_data

    from gearsim.analysis import load_measurement

    meas, _ = make_demo_data.make()
    disk = load_measurement(make_demo_data.CSV, "simple_gear")
    for col in ("base_speed", "load_torque", "base_torque", "follower_speed", "temperature"):
        scale = max(abs(meas[col]).max(), 1.0)
        assert abs(disk[col] - meas[col]).max() <= 1e-5 * scale, col
