"""Acceptance of the rig effects of physics.md 11 (sensor_delay,
stribeck_friction, compliance, torque_ripple) on data gearsim did not make:
records of the independent generator (tests/python/analysis/independent),
whose truths are in its RIG_EFFECT_TRUTHS.

For each effect on both rigs: the model lacks it, the diagnosis ranks it
first, fitting it brings the validation error to within 1.5x the record's
own noise floor, and its parameters land within the tolerances stated below
with their reasons. Then two effects hidden together, found by two rounds of
run_rounds: a torque delay with Coulomb friction, a compliant shaft with
viscous friction.

What each record holds:

- sensor_delay: the torque logged 6.4 ms after the speeds (read from the
  true torque at the generator's 0.25 ms integration step), the rich profile;
- stribeck_friction: Coulomb friction plus a breakaway hump (the start model
  has the Coulomb level), the creep profile with slow holds at 0.5 to 4 times
  the Stribeck speed;
- compliance: a shaft spring-damper between the motor, on which the encoder
  sits, and a base gear of its own inertia, the torque sensor in the shaft;
  the steps profile, whose moves at constant acceleration ring the shaft at
  about 48 Hz at every start and end (the smooth moves of the rich profile
  hardly excite it);
- torque_ripple: per revolution and per tooth harmonics of the base gear's
  angle acting between the torque sensor and the mesh; the start model knows
  the teeth count (a user reads it off the gear).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from acceptance_checks import FLOOR_FACTOR, noise_floor, ranked_first_and_fitted_to_the_floor
from independent import RIG_EFFECT_TRUTHS, RIGS, gearsim_model, generate, mechanism

from gearsim.analysis import fit
from gearsim.analysis import modelkit as mk
from gearsim.analysis.fitting import REFIT
from gearsim.analysis.report import run_rounds

#: hidden effect -> the effects of its record and generate()'s options
RECORDS = {
    "sensor_delay": (("sensor_delay",), {}),
    "stribeck_friction": (("coulomb_friction", "stribeck_friction"), {"profile": "creep"}),
    "compliance": (("compliance",), {"profile": "steps"}),
    "torque_ripple": (("torque_ripple",), {}),
}
CASES = [(block, effect) for block in RIGS for effect in RIG_EFFECT_TRUTHS[block]]


# A rigid rig against a compliant mesh under Coulomb friction on the rack
# (test_acceptance.py, RACK_COULOMB): 1.47x the floor with the true
# parameters here, 1.53x after the two rounds; a third round adds the
# structure for reversals (a compliance at the mesh, the friction creeping
# behind it) and reaches 1.06x. Was a strict expected failure.
RACK_COULOMB_STRUCTURE = ("compliance",)


def _record(block: str, effect: str):
    effects, options = RECORDS[effect]
    return generate(block, effects, **options)


def _start_model(block: str, effects: tuple[str, ...], hidden: tuple[str, ...]):
    """The truth without the `hidden` effects; with what a user knows from a
    datasheet about a hidden effect: the ripple's teeth count, and the base
    gear's inertia behind a compliant shaft (the analysis takes it as given:
    a speed-driven rig sees only base_inertia + a^2 * driven inertia, so a
    seeded base inertia would move the driven one; docs/analysis.md)."""
    start = gearsim_model(block, tuple(e for e in effects if e not in hidden))
    truth = mechanism(block, effects)
    if "torque_ripple" in hidden:
        start = start.replace(rig_params={"ripple_mesh_teeth": truth.teeth})
    if "compliance" in hidden:
        start = start.replace(rig_params={"base_inertia": truth.gear_inertia})
    return start


def _series_stiffness(mech) -> float:
    """The shaft in series with the mesh, seen at the base shaft (N*m/rad):
    1/(1/k + 1/(K*r_B^2)). The truth's mesh is compliant too (5000 N*m/rad
    there), and a rigid-mesh model can only see the two springs as one; the
    base gear between them is light (0.001 kg*m^2 against 0.0056 and
    0.0125 kg*m^2 of driven inertia at the base), so to first order the
    lower mode is that of the series spring."""
    mesh = mech.mesh_stiffness_N_m * mech.base_radius_m**2
    return 1.0 / (1.0 / mech.shaft_stiffness_Nm_rad + 1.0 / mesh)


def _ripple_phasors(values: dict, prefix: str) -> list[complex]:
    """A*exp(i*phi) per harmonic: amplitude and phase compared together,
    whatever sign convention a fit lands on (A >= 0 keeps it unique)."""
    amplitudes = values[f"ripple_{prefix}_amplitude"]
    phases = values[f"ripple_{prefix}_phase"]
    return [a * complex(math.cos(p), math.sin(p)) for a, p in zip(amplitudes, phases, strict=True)]


#: the model's own lag, which the fitted delay absorbs: an encoder speed is
#: the mean over the sample before its instant (half a sample late) and the
#: rig's inertia torque takes the backward difference of it (another half):
#: at most one sample, 1 ms
MODEL_LAG_S = 1e-3


def check_delay(block: str, fitted, record) -> None:
    """The fitted torque delay against the truth's 6.4 ms. The fit measures
    the torque's lag relative to what the rig makes of the encoder speeds,
    which lags the truth's instants itself (MODEL_LAG_S): absolutely, within
    that; relative to the same fit on the same record without the delay (the
    same motion and noise draws), within 0.2 ms (a fifth of a sample:
    linear interpolation between 1 ms samples against the truth's 0.25 ms
    grid, and torque noise)."""
    truth = RIG_EFFECT_TRUTHS[block]["sensor_delay"]["torque_delay_s"]
    got = mk.torque_delay(fitted)
    assert truth - MODEL_LAG_S <= got <= truth, f"{got * 1e3:.3f} ms"
    others = tuple(e for e in record.effects if e != "sensor_delay")
    on_time = generate(block, others)
    baseline = fit(gearsim_model(block, others), on_time.measurement, "sensor_delay")
    own_lag = mk.torque_delay(baseline.model)
    assert got - own_lag == pytest.approx(truth, abs=0.2e-3), (
        f"{got * 1e3:.3f} ms with the delay, {own_lag * 1e3:.3f} ms without"
    )


def check_parameters(block: str, effect: str, fitted, record) -> None:
    """Per-parameter tolerances, each with the reason it is not tighter."""
    mech = record.mechanism
    fr = mk.rig_values(fitted)
    truth = gearsim_model(block, record.effects)
    tr = mk.rig_values(truth)
    if effect == "sensor_delay":
        check_delay(block, fitted, record)
    elif effect == "stribeck_friction":
        # the level at rest is seen only through the hump at the slow holds
        # and the passes through zero, where the compliant mesh smooths the
        # friction's rise: 15 %; the Stribeck speed sets the hump's width,
        # sampled at four slow speeds: 25 %; the Coulomb level, re-estimated
        # with them, is the friction at every fast hold: 5 %
        assert fr["load_breakaway_friction"] == pytest.approx(
            tr["load_breakaway_friction"], rel=0.15
        )
        assert fr["load_stribeck_speed"] == pytest.approx(tr["load_stribeck_speed"], rel=0.25)
        assert fr["load_coulomb_friction"] == pytest.approx(tr["load_coulomb_friction"], rel=0.05)
    elif effect == "compliance":
        # the stiffness a rigid-mesh model sees is the shaft in series with
        # the mesh (_series_stiffness): 10 % of that
        assert fr["compliance_stiffness"] == pytest.approx(_series_stiffness(mech), rel=0.10)
        # the ring's frequency is what the data shows best: with the fitted
        # base inertia and driven inertia, sqrt(k/(J_B + a^2*J_F)) within 5 %
        # of the series spring's mode (physics.md 11.4)
        a = mech.kinematic_ratio
        key = mk.driven_inertia_key(truth)
        j_eff = fr["base_inertia"] + a**2 * fr[key]
        j_eff_true = mech.gear_inertia + a**2 * mech.driven_inertia
        assert math.sqrt(fr["compliance_stiffness"] / j_eff) == pytest.approx(
            math.sqrt(_series_stiffness(mech) / j_eff_true), rel=0.05
        )
        # damping ratio 0.05: the ring decays over a few periods in 1 %
        # torque noise, and the mesh's own damping adds to it: a factor 2
        zeta = fr["compliance_damping"] / (2 * math.sqrt(fr["compliance_stiffness"] * j_eff))
        zeta_true = mech.shaft_damping_Nms_rad / (
            2 * math.sqrt(mech.shaft_stiffness_Nm_rad * j_eff_true)
        )
        assert zeta_true / 2 <= zeta <= 2 * zeta_true
    elif effect == "torque_ripple":
        # each harmonic as a phasor A*exp(i*phi) (amplitudes 0.02 to
        # 0.1 N*m, torque noise 0.06-0.07 N*m std over 12 000 samples).
        # Per revolution: within 0.01 N*m. Per tooth: within 0.02 N*m. The
        # rig takes the ripple at the angle it integrates from the encoder
        # speeds, which lags the truth's instantaneous angle by half a sample
        # or more (MODEL_LAG_S): at 16-20 teeth and 10-20 rad/s that turns
        # the first tooth harmonic by 0.1-0.2 rad, 0.006-0.012 N*m of a
        # 0.06 N*m phasor, and its speed dependence also blurs the amplitude
        assert fr["ripple_mesh_teeth"] == mech.teeth
        for prefix, tolerance in (("revolution", 0.01), ("mesh", 0.02)):
            got, want = _ripple_phasors(fr, prefix), _ripple_phasors(tr, prefix)
            for i, (g, w) in enumerate(zip(got, want, strict=True), start=1):
                assert abs(g - w) <= tolerance, f"{prefix} harmonic {i}: {g:.4f} vs {w:.4f}"
    # the driven inertia is co-estimated with every effect and must stay
    # right: 5 %, as for the contract's effects
    key = mk.driven_inertia_key(truth)
    assert fr[key] == pytest.approx(tr[key], rel=0.05)


@pytest.mark.parametrize(
    "block,effect",
    [pytest.param(b, e, id=f"{b}-{e}") for b, e in CASES],
)
def test_hidden_effect_ranked_fitted_to_the_noise_floor(block: str, effect: str) -> None:
    record = _record(block, effect)
    start = _start_model(block, record.effects, (effect,))
    result = ranked_first_and_fitted_to_the_floor(start, record, effect)
    check_parameters(block, effect, result.model, record)


#: (block, hidden effects, profile, the structure the rounds add as well)
TWO_EFFECT_CASES = [
    ("simple_gear", ("sensor_delay", "coulomb_friction"), "rich", ()),
    ("rack_pinion", ("sensor_delay", "coulomb_friction"), "rich", RACK_COULOMB_STRUCTURE),
    ("simple_gear", ("compliance", "viscous_friction"), "steps", ()),
    ("rack_pinion", ("compliance", "viscous_friction"), "steps", ()),
]


@pytest.mark.parametrize(
    "block,effects,profile,structure",
    [pytest.param(b, e, p, x, id=f"{b}-{'+'.join(e)}") for b, e, p, x in TWO_EFFECT_CASES],
)
def test_two_rounds_find_both_hidden_effects(
    block: str, effects: tuple[str, str], profile: str, structure: tuple[str, ...]
) -> None:
    record = generate(block, effects, profile=profile)
    rounds = run_rounds(
        gearsim_model(block), record.measurement, rounds=len(effects) + len(structure)
    )
    found = [r.effect for r in rounds[1:] if r.effect != REFIT]
    assert sorted(found) == sorted(effects + structure), found
    floor = noise_floor(record)
    after = rounds[-1].fit.validation_nrmse_after
    assert after <= FLOOR_FACTOR * floor, f"{after / floor:.2f}x the noise floor"
    fitted, truth = rounds[-1].fit.model, gearsim_model(block, effects)
    fr, tr = mk.rig_values(fitted), mk.rig_values(truth)
    if "sensor_delay" in effects:
        # Coulomb friction's torque steps at the reversals are the torque's
        # fastest changes, and the compliant mesh shifts them by the
        # structural lag of test_acceptance.py: the delay fitted next to the
        # friction lands 1.42 ms short on the gear (4.98 ms, the same with
        # the true Coulomb level given), while the same fit on the record
        # without the delay gives +0.35 ms. Within 1.5 ms, short side. With
        # the structure for reversals in the model the lag is the model's
        # own, and the delay and the creep trade off over a sample: 7.06 ms
        # on the rack; within one sample (1 ms) either side
        delay = RIG_EFFECT_TRUTHS[block]["sensor_delay"]["torque_delay_s"]
        got = mk.torque_delay(fitted)
        if structure:
            assert abs(got - delay) <= 1e-3, got
        else:
            assert delay - 1.5e-3 <= got <= delay, got
        # the compliant mesh smooths each reversal over a few ms: 5 %, as in
        # test_acceptance.py
        assert fr["load_coulomb_friction"] == pytest.approx(tr["load_coulomb_friction"], rel=0.05)
    else:
        # a linear term against speed, well excited: 5 %; the shaft as alone
        assert mk.viscous_value(fitted) == pytest.approx(mk.viscous_value(truth), rel=0.05)
        assert fr["compliance_stiffness"] == pytest.approx(
            _series_stiffness(record.mechanism), rel=0.10
        )


def test_truths_are_what_the_docs_say() -> None:
    """The numbers the docstrings and comments quote, from the constants:
    48.1 Hz and 47.5 Hz shafts with the motor held and the mesh rigid, a
    damping ratio of 0.050, and the delay of 6.4 samples."""
    gear = mechanism("simple_gear", ("compliance",))
    rack = mechanism("rack_pinion", ("compliance",))
    # gear: sqrt(600/(0.001 + 0.05/9)) = 302.53 rad/s; rack:
    # sqrt(1200/(0.001 + 0.05^2*5)) = 298.14 rad/s
    assert gear.shaft_natural_frequency_rad_s / (2 * np.pi) == pytest.approx(48.15, abs=0.01)
    assert rack.shaft_natural_frequency_rad_s / (2 * np.pi) == pytest.approx(47.45, abs=0.01)
    # the series springs of check_parameters: 600 and 5000 -> 535.7 N*m/rad
    assert _series_stiffness(gear) == pytest.approx(3000.0 / 5.6, rel=1e-12)
    delay = RIG_EFFECT_TRUTHS["simple_gear"]["sensor_delay"]["torque_delay_s"]
    assert delay / 1e-3 == pytest.approx(6.4)
