"""An independent generator of test measurements, written in numpy from the
physics of docs/physics.md: a compliant mesh (a dead zone in a spring when
there is backlash), a drive that follows a commanded speed through its own
speed loop, its own RK4 integrator at a quarter of the sample period, and
real sensors (encoder speeds from whole position counts, torque noise and
offset, load noise). Beyond the blocks' losses it knows a delayed torque channel,
a Stribeck hump on the driven side, a compliant shaft between the motor and
the base gear, and a torque ripple of the base gear's angle
(RIG_EFFECT_TRUTHS). It never calls gearsim's C core or its Rig, so tests
that fit gearsim to these records stop fitting data made by the model itself.
See docs/testing-python.md.
"""

from .generator import (
    DT,
    PEAKS,
    RIG_EFFECT_TRUTHS,
    RIGS,
    TRUTHS,
    Record,
    gearsim_model,
    generate,
    mechanism,
)
from .plant import Losses, Mechanism, TrueRun, simulate_true

__all__ = [
    "RIG_EFFECT_TRUTHS",
    "DT",
    "PEAKS",
    "RIGS",
    "TRUTHS",
    "Record",
    "generate",
    "gearsim_model",
    "mechanism",
    "Losses",
    "Mechanism",
    "TrueRun",
    "simulate_true",
]
