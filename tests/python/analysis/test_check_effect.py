"""check_effect: every registered effect checked against the contract of
gearsim.analysis.effects.base the same way, like scikit-learn's estimator
checks. A new effect module passes these before anything else looks at it.

Each check runs on short synthetic records of both rigs (the C rig with
sensor imperfections, gearsim.analysis.synthetic) whose starting model lacks
the effect; an effect that does not apply to a rig is checked to say why."""

from __future__ import annotations

import dataclasses
import math
from functools import cache

import numpy as np
import pytest
from analysis_helpers import CONTRACT_EFFECTS, base_model, measurement
from evidence_checks import assert_evidence_adds_up

from gearsim.analysis import compare, prepare_inputs
from gearsim.analysis import modelkit as mk
from gearsim.analysis.effects import (
    EFFECTS,
    Effect,
    FitParam,
    Screening,
    apply_changes,
    coestimated,
    present_effects,
)
from gearsim.analysis.fitting import FitResult, fit_effect
from gearsim.analysis.signatures import build_context

BLOCKS = ("simple_gear", "rack_pinion")
#: what every effect is allowed to name as a look-alike besides the effects
OTHER_OWNERS = {"inertia", "noise"}
#: a record with reversals under friction and a resonance-free rigid drive:
#: every effect can be screened on it
RECORD_EFFECTS = ("coulomb_friction", "viscous_friction")


def _start(block: str):
    """The starting model: the base rig, with the teeth count a ripple needs."""
    return base_model(block).replace(rig_params={"ripple_mesh_teeth": 17})


@cache
def _context(block: str):
    meas = measurement(block, RECORD_EFFECTS, samples=3000)
    model = _start(block)
    inputs = prepare_inputs(meas)
    base = compare(model, meas, inputs)
    return build_context(model, meas, inputs, base.sim, base.regime_masks)


def _effects_on(block: str) -> list[Effect]:
    return [e for e in EFFECTS.values() if block in e.blocks]


CASES = [(name, block) for name in EFFECTS for block in BLOCKS]


def _applies(name: str, block: str) -> bool:
    return block in EFFECTS[name].blocks


def _seed_values(ctx, eff: Effect, screening: Screening) -> dict[str, float]:
    params = eff.parameters(ctx, screening) + coestimated(ctx, eff, screening)
    return {p.name: p.clipped_x0() for p in params}


# ---------------------------------------------------------------- identity


@pytest.mark.parametrize("name", list(EFFECTS))
def test_identity(name):
    eff = EFFECTS[name]
    assert isinstance(eff, Effect) and eff.name == name and name in CONTRACT_EFFECTS
    assert eff.summary and eff.signature_text and eff.excitation, name
    assert set(eff.blocks) <= set(BLOCKS) and eff.blocks, name
    assert eff.n_params >= 1
    known = set(EFFECTS) | OTHER_OWNERS
    assert set(eff.separated_from) <= known, set(eff.separated_from) - known
    assert set(eff.replaces) <= set(EFFECTS) and set(eff.nests) <= set(EFFECTS)
    assert name not in eff.nests and name not in eff.replaces
    # the contract is abstract: the base class cannot stand for an effect
    with pytest.raises(TypeError):
        Effect()  # type: ignore[abstract]


@pytest.mark.parametrize("name, block", CASES)
def test_applicability(name, block):
    eff = EFFECTS[name]
    model = _start(block)
    assert not eff.present(model), "the base rig has none of the effects"
    why = eff.applies(model)
    if not _applies(name, block):
        assert why and block in why
    else:
        assert why is None or isinstance(why, str)


# ---------------------------------------------------------------- screening


@pytest.mark.parametrize("name, block", CASES)
def test_screening_is_frozen_and_finite(name, block):
    if not _applies(name, block):
        pytest.skip(f"{name} does not apply to the {block} rig")
    ctx = _context(block)
    eff = EFFECTS[name]
    s = eff.screen(ctx)
    assert isinstance(s, Screening)
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.predicted_nrmse = 0.0  # type: ignore[misc]
    assert math.isfinite(s.predicted_nrmse) and s.predicted_nrmse >= 0.0
    assert s.ruled_out is None or (isinstance(s.ruled_out, str) and s.ruled_out)
    if s.regression is not None:
        with pytest.raises(dataclasses.FrozenInstanceError):
            s.regression.nrmse = 0.0
        assert np.all(np.isfinite(s.regression.coef))


@pytest.mark.parametrize("name, block", CASES)
def test_evidence_adds_up(name, block):
    if not _applies(name, block):
        pytest.skip(f"{name} does not apply to the {block} rig")
    ctx = _context(block)
    eff = EFFECTS[name]
    s = eff.screen(ctx)
    ev = eff.evidence(ctx, s)
    assert isinstance(ev.get("text"), str) and ev["text"]
    assert ev.get("signature") == eff.signature_text
    assert_evidence_adds_up(ev, {}, ctx.meas.dt, why=s.ruled_out)


# ---------------------------------------------------------------- parameters and model


@pytest.mark.parametrize("name, block", CASES)
def test_parameters_are_well_posed(name, block):
    if not _applies(name, block):
        pytest.skip(f"{name} does not apply to the {block} rig")
    ctx = _context(block)
    eff = EFFECTS[name]
    for screening in (eff.screen(ctx), None):
        params = eff.parameters(ctx, screening)
        assert params, "an effect has at least one parameter"
        names = [p.name for p in params + coestimated(ctx, eff, screening)]
        assert len(names) == len(set(names)), names
        for p in params:
            assert isinstance(p, FitParam) and p.role == "effect"
            assert p.lower <= p.clipped_x0() <= p.upper, p
            assert math.isfinite(p.clipped_x0()) and p.diff_step > 0
            if p.log:
                assert p.lower > 0 and p.upper > p.lower, p
            for g in p.grid:
                assert g > 0
            for start in p.starts:
                assert p.lower <= p.clip(start) <= p.upper


@pytest.mark.parametrize("name, block", CASES)
def test_build_gives_a_model_with_the_effect(name, block):
    if not _applies(name, block):
        pytest.skip(f"{name} does not apply to the {block} rig")
    ctx = _context(block)
    eff = EFFECTS[name]
    s = eff.screen(ctx)
    values = _seed_values(ctx, eff, s)
    model = apply_changes(ctx.model, eff.build(ctx, values))
    model.rig(dt=ctx.meas.dt)  # the C core accepts it
    assert eff.present(model)
    assert eff in present_effects(model)
    assert eff.build(ctx, {}) in (({}, {}), ({}, {}, {})), "nothing to build without its values"
    reported = eff.report(model)
    assert reported
    rig, blk = mk.rig_values(model), mk.block_values(model)
    for key, value in reported.items():
        assert key in rig or key in blk or key in model.analysis or key.endswith("_hz"), key
        if isinstance(value, str):  # an option (a hard-stop law)
            assert value == (rig.get(key) or blk.get(key)), key
            continue
        for v in np.atleast_1d(np.asarray(value, dtype=float)):
            assert math.isfinite(v), (key, value)
    # once present, it is no candidate, and what it re-estimates is well posed
    assert eff.applies(model) == "already in the model"
    ctx2 = dataclasses.replace(ctx, model=model, columns=dict(ctx.columns))
    for p in eff.coestimated(ctx2, None):
        assert p.role == "coestimated" and p.lower <= p.clipped_x0() <= p.upper, p


# ---------------------------------------------------------------- the fit and the report


@pytest.mark.parametrize("name, block", CASES)
def test_fit_runs_and_reports(name, block):
    if not _applies(name, block):
        pytest.skip(f"{name} does not apply to the {block} rig")
    ctx = _context(block)
    r = fit_effect(ctx, name, max_nfev=12)
    assert isinstance(r, FitResult) and r.effect == name
    assert EFFECTS[name].present(r.model)
    assert r.parameters == EFFECTS[name].report(r.model)
    assert isinstance(r.accepted, bool) and r.verdict.startswith(
        "accepted" if r.accepted else "not accepted"
    )
    for w in r.warnings:
        assert w["kind"] and w["text"]
    for f in r.fitted:
        assert f["std"] is None or (math.isfinite(f["std"]) and f["std"] >= 0)
    json_ok = r.to_json()
    assert json_ok["effect"] == name and "accepted" in json_ok and "verdict" in json_ok


@pytest.mark.parametrize("name", [n for n, e in EFFECTS.items() if e.plot is not None])
def test_signature_plot_draws(name):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    block = EFFECTS[name].blocks[0]
    fig, ax = plt.subplots()
    try:
        EFFECTS[name].plot(_context(block), ax)
        assert ax.get_title(), "a signature plot says what it shows"
    finally:
        plt.close(fig)
