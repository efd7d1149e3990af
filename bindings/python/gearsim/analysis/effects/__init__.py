"""The effects of docs/measurement-format.md section 3, one module each
(the class and its evidence code side by side), behind one contract
(:class:`Effect`, base.py) and one registry (:data:`EFFECTS`, registry.py).

diagnose, fitting and report never test an effect's name: everything they
know about an effect they ask its class. Adding an effect means writing one
module with one subclass of Effect and registering it in registry.py; the
check_effect suite (tests/python/analysis/test_check_effect.py) then checks
it like every other.

The driven inertia is re-estimated with every new effect (an inertia error
shares the acceleration column with every torque-like effect):
:data:`INERTIA`.
"""

from __future__ import annotations

from .base import (
    INERTIA,
    Changes,
    Column,
    DrivenInertia,
    Effect,
    FitParam,
    Screening,
    present_mesh_loss,
)
from .registry import (
    EFFECT_NAMES,
    EFFECTS,
    applicable_effects,
    apply_changes,
    build_changes,
    coestimated,
    get_effect,
    nuisance_columns,
    present_effects,
    separating_excitation,
    three_changes,
)

__all__ = [
    "EFFECTS",
    "EFFECT_NAMES",
    "FitParam",
    "Effect",
    "Screening",
    "Changes",
    "Column",
    "DrivenInertia",
    "INERTIA",
    "get_effect",
    "applicable_effects",
    "present_effects",
    "coestimated",
    "nuisance_columns",
    "build_changes",
    "apply_changes",
    "three_changes",
    "separating_excitation",
    "present_mesh_loss",
]
