"""Helpers of the analysis tests: rigs, hidden-effect truths and
synthetic measurements made with the C core plus realistic sensor imperfections
(1 % noise on torque and load, encoder-like quantized speeds, a torque-sensor
offset; gearsim.analysis.synthetic)."""

from __future__ import annotations

import os
import sys
from functools import cache

import pytest

import gearsim
from gearsim.analysis import synthetic as S

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
EXAMPLES = os.path.join(REPO, "examples")

#: The effect names of the measurement format (docs/measurement-format.md
#: section 3), written out here as the tests' own copy of the contract: the
#: blocks' own effects, then the rig effects (physics.md 11). RESERVED_EFFECTS
#: lists names the contract reserves for later (none today).
CONTRACT_EFFECTS = (
    "meshing_efficiency",
    "load_dependent_efficiency",
    "temperature_dependent_efficiency",
    "viscous_friction",
    "backlash",
    "coulomb_friction",
    "load_offset",
    "sensor_delay",
    "stribeck_friction",
    "compliance",
    "torque_ripple",
)
RESERVED_EFFECTS: tuple[str, ...] = ()

SAMPLES = 10_000
DT = 1e-3

RIGS = {
    # block, block params, rig params, excitation peak speed (rad/s) and load (N*m / N)
    "simple_gear": (
        {"teeth_ratio": 3.0, "base_radius": 0.05},
        {"follower_inertia": 0.05},
        30.0,
        3.0,
    ),
    "rack_pinion": ({"pinion_radius": 0.05}, {"rack_mass": 5.0}, 20.0, 50.0),
}

#: hidden effect -> (block params, rig params) of the truth, per rig
TRUTHS = {
    "simple_gear": {
        "meshing_efficiency": (
            {"friction_model": "constant_efficiency", "efficiency_const": 0.75},
            {},
        ),
        "load_dependent_efficiency": (
            {
                "friction_model": "load_dependent_efficiency",
                "idle_torque": 0.3,
                "nominal_output_torque": 3.0,
                "efficiency_nominal": 0.7,
            },
            {},
        ),
        "temperature_dependent_efficiency": (
            {
                "friction_model": "temperature_dependent_efficiency",
                "temperature_vector": [290.0, 310.0, 330.0],
                "efficiency_vector": [0.95, 0.8, 0.6],
            },
            {},
        ),
        "viscous_friction": ({"viscous_coefficients": [0.0, 0.15]}, {}),
        "backlash": (
            {"backlash_enabled": True, "linear_backlash": 1e-3, "stiffness": 1e5, "damping": 2e3},
            {},
        ),
        "coulomb_friction": ({}, {"load_coulomb_friction": 1.5}),
        "load_offset": ({}, {"load_offset": 1.5}),
    },
    "rack_pinion": {
        "meshing_efficiency": (
            {"friction_model": "constant_efficiency", "efficiency_const": 0.75},
            {},
        ),
        "temperature_dependent_efficiency": (
            {
                "friction_model": "temperature_dependent_efficiency",
                "temperature_vector": [290.0, 310.0, 330.0],
                "efficiency_vector": [0.95, 0.8, 0.6],
            },
            {},
        ),
        "viscous_friction": ({"rack_viscous_coefficient": 40.0}, {}),
        "backlash": (
            {"backlash_enabled": True, "linear_backlash": 1e-3, "stiffness": 1e5, "damping": 2e3},
            {},
        ),
        "coulomb_friction": ({}, {"load_coulomb_friction": 30.0}),
        "load_offset": ({}, {"load_offset": 30.0}),
    },
}


#: Sensor imperfections per case (default: gearsim.analysis.synthetic.SensorModel(),
#: 1 % noise on torque and load, 0.2 % noise and 0.2 % quantization on speeds,
#: 0.5 % torque offset). The gear's backlash impacts are timed by the integral
#: of the measured base speed, so even the true model only halves the error at
#: 0.2 % speed noise; that case uses a good encoder (0.05 % noise, 0.1 % steps).
SENSORS = {
    ("simple_gear", ("backlash",)): S.SensorModel(speed_noise=0.0005, speed_resolution=0.001),
}


def base_model(block: str) -> gearsim.Model:
    bp, rp, _, _ = RIGS[block]
    return gearsim.Model(block, bp, rp)


def truth_model(block: str, effects: tuple[str, ...]) -> gearsim.Model:
    m = base_model(block)
    for e in effects:
        b, r = TRUTHS[block][e]
        m = m.replace(block_params=b, rig_params=r)
    return m


@cache
def measurement(block: str, effects: tuple[str, ...], seed: int = 3, samples: int = SAMPLES):
    """A synthetic measurement of the truth with `effects` (cached per session)."""
    _, _, speed, load = RIGS[block]
    exc = S.excitation(samples, DT, max_speed=speed, max_load=load, seed=seed)
    sensors = SENSORS.get((block, effects), S.SensorModel())
    return S.synthesize(
        truth_model(block, effects),
        exc,
        sensors,
        seed=seed + 2,
        path=f"<{block}:{'+'.join(effects)}>",
    )


def emps_or_skip() -> str:
    """The EMPS data's path (examples/emps_adapter.py says where it is looked
    for), or skip with the reason."""
    if EXAMPLES not in sys.path:
        sys.path.insert(0, EXAMPLES)
    import emps_adapter

    path = emps_adapter.default_data_path()
    if not os.path.exists(path):
        pytest.skip(
            f"EMPS data not found at {path} (not part of the repository; README, Real data)"
        )
    return path
