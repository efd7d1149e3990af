"""diagnose and report judge by one rule: an effect that lowers the
validation error by 8 % (the report used to need 10 %, diagnose 0.5 %) is
offered by diagnose and accepted by the report; with nothing missing, both
end on "nothing left that helps"."""

from __future__ import annotations

import pytest
from analysis_helpers import DT, base_model

from gearsim.analysis import diagnose, scoring
from gearsim.analysis import synthetic as S
from gearsim.analysis.diagnose import NOTHING_HELPS
from gearsim.analysis.report import run_rounds


def _gear_measurement(rig_params: dict):
    truth = base_model("simple_gear").replace(rig_params=rig_params)
    exc = S.excitation(4000, DT, max_speed=30.0, max_load=3.0, seed=5)
    # no torque-sensor offset: it would look like a load offset itself
    return S.synthesize(truth, exc, S.SensorModel(torque_offset=0.0), seed=6, path="<rules>")


def test_a_small_gain_is_judged_alike():
    meas = _gear_measurement({"load_offset": 0.05})
    start = base_model("simple_gear")
    d = diagnose(start, meas)
    best = d.best
    assert best.effect == "load_offset" and best.method == "fit"
    gain = 1.0 - best.nrmse_after / d.baseline_nrmse
    assert 0.02 < gain < 0.10, gain  # the band where the old rules disagreed
    assert best.helps and d.best_helps
    assert best.helps == scoring.helps(
        best, d.validation_baseline_nrmse, d.baseline_score, d.baseline_nrmse
    )
    assert d.conclusion.startswith("add load_offset")
    rounds = run_rounds(start, meas, rounds=1)
    assert [r.effect for r in rounds] == [None, "load_offset"]
    assert rounds[1].validation_nrmse < rounds[0].validation_nrmse
    # the fitted offset is the hidden one (sensor noise 1 % of the torque range)
    assert best.parameters["load_offset"] == pytest.approx(0.05, rel=0.2)


def test_nothing_missing_ends_both():
    meas = _gear_measurement({})
    start = base_model("simple_gear")
    d = diagnose(start, meas)
    assert not d.best_helps and not any(c.helps for c in d.candidates)
    assert d.conclusion.startswith(NOTHING_HELPS)
    assert d.to_json()["conclusion"].startswith(NOTHING_HELPS)
    rounds = run_rounds(start, meas, rounds=2)
    assert len(rounds) == 1 and rounds[0].diagnosis.conclusion.startswith(NOTHING_HELPS)


def test_candidates_sorted_by_their_score():
    meas = _gear_measurement({"load_coulomb_friction": 1.0})
    d = diagnose(base_model("simple_gear"), meas)
    fitted = [c for c in d.candidates if c.method == "fit"]
    screened = [c for c in d.candidates if c.method == "screening"]
    assert d.candidates == fitted + screened
    for a, b in zip(fitted, fitted[1:], strict=False):
        # in score order, unless b is within the noise of a and simpler
        assert a.score <= b.score or (
            scoring.within_noise(a, b, d.tie_relative) and a.n_parameters < b.n_parameters
        ), (a.effect, a.score, b.effect, b.score)
    assert d.candidates[0].effect == "coulomb_friction"
