"""The acceptance checks shared by test_acceptance.py (the contract's effects)
and test_acceptance_rig_effects.py (the rig effects of physics.md 11), on
records of the independent generator (tests/python/analysis/independent)."""

from __future__ import annotations

from typing import Any

from gearsim.analysis import diagnose, fit

#: the validation error must fall to within this factor of the record's own
#: noise floor (the nrmse of the noise-free truth against the measurement)
FLOOR_FACTOR = 1.5


def noise_floor(record: Any) -> float:
    return record.noise_floor()["overall"]


def ranked_first_and_fitted_to_the_floor(start: Any, record: Any, effect: str) -> Any:
    """diagnose ranks `effect` first on the record; fit with it lowers the
    validation error to within FLOOR_FACTOR of the noise floor. The fit."""
    ranking = [c.effect for c in diagnose(start, record.measurement).candidates]
    assert ranking[0] == effect, f"ranking {ranking}"
    result = fit(start, record.measurement, effect)
    floor = noise_floor(record)
    assert result.validation_nrmse_after < result.validation_nrmse_before
    assert result.validation_nrmse_after <= FLOOR_FACTOR * floor, (
        f"validation nrmse {result.validation_nrmse_after:.4f} is "
        f"{result.validation_nrmse_after / floor:.2f}x the noise floor {floor:.4f}"
    )
    return result
