"""The plain-Python full Simple Gear rig of the benchmark (bench/alternatives.py,
python_loop_full) solves the same equations as gearsim: its base torque and
follower speed agree with Rig.run to 1e-9 of their peaks, so the speed ratio
that bench/python_bench.py reports compares like with like."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

import gearsim

BENCH = Path(__file__).resolve().parents[2] / "bench"
TOLERANCE = 1e-9  # max abs difference / peak (docs/performance.md, Alternatives)


@pytest.fixture(scope="module")
def alt():
    """bench/alternatives.py, loaded from its path (bench/ is not a package)."""
    spec = importlib.util.spec_from_file_location(
        "gearsim_bench_alternatives", BENCH / "alternatives.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _gearsim_rig(alt, p):
    block, rig = alt.full_gearsim_params(p)
    model = gearsim.Model(block="simple_gear", block_params=block, rig_params=rig)
    return model.rig(dt=p["dt"])


def test_full_params_are_sg_full(alt):
    """FULL_PARAMS is the C benchmark configuration sg_full (bench/bench_common.h):
    the defaults with its overrides, nothing else."""
    block, rig = alt.full_gearsim_params()
    model = gearsim.Model(block="simple_gear", block_params=block, rig_params=rig)
    assert model.resolved_block_params == {
        **gearsim.SimpleGear().params,
        "friction_model": "temperature_load_dependent_efficiency",
        "initial_temperature": 295.0,
        "viscous_coefficients": [0.002, 0.004],
        "backlash_enabled": True,
        "hard_stop_model": "smooth",
    }
    assert model.resolved_rig_params == {
        **gearsim.Rig.defaults("simple_gear"),
        "thermal_resistance": 2.0,
        "load_coulomb_friction": 0.05,
    }


@pytest.mark.parametrize("variant", ["sg_full", "hot"])
def test_python_full_rig_matches_gearsim(alt, variant):
    p = dict(alt.FULL_PARAMS)
    if variant == "hot":
        # a small thermal mass and a table whose breakpoints the run crosses
        p.update(
            temperature_vector=[280.0, 296.0, 320.0], load_vector=[0.0, 1.0, 3.0], thermal_mass=0.5
        )
    # the benchmark's tones, 4 s of them in 500 steps: the base reverses and the
    # load changes sign, so the teeth cross the gap both ways
    w, load = alt.scenario(500, dt=8e-3)
    rig = _gearsim_rig(alt, p)
    ref = rig.run(base_speed=w, load=load)
    py = alt.python_loop_full(w, load, p)

    assert py["substeps"] == rig.substeps == 2
    for name in ("base_torque", "driven_speed"):
        peak = np.max(np.abs(ref[name]))
        diff = np.max(np.abs(np.asarray(py[name]) - ref[name]))
        assert diff <= TOLERANCE * peak, f"{name}: max |diff| {diff:.3e} of peak {peak:.3e}"
    np.testing.assert_allclose(py["temperature"], ref.temperature, rtol=0, atol=1e-9)
    np.testing.assert_allclose(py["backlash_position"], ref.backlash_position, rtol=0, atol=1e-12)

    # the comparison covers contact on both sides and free play in between
    x = ref.backlash_position
    half_gap = 0.5 * p["linear_backlash"]
    assert (x > half_gap).any() and (x < -half_gap).any() and (np.abs(x) < half_gap).any()
    if variant == "hot":
        assert ref.temperature.max() > 296.0  # crossed a temperature breakpoint
