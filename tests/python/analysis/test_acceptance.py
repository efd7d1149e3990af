"""Acceptance of the diagnosis on data gearsim did not make: records of the
independent generator (compliant mesh, a drive with its own speed loop,
encoder speeds, torque noise and offset; tests/python/analysis/independent).

For every effect of the contract on both rigs: the model lacks it, the
diagnosis ranks it first, fitting it brings the validation error to within
1.5x the record's own noise floor, and its parameters land near the truth.
Then backlash next to viscous friction in either order, the one-direction
stroke that must raise an identifiability warning, and the nested pair of a
constant and a load-dependent efficiency.

The noise floor is taken over the whole record; the validation blocks are
spread over it (docs/analysis.md) and the noise is stationary.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from acceptance_checks import FLOOR_FACTOR, noise_floor, ranked_first_and_fitted_to_the_floor
from independent import RIGS, TRUTHS, gearsim_model, generate
from independent.generator import LOAD_DEPENDENT_NOMINAL

from gearsim.analysis import compare, diagnose, fit, prepare_inputs
from gearsim.analysis import modelkit as mk
from gearsim.analysis.fitting import REFIT
from gearsim.analysis.report import run_rounds

CASES = [(block, effect) for block in ("simple_gear", "rack_pinion") for effect in TRUTHS[block]]

#: gearsim's rig with the true parameters, as a multiple of the noise floor,
#: for the effects a compliant mesh does not disturb (at most 1.17 measured
#: over seeds 5, 11 and 23). Coulomb friction and backlash are not held to it:
#: the compliance filters their torque steps, and the same rig reaches 1.16 to
#: 1.50 (Coulomb) and 1.16 to 1.64 (backlash) depending on the record's seed
#: (docs/analysis.md, "What input conditioning cannot remove").
TRUE_MODEL_FACTOR = 1.2
COMPLIANCE_SENSITIVE = ("coulomb_friction", "backlash")

# A rigid rig cannot follow a compliant mesh under Coulomb friction near
# standstill: at the dwells the driven side creeps inside the friction's
# smoothing band, where the friction acts as a damper (30 N per 5 mm/s) in
# series with the mesh spring (2e5 N/m), a 30 ms lag the rigid rig does not
# have: 1.47x the floor with the true parameters in a rigid rig. The
# structure for reversals (a compliance at the mesh with the friction
# regularised behind it, physics.md 11.6) has that lag: 1.06x with the true
# parameters, and the rounds add it after the Coulomb friction
# (test_rack_coulomb_reaches_the_floor_with_the_structure_for_reversals).
RACK_COULOMB = ("rack_pinion", "coulomb_friction")


def structured_truth(block: str, effects: tuple[str, ...]):
    """The truth in gearsim with the structure for reversals: the mesh spring
    and damper as a compliance at the mesh (times the base radius squared),
    the driven-side friction regularised behind it."""
    import gearsim

    mech = RIGS[block]
    t = gearsim_model(block, effects)
    rp = dict(t.rig_params)
    rp.update(
        compliance_stiffness=mech.mesh_stiffness_N_m * mech.base_radius_m**2,
        compliance_damping=mech.mesh_damping_Ns_m * mech.base_radius_m**2,
        load_friction_regularised=True,
    )
    return gearsim.Model(block, dict(t.block_params), rp)


def _case_params(cases, marked):
    return [pytest.param(b, e, id=f"{b}-{e}", marks=marked.get((b, e), ())) for b, e in cases]


def _load_dependent_eta(values: dict, torque: np.ndarray) -> np.ndarray:
    """eq. 2.4 with k from eq. 2.5, at follower torques `torque` (N*m)."""
    g, idle = values["teeth_ratio"], values["idle_torque"]
    k = 1.0 / values["efficiency_nominal"] - 1.0 - g * idle / values["nominal_output_torque"]
    return torque / (g * idle + (k + 1.0) * torque)


def check_parameters(block: str, effect: str, fitted, truth) -> None:
    """Per-parameter tolerances, each with the reason it is not tighter."""
    fb, fr = mk.block_values(fitted), mk.rig_values(fitted)
    tb, tr = mk.block_values(truth), mk.rig_values(truth)
    if effect == "meshing_efficiency":
        # the truth blends the two power-flow directions over 0.3 W and its
        # compliant mesh delays the torque: 0.02 absolute
        assert fb["efficiency_const"] == pytest.approx(tb["efficiency_const"], abs=0.02)
    elif effect == "load_dependent_efficiency":
        # idle part and slope trade off against each other and the inertia;
        # the efficiency curve over the loads of the record is what is seen
        torques = np.array([0.5, 1.0, 2.0, 3.0])
        np.testing.assert_allclose(
            _load_dependent_eta(fb, torques), _load_dependent_eta(tb, torques), atol=0.03
        )
    elif effect == "temperature_dependent_efficiency":
        # three breakpoints fitted at the data's own percentiles, not at the
        # truth's 290/310/330 K: compare the curves inside the span
        temps = np.array([295.0, 310.0, 325.0])
        np.testing.assert_allclose(
            np.interp(temps, fb["temperature_vector"], fb["efficiency_vector"]),
            np.interp(temps, tb["temperature_vector"], tb["efficiency_vector"]),
            atol=0.03,
        )
    elif effect == "viscous_friction":
        # a linear term against speed, well excited: 5 %
        assert mk.viscous_value(fitted) == pytest.approx(mk.viscous_value(truth), rel=0.05)
    elif effect == "coulomb_friction":
        # the compliant mesh smooths each reversal over a few ms: 5 %
        assert fr["load_coulomb_friction"] == pytest.approx(tr["load_coulomb_friction"], rel=0.05)
    elif effect == "load_offset":
        # the torque sensor's offset (0.5 % of its range) looks like a load
        # offset to a rigid speed-driven rig and shifts the estimate: 8 %
        assert fr["load_offset"] == pytest.approx(tr["load_offset"], rel=0.08)
    elif effect == "backlash":
        # the gap is timed by the integral of an encoder speed: 15 %
        assert fb["linear_backlash"] == pytest.approx(tb["linear_backlash"], rel=0.15)
    # the inertia is co-estimated with every effect and must stay right; the
    # truth's base inertia sits behind the torque sensor, so 5 %
    key = mk.driven_inertia_key(truth)
    assert fr[key] == pytest.approx(tr[key], rel=0.05)


@pytest.mark.parametrize(
    "block,effect",
    [c for c in CASES if c[1] not in COMPLIANCE_SENSITIVE],
    ids=[f"{b}-{e}" for b, e in CASES if e not in COMPLIANCE_SENSITIVE],
)
def test_true_parameters_reach_the_noise_floor(block: str, effect: str) -> None:
    """The simulation itself: gearsim's rig with the truth's parameters, on the
    conditioned measured inputs, against the record's noise floor."""
    record = generate(block, (effect,))
    ratio = compare(gearsim_model(block, (effect,)), record.measurement).nrmse / noise_floor(record)
    assert ratio <= TRUE_MODEL_FACTOR, f"{ratio:.3f}x the noise floor"


@pytest.mark.parametrize("block", ["simple_gear", "rack_pinion"])
def test_coulomb_truth_in_the_structure_for_reversals_reaches_the_floor(block: str) -> None:
    """A compliant mesh under Coulomb friction: gearsim's rig with the true
    parameters reaches the floor once it has the structure for reversals
    (1.05x gear, 1.06x rack; a rigid rig 1.16x and 1.47x)."""
    record = generate(block, ("coulomb_friction",))
    floor = noise_floor(record)
    rigid = compare(gearsim_model(block, ("coulomb_friction",)), record.measurement).nrmse / floor
    structured = compare(structured_truth(block, ("coulomb_friction",)), record.measurement)
    ratio = structured.nrmse / floor
    assert ratio <= TRUE_MODEL_FACTOR, f"{ratio:.3f}x the noise floor"
    assert ratio < rigid, (ratio, rigid)


@pytest.mark.parametrize("effects", [("backlash",), ("backlash", "viscous_friction")], ids="+".join)
def test_backlash_contact_gets_the_speed_it_needs(effects: tuple[str, ...]) -> None:
    """A contact integrates the speed: fed through the rigid rig's cut-off,
    the impacts are smeared (1.42x and 1.47x the floor with the true
    parameters); through the contact's own cut-off, 1.17x both."""
    record = generate("simple_gear", effects)
    truth = gearsim_model("simple_gear", effects)
    inputs = prepare_inputs(record.measurement)
    assert inputs.contact_speed is not None
    rigid_cut = dataclasses.replace(inputs, contact_speed=None)
    floor = noise_floor(record)
    with_contact = compare(truth, record.measurement, inputs).nrmse / floor
    without = compare(truth, record.measurement, rigid_cut).nrmse / floor
    assert with_contact <= 0.9 * without, (with_contact, without)
    assert with_contact <= 1.25, with_contact


@pytest.mark.parametrize("block,effect", _case_params([c for c in CASES if c != RACK_COULOMB], {}))
def test_hidden_effect_ranked_fitted_to_the_noise_floor(block: str, effect: str) -> None:
    record = generate(block, (effect,))
    start = gearsim_model(block)
    result = ranked_first_and_fitted_to_the_floor(start, record, effect)
    check_parameters(block, effect, result.model, gearsim_model(block, (effect,)))


def test_rack_coulomb_reaches_the_floor_with_the_structure_for_reversals() -> None:
    """Was a strict expected failure (1.59x the floor after the fit, a rigid
    rig): the Coulomb friction is ranked first and fitted; then the rounds
    propose the compliance from the lag after the reversals and reach the
    floor (0.93x measured, a load offset for the torque sensor's offset
    after it)."""
    block, effect = RACK_COULOMB
    record = generate(block, (effect,))
    start = gearsim_model(block)
    ranking = [c.effect for c in diagnose(start, record.measurement).candidates]
    assert ranking[0] == effect, ranking
    rounds = run_rounds(start, record.measurement, rounds=3)
    found = [r.effect for r in rounds[1:] if r.effect != REFIT]
    assert found[0] == effect and "compliance" in found, found
    floor = noise_floor(record)
    assert rounds[-1].validation_nrmse <= FLOOR_FACTOR * floor, rounds[-1].validation_nrmse / floor
    check_parameters(block, effect, rounds[-1].model, gearsim_model(block, (effect,)))


@pytest.mark.parametrize(
    "order",
    [("backlash", "viscous_friction"), ("viscous_friction", "backlash")],
    ids=["backlash-first", "viscous-first"],
)
def test_backlash_next_to_viscous_friction_in_either_order(order: tuple[str, str]) -> None:
    """A failure seen before: after viscous friction, the backlash gap came out
    40 % short. Either order must reach the floor and both truths."""
    effects = ("backlash", "viscous_friction")
    record = generate("simple_gear", effects)
    model = gearsim_model("simple_gear")
    for effect in order:
        result = fit(model, record.measurement, effect)
        model = result.model
    floor = noise_floor(record)
    assert result.validation_nrmse_after <= FLOOR_FACTOR * floor, (
        result.validation_nrmse_after / floor
    )
    truth = gearsim_model("simple_gear", effects)
    for effect in effects:
        check_parameters("simple_gear", effect, model, truth)


def test_two_rounds_find_backlash_and_viscous_friction() -> None:
    record = generate("simple_gear", ("backlash", "viscous_friction"))
    rounds = run_rounds(gearsim_model("simple_gear"), record.measurement, rounds=2)
    found = [r.effect for r in rounds[1:] if r.effect != REFIT]
    assert sorted(found) == ["backlash", "viscous_friction"], found
    assert rounds[-1].fit.validation_nrmse_after <= FLOOR_FACTOR * noise_floor(record)


#: one direction, constant acceleration, near-constant load: each of these is
#: a constant force on the rack (the inertia too: mass times a constant
#: acceleration)
LOOK_ALIKE = {"coulomb_friction", "load_offset", "meshing_efficiency", "inertia"}
LOOK_ALIKE_PARAMETERS = {"load_coulomb_friction", "load_offset", "efficiency_const", "rack_mass"}


def _names_in(warning: dict) -> set[str]:
    """Effect and parameter names a warning mentions (fields or text)."""
    names = set()
    for key in ("effects", "parameters"):
        names |= set(warning.get(key) or ())
    text = warning.get("text", "")
    names |= {n for n in LOOK_ALIKE | LOOK_ALIKE_PARAMETERS if n in text}
    return names


def test_one_direction_stroke_warns_that_effects_look_alike() -> None:
    """One stroke at near-constant acceleration against a near-constant load:
    Coulomb friction, a load offset and a mesh efficiency are each a constant
    force there. Whatever ranks first, the diagnosis must say so."""
    record = generate("rack_pinion", ("coulomb_friction",), profile="stroke", duration_s=8.0)
    result = diagnose(gearsim_model("rack_pinion"), record.measurement)
    alike = [
        w for w in result.warnings if len(_names_in(w) & (LOOK_ALIKE | LOOK_ALIKE_PARAMETERS)) >= 2
    ]
    assert alike, [w.get("text") for w in result.warnings]
    assert all(w.get("kind") for w in alike)


def test_constant_efficiency_ranks_above_load_dependent_on_constant_data() -> None:
    """Nested pair: a load-dependent efficiency with k = 1/eta - 1 and no idle
    torque is a constant efficiency, so it can only tie; the simpler one wins."""
    record = generate("simple_gear", ("meshing_efficiency",))
    ranking = [
        c.effect for c in diagnose(gearsim_model("simple_gear"), record.measurement).candidates
    ]
    assert ranking.index("meshing_efficiency") < ranking.index("load_dependent_efficiency"), ranking


def test_truth_nominal_point_is_consistent() -> None:
    """The load-dependent truth states k through gearsim's nominal point
    (eq. 2.5): k = 1/0.7 - 1 - 3*0.3/3 = 0.12857."""
    tau_nom, eta_nom = LOAD_DEPENDENT_NOMINAL
    k = TRUTHS["simple_gear"]["load_dependent_efficiency"]["load_slope"]
    assert k == pytest.approx(1 / eta_nom - 1 - 3.0 * 0.3 / tau_nom)
