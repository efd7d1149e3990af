"""The judging rules of the analysis engine, on hand-computed numbers: the
validation split, the score, the sort and tie rule, the stopping rule."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pytest

from gearsim.analysis import scoring


def test_held_out_blocks_by_hand():
    # block i is held out when floor((i+1) f) > floor(i f)
    assert scoring.held_out_blocks(0.3) == (3, 6, 9)
    assert scoring.held_out_blocks(0.2) == (4, 9)
    assert scoring.held_out_blocks(0.5) == (1, 3, 5, 7, 9)


def test_split_masks_are_contiguous_blocks():
    s = scoring.split_record(100, True, 0.3)
    held = np.nonzero(s.validation)[0]
    assert list(held) == list(range(30, 40)) + list(range(60, 70)) + list(range(90, 100))
    assert not np.any(s.estimation & s.validation)
    assert np.all(s.estimation | s.validation)
    off = scoring.split_record(100, False)
    assert off.estimation.all() and off.validation.all() and not off.enabled
    with pytest.raises(ValueError, match="fraction"):
        scoring.split_record(100, True, 0.7)


def test_lag1_autocorrelation_and_effective_samples():
    x = np.array([1.0, -1.0, 1.0, -1.0])
    # mean 0: sum x_k x_k+1 = -3, sum x^2 = 4
    assert scoring.lag1_autocorrelation(x) == pytest.approx(-0.75)
    # negative rho is clamped to 0: n stays n
    assert scoring.effective_samples(4, -0.75) == pytest.approx(4.0)
    # rho = 0.5: n (1 - 0.5) / (1 + 0.5) = n / 3
    assert scoring.effective_samples(300, 0.5) == pytest.approx(100.0)


def test_bic_by_hand():
    residual = np.array([0.1, -0.2, 0.2, 0.0])
    mask = np.array([True, True, True, False])
    mse = scoring.normalized_mse(residual, 0.5, mask)
    # ((0.2)^2 + (0.4)^2 + (0.4)^2) / 3 = 0.12
    assert mse == pytest.approx(0.12)
    score = scoring.bic_score([0.12, 0.02], [3.0, 2.0], k=2)
    # e_o = sqrt(0.12), sqrt(0.02); e = their mean; N = their n_eff weighted
    # by e_o / sum(e_o)
    e1, e2 = math.sqrt(0.12), math.sqrt(0.02)
    n = (3.0 * e1 + 2.0 * e2) / (e1 + e2)
    expected = n * math.log(((e1 + e2) / 2) ** 2) + 2 * math.log(n)
    assert score == pytest.approx(expected)
    # an output whose error is a millionth of the other's barely counts: the
    # score follows the contract's nrmse, not the log of every output's error
    tiny = scoring.bic_score([0.01, 1e-12], [100.0, 3000.0], k=0)
    smaller = scoring.bic_score([0.01, 0.5e-12], [100.0, 3000.0], k=0)
    assert abs(tiny - smaller) < 0.1 * scoring.TIE_SCORE


@dataclass
class Fake:
    effect: str
    score: float
    validation_nrmse_after: float
    n_parameters: int
    method: str = "fit"
    tied_with: list = field(default_factory=list)


def test_sorted_by_score_fitted_before_screening():
    a = Fake("a", -50.0, 0.30, 2)
    b = Fake("b", -80.0, 0.10, 2)
    s = Fake("s", -500.0, 0.05, 1, method="screening")  # a better-looking estimate
    ranked = scoring.order_candidates([a, s, b])
    assert [c.effect for c in ranked] == ["b", "a", "s"]
    assert b.tied_with == [] and a.tied_with == []


def test_tie_puts_the_simpler_first():
    # scores 1.5 apart (< 2): within the noise; the one with fewer parameters leads
    rich = Fake("load_dependent_efficiency", -100.0, 0.0500, 4)
    simple = Fake("meshing_efficiency", -98.5, 0.0530, 3)
    other = Fake("coulomb_friction", -60.0, 0.0900, 3)
    ranked = scoring.order_candidates([rich, other, simple])
    assert [c.effect for c in ranked] == [
        "meshing_efficiency",
        "load_dependent_efficiency",
        "coulomb_friction",
    ]
    assert simple.tied_with == ["load_dependent_efficiency"]
    # validation errors 0.5 % apart are within the noise too, however far the scores
    x = Fake("x", -300.0, 0.1000, 5)
    y = Fake("y", -200.0, 0.1005, 2)
    assert scoring.within_noise(x, y)
    assert [c.effect for c in scoring.order_candidates([x, y])] == ["y", "x"]
    # 5 % apart and 100 apart: not a tie, the score decides
    z = Fake("z", -200.0, 0.105, 2)
    assert not scoring.within_noise(x, z)
    assert [c.effect for c in scoring.order_candidates([z, x])] == ["x", "z"]


def test_helps_rule():
    c = Fake("c", -120.0, 0.097, 2)
    # 3 % lower validation error and a lower score: helps
    assert scoring.helps(c, 0.1, -100.0)
    # 1 % lower: below the margin
    c.validation_nrmse_after = 0.099
    assert not scoring.helps(c, 0.1, -100.0)
    # lower error but a worse score (the parameters do not pay for themselves)
    c.validation_nrmse_after = 0.05
    assert not scoring.helps(c, 0.1, -130.0)
    # a screening estimate never helps: it was not verified on the simulation
    c.method = "screening"
    assert not scoring.helps(c, 0.1, -100.0)
