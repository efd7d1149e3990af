"""Identifiability warnings on problems whose answer is known by hand."""

from __future__ import annotations

import numpy as np

from gearsim.analysis.effects import FitParam, separating_excitation
from gearsim.analysis.identifiability import (
    CORRELATION_LIMIT,
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
    warns = parameter_warnings(_params(), x, corr, np.zeros(3), np.ones(3), "coulomb_friction")
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
    warns = parameter_warnings(_params(), x, corr, active, np.ones(3), "meshing_efficiency")
    by_kind = {w["kind"]: w for w in warns}
    assert set(by_kind) == {"at_bound", "coestimate_moved"}
    assert by_kind["at_bound"]["parameters"] == ["load_coulomb_friction"]
    assert by_kind["at_bound"]["bound"] == "lower"
    moved = by_kind["coestimate_moved"]
    assert moved["parameters"] == ["follower_inertia"] and "-42 %" in moved["text"]
    assert moved["excitation"] == separating_excitation("inertia", "meshing_efficiency")
    # 20 % is within the limit: no warning
    x = np.array([1.0, 0.9, 0.06])
    assert parameter_warnings(_params(), x, corr, np.zeros(3), np.ones(3), "x") == []
