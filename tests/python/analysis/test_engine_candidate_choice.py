"""Which candidates diagnose fits (for cost): the best few by screening,
the cheap ones, and the costly ones only when screening predicts a gain; all
of them once a fitted candidate with no signature of its own helped anyway.
And the backlash multi-start probes hold the parameters without starts."""

from __future__ import annotations

import importlib
from dataclasses import dataclass

import numpy as np
import pytest
from analysis_helpers import base_model, measurement

from gearsim.analysis import diagnose
from gearsim.analysis import fitting as F
from gearsim.analysis.effects import FitParam

# the package exports the function diagnose under the module's name
D = importlib.import_module("gearsim.analysis.diagnose")


@dataclass
class FakeEffect:
    name: str
    n_params: int = 1
    costly: bool = False


@dataclass
class FakeScreened:
    effect: FakeEffect
    predicted: float
    ruled_out: str | None = None


@dataclass
class FakeFit:
    validation_nrmse_after: float


# the re-estimation alone predicts 0.100; a 2 % gain (scoring.HELP_MARGIN)
# needs 0.098 or less
NUISANCE = 0.100


def _screened() -> list[FakeScreened]:
    return [
        FakeScreened(FakeEffect("a", 2), 0.050),
        FakeScreened(FakeEffect("ruled", 1), 0.060, ruled_out="no sign"),
        FakeScreened(FakeEffect("b", 3), 0.0995),
        FakeScreened(FakeEffect("c", 2), 0.0999),
        FakeScreened(FakeEffect("gain", 3), 0.0969),  # 3.1 % predicted: worth it
        FakeScreened(FakeEffect("cheap", 1), 0.1000),
        FakeScreened(FakeEffect("contact", 1, costly=True), 0.0990),
        FakeScreened(FakeEffect("stiff", 2), 0.0999),
    ]


def test_the_best_three_the_cheap_and_the_predicted_gains_are_fitted():
    chosen = D._worth_fitting(_screened(), NUISANCE, None)
    # a, b, c: the best three not ruled out; gain: 0.0969 <= 0.098; cheap:
    # one parameter without contact. contact (costly) and stiff (2
    # parameters) predict 1 % and 0.1 %: left to screening
    assert chosen == {"a", "b", "c", "gain", "cheap"}


def test_a_costly_model_makes_every_candidate_costly():
    # a model whose simulation sub-steps a contact or a spring: the cheap
    # exception no longer holds; the best three and the predicted gains stay
    from types import SimpleNamespace

    from gearsim.analysis.effects import EFFECTS

    costly = SimpleNamespace()
    original = D._costly_model
    D._costly_model = lambda model: model is costly
    try:
        chosen = D._worth_fitting(_screened(), NUISANCE, None, costly)
    finally:
        D._costly_model = original
    assert chosen == {"a", "b", "c", "gain"}
    assert EFFECTS["backlash"].costly and EFFECTS["compliance"].costly


def test_top_fits_the_first_n_not_ruled_out_whatever_they_predict():
    assert D._worth_fitting(_screened(), NUISANCE, 2) == {"a", "b"}
    assert D._worth_fitting(_screened(), NUISANCE, 4) == {"a", "b", "c", "gain"}


def test_a_fit_helping_without_a_signature_sends_every_candidate_to_fitting():
    screened = _screened()
    # cheap predicted 0.1000 (no gain of its own: at most 0.1 % is 0.0999);
    # the baseline validation error is 0.200, helping needs <= 0.196
    helped = {"a": FakeFit(0.10), "cheap": FakeFit(0.193)}
    assert D._screening_underreads(screened, helped, NUISANCE, 0.200)
    # 0.197 is a 1.5 % gain: not helping (2 % needed)
    assert not D._screening_underreads(
        screened, {"a": FakeFit(0.10), "cheap": FakeFit(0.197)}, NUISANCE, 0.200
    )
    # a helps, but screening saw its signature (0.050): nothing underread
    assert not D._screening_underreads(screened, {"a": FakeFit(0.10)}, NUISANCE, 0.200)


class Bowl:
    """cost = (x0 - 2)^2 + 4 (x1 - 5)^2 as two residuals; x0 has starts."""

    def __init__(self):
        self.params = [
            FitParam("gap", 1.0, 0.0, 10.0, starts=(0.5, 3.0), diff_step=1e-6),
            FitParam("stiffness", 1.0, 0.0, 10.0, diff_step=1e-6),
        ]
        self.seen: list[np.ndarray] = []

    def residuals(self, x):
        self.seen.append(np.array(x, dtype=float))
        return np.array([x[0] - 2.0, 2.0 * (x[1] - 5.0)])


def test_probe_moves_only_the_parameters_with_starts():
    bowl = Bowl()
    cost, x = F._probe(bowl, np.array([3.0, 1.0]), [0])
    # x1 held at 1: the best over x0 is x0 = 2 with cost (2 (1 - 5))^2 / 2 = 32
    assert x[0] == pytest.approx(2.0, abs=1e-6) and x[1] == 1.0
    assert cost == pytest.approx(32.0, rel=1e-9)
    assert all(s[1] == 1.0 for s in bowl.seen)


def test_multi_start_then_fits_every_parameter():
    res = F._multi_start(Bowl(), np.array([1.0, 1.0]), 50)
    assert res.x == pytest.approx([2.0, 5.0], abs=1e-6)


def test_gear_backlash_record_leaves_the_costly_candidates_to_screening():
    # 10 000 samples of a gear with a hidden backlash: screening sees nothing
    # of the multi-parameter efficiencies and Stribeck friction, and the
    # cheap fits do not help, so those stay screening estimates
    d = diagnose(base_model("simple_gear"), measurement("simple_gear", ("backlash",)))
    assert d.best.effect == "backlash" and d.best.helps
    methods = {c.effect: c.method for c in d.candidates}
    assert methods["stribeck_friction"] == "screening"
    assert methods["viscous_friction"] == "fit" and methods["coulomb_friction"] == "fit"
    note = next(n for n in d.notes if n.startswith("not fitted"))
    assert "stribeck_friction" in note and "viscous_friction" not in note
