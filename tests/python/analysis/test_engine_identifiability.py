"""Identifiability warnings on problems whose answer is known by hand."""

from __future__ import annotations

import numpy as np

from gearsim.analysis import fitting as F
from gearsim.analysis.effects import FitParam, separating_excitation
from gearsim.analysis.identifiability import (
    CORRELATION_LIMIT,
    correlated_warnings,
    correlation_matrix,
    parameter_warnings,
)


def _params():
    return [
        FitParam("load_coulomb_friction", 1.0, 0.0, 10.0, owner="coulomb_friction"),
        FitParam("efficiency_const", 0.9, 0.3, 1.0, owner="meshing_efficiency"),
        FitParam(
            "follower_inertia", 0.05, 1e-5, 50.0, role="coestimated", before=0.05, owner="inertia"
        ),
    ]


def test_collinear_columns_give_a_correlation_warning():
    # a linear least-squares problem y = A p: the first two columns nearly
    # collinear (one is the other plus 1e-3 noise), the third independent
    rng = np.random.default_rng(0)
    u = rng.standard_normal(500)
    jac = np.column_stack([u, u + 1e-3 * rng.standard_normal(500), rng.standard_normal(500)])
    corr, _ = correlation_matrix(jac)
    assert abs(corr[0, 1]) > 0.99 and abs(corr[0, 2]) < 0.2
    x = np.array([1.0, 0.9, 0.05])
    warns = parameter_warnings(_params(), x, np.zeros(3), np.ones(3), "coulomb_friction")
    warns += correlated_warnings(_params(), corr, "coulomb_friction")
    kinds = [w["kind"] for w in warns]
    assert kinds == ["correlated"], warns
    w = warns[0]
    assert w["parameters"] == ["load_coulomb_friction", "efficiency_const"]
    assert abs(w["correlation"]) > CORRELATION_LIMIT
    # the warning says which excitation separates Coulomb friction from an efficiency
    assert w["excitation"] == separating_excitation("coulomb_friction", "meshing_efficiency")
    assert "loads" in w["excitation"]


def test_bound_and_moved_coestimate():
    corr = np.eye(3)
    # Coulomb friction at its lower bound 0; inertia moved -42 % from 0.05
    x = np.array([0.0, 0.9, 0.029])
    active = np.array([-1, 0, 0])
    warns = parameter_warnings(_params(), x, active, np.ones(3), "meshing_efficiency")
    by_kind = {w["kind"]: w for w in warns}
    assert set(by_kind) == {"at_bound", "coestimate_moved"}
    assert by_kind["at_bound"]["parameters"] == ["load_coulomb_friction"]
    assert by_kind["at_bound"]["bound"] == "lower"
    moved = by_kind["coestimate_moved"]
    assert moved["parameters"] == ["follower_inertia"] and "-42 %" in moved["text"]
    assert moved["excitation"] == separating_excitation("inertia", "meshing_efficiency")
    # 20 % is within the limit: no warning
    x = np.array([1.0, 0.9, 0.06])
    assert parameter_warnings(_params(), x, np.zeros(3), np.ones(3), "x") == []
    assert correlated_warnings(_params(), corr, "x") == []


class _Solution:
    """What least_squares returns, for _identify: the Jacobian in the
    optimiser's coordinates, the cost and the parameters."""

    def __init__(self, jac, x, cost):
        self.jac, self.x, self.cost = np.asarray(jac, float), np.asarray(x, float), cost
        self.active_mask = np.zeros(len(x), dtype=int)
        self.success, self.message = True, ""


class _Problem:
    def __init__(self, params):
        self.params = params


def test_a_degenerate_direction_is_not_identifiable_and_gets_no_std():
    # residual = (p0 + p1) u + p2 v: p0 and p1 only as their sum, exactly.
    # A correlation of -1.000 with a tiny std is what the rank-deficient
    # normal equations give; the record cannot tell p0 from p1 at all
    rng = np.random.default_rng(1)
    u, v = rng.standard_normal(400), rng.standard_normal(400)
    params = _params()
    x = np.array([1.0, 0.9, 0.05])
    scale = F._scales_u(params, x)
    jac = np.column_stack([u, u, v]) / scale  # d residual / d x, x in its own units
    std, corr, warns = F._uncertainty(_Problem(params), _Solution(jac, x, 0.5 * 400 * 1e-4), "x")
    bad = [w for w in warns if w["kind"] == "not_identifiable"]
    assert len(bad) == 1, warns
    w = bad[0]
    assert w["parameters"] == ["load_coulomb_friction", "efficiency_const"]
    assert "not identifiable from this record" in w["text"] and w["excitation"]
    assert w["excitation"] == separating_excitation("coulomb_friction", "meshing_efficiency")
    assert np.isnan(std[0]) and np.isnan(std[1]) and np.isfinite(std[2])
    assert np.isnan(corr[0, 1]), "no correlation is claimed for an undetermined pair"
    assert not [w for w in warns if w["kind"] == "correlated"]


def test_a_well_posed_problem_has_stds_from_the_scaled_jacobian():
    # residual = p0 u + p1 v + p2 w with independent columns and residual
    # variance s2: std_i = sqrt(s2 / sum(column_i^2)) exactly (orthogonal
    # columns), whatever the parameters' scales
    n = 400
    t = np.arange(n)
    u, v, w = np.cos(2 * np.pi * 3 * t / n), np.sin(2 * np.pi * 5 * t / n), np.ones(n)
    params = _params()
    x = np.array([1.0, 0.9, 0.05])
    cost = 0.5 * 0.01 * (n - 3)  # s2 = 2 cost / (n - p) = 0.01
    std, corr, warns = F._uncertainty(
        _Problem(params), _Solution(np.column_stack([u, v, w]), x, cost), "x"
    )
    want = np.sqrt(0.01 / np.array([u @ u, v @ v, w @ w]))
    assert np.allclose(std, want, rtol=1e-9)
    assert not [w for w in warns if w["kind"] in ("not_identifiable", "correlated")]
