"""The hidden effect is found, fitting it halves the error, its parameters land
near the truth: every effect of the contract table on both rigs, from
measurements synthesized with the C core plus sensor imperfections."""

from __future__ import annotations

import numpy as np
import pytest
from analysis_helpers import TRUTHS, base_model, measurement, truth_model

from gearsim.analysis import diagnose, fit
from gearsim.analysis import modelkit as mk

CASES = [(block, effect) for block in ("simple_gear", "rack_pinion") for effect in TRUTHS[block]]


def _eta_curve(values: dict, temps: np.ndarray) -> np.ndarray:
    return np.interp(temps, values["temperature_vector"], values["efficiency_vector"])


def _load_dependent_eta(values: dict, load: np.ndarray) -> np.ndarray:
    """Efficiency at follower torque `load` of the load-dependent model (eq. 2.4, 2.5)."""
    g = values["teeth_ratio"]
    idle = values["idle_torque"]
    k = 1.0 / values["efficiency_nominal"] - 1.0 - g * idle / values["nominal_output_torque"]
    return load / (g * idle + (k + 1.0) * load)


def check_parameters(block: str, effect: str, fitted_model, truth) -> None:
    fb, fr = mk.block_values(fitted_model), mk.rig_values(fitted_model)
    tb, tr = mk.block_values(truth), mk.rig_values(truth)
    if effect == "coulomb_friction":
        assert fr["load_coulomb_friction"] == pytest.approx(tr["load_coulomb_friction"], rel=0.1)
    elif effect == "load_offset":
        assert fr["load_offset"] == pytest.approx(tr["load_offset"], rel=0.1)
    elif effect == "viscous_friction":
        assert mk.viscous_value(fitted_model) == pytest.approx(mk.viscous_value(truth), rel=0.1)
    elif effect == "meshing_efficiency":
        assert fb["efficiency_const"] == pytest.approx(tb["efficiency_const"], abs=0.03)
    elif effect == "load_dependent_efficiency":
        loads = np.array([0.5, 1.0, 2.0, 3.0])
        np.testing.assert_allclose(
            _load_dependent_eta(fb, loads), _load_dependent_eta(tb, loads), atol=0.04
        )
    elif effect == "temperature_dependent_efficiency":
        temps = np.array([295.0, 310.0, 325.0])
        np.testing.assert_allclose(_eta_curve(fb, temps), _eta_curve(tb, temps), atol=0.04)
    elif effect == "backlash":
        assert fb["linear_backlash"] == pytest.approx(tb["linear_backlash"], rel=0.2)
    # inertia is co-estimated every time and must stay right
    key = mk.driven_inertia_key(truth)
    assert fr[key] == pytest.approx(tr[key], rel=0.1)


@pytest.mark.parametrize("block,effect", CASES, ids=[f"{b}-{e}" for b, e in CASES])
def test_hidden_effect_found_and_fitted(block: str, effect: str) -> None:
    meas = measurement(block, (effect,))
    start = base_model(block)
    d = diagnose(start, meas)
    ranking = [c.effect for c in d.candidates]
    assert ranking[0] == effect, f"ranking {ranking}"
    best = d.candidates[0]
    assert best.evidence.get("text")
    r = fit(start, meas, effect)
    assert r.nrmse_after <= 0.5 * r.nrmse_before, (r.nrmse_before, r.nrmse_after)
    assert r.nrmse_before == pytest.approx(d.baseline_nrmse, rel=1e-9)
    check_parameters(block, effect, r.model, truth_model(block, (effect,)))


@pytest.mark.parametrize(
    "block,effects",
    [
        ("simple_gear", ("meshing_efficiency", "load_offset")),
        ("rack_pinion", ("coulomb_friction", "viscous_friction")),
    ],
    ids=["gear-efficiency+offset", "rack-coulomb+viscous"],
)
def test_two_effects_found_in_two_rounds(block: str, effects: tuple[str, ...]) -> None:
    meas = measurement(block, effects)
    model = base_model(block)
    found = []
    nrmse = [None]
    for _ in range(2):
        d = diagnose(model, meas)
        if nrmse[0] is None:
            nrmse[0] = d.baseline_nrmse
        best = d.candidates[0].effect
        found.append(best)
        r = fit(model, meas, best)
        model = r.model
        nrmse.append(r.nrmse_after)
    assert sorted(found) == sorted(effects), found
    assert nrmse[2] < nrmse[1] < nrmse[0]
    assert nrmse[2] <= 0.5 * nrmse[0]
    for e in effects:
        check_parameters(block, e, model, truth_model(block, effects))
