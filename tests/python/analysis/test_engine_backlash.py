"""Backlash multi-start: a fit started from a short gap can stop in a local
minimum; starting from several gaps over the evidence's range and keeping the
best does not."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from analysis_helpers import TRUTHS, base_model, measurement

from gearsim.analysis import compare, prepare_inputs
from gearsim.analysis import fitting as F
from gearsim.analysis.effects import EFFECTS, FitParam
from gearsim.analysis.signatures import build_context


def _bump(x: float, centre: float, width: float) -> float:
    return float(np.exp(-(((x - centre) / width) ** 2)))


class TwoWells:
    """cost(x) = 2 - 0.5 bump(x, 0.35) - 1.0 bump(x, 1.0): a shallow local
    minimum at 0.35 (cost 1.5) and the global one at 1.0 (cost 1.0)."""

    def __init__(self, starts=()):
        self.params = [FitParam("gap", 0.3, 0.01, 5.0, starts=starts, diff_step=1e-4)]

    def residuals(self, x):
        c = 2.0 - 0.5 * _bump(x[0], 0.35, 0.05) - 1.0 * _bump(x[0], 1.0, 0.1)
        return np.array([np.sqrt(c)])


def test_single_start_from_a_short_gap_stays_in_the_local_minimum():
    single = F._multi_start(TwoWells(), np.array([0.3]), 200)
    assert single.x[0] == pytest.approx(0.35, abs=0.01)
    many = F._multi_start(TwoWells(starts=(0.2, 0.5, 0.9, 1.6)), np.array([0.3]), 200)
    assert many.x[0] == pytest.approx(1.0, abs=0.01)
    assert 2 * many.cost == pytest.approx(1.0, abs=1e-3)


def test_start_gaps_span_the_evidence():
    class Evidence:
        gap_range = (0.8e-3, 1.6e-3)

    starts = EFFECTS["backlash"].start_gaps(Evidence())
    # geometric steps from half the smallest to twice the largest gap seen
    assert starts[0] == pytest.approx(0.4e-3) and starts[-1] == pytest.approx(3.2e-3)
    ratios = np.diff(np.log(starts))
    assert np.allclose(ratios, ratios[0])


def test_backlash_next_to_viscous_from_a_short_gap():
    # truth: gap 1 mm next to viscous friction; the model already has the
    # viscous friction; the screening's gap estimate is replaced by 0.2 mm
    meas = measurement("rack_pinion", ("backlash", "viscous_friction"))
    start = base_model("rack_pinion").replace(
        block_params=TRUTHS["rack_pinion"]["viscous_friction"][0]
    )
    inputs = prepare_inputs(meas)
    c = compare(start, meas, inputs)
    ctx = build_context(start, meas, inputs, c.sim, c.regime_masks)
    screening = EFFECTS["backlash"].screen(ctx)
    short = dataclasses.replace(
        screening, evidence=dataclasses.replace(screening.evidence, gap_estimate=0.2e-3)
    )
    r = F.fit_effect(ctx, "backlash", screen_result=short)
    assert r.parameters["linear_backlash"] == pytest.approx(1e-3, rel=0.1)
    assert r.validation_nrmse_after < 0.5 * r.validation_nrmse_before
