"""Property tests over random valid parameters and operating points
(hypothesis): passivity, energy balance, determinism, snapshot/restore."""

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import gearsim

# random stiff contacts on light sides hit the sub-step cap by design; the
# warning itself is tested in test_bindings_rig.py
pytestmark = pytest.mark.filterwarnings("ignore::gearsim.SubstepWarning")

# Derandomized by default, so that the suite gives the same verdict on every run;
# GEARSIM_HYPOTHESIS_EXPLORE=1 draws new examples (and uses the example database).
EXPLORE = bool(os.environ.get("GEARSIM_HYPOTHESIS_EXPLORE"))
SETTINGS = settings(
    max_examples=60,
    deadline=None,
    derandomize=not EXPLORE,
    database=settings.default.database if EXPLORE else None,
    suppress_health_check=[HealthCheck.too_slow],
)


def _floats(lo, hi):
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)


@st.composite
def _table(draw, lo, step_lo, step_hi, n=None):
    n = draw(st.integers(2, 5)) if n is None else n
    start = draw(_floats(*lo))
    steps = draw(st.lists(_floats(step_lo, step_hi), min_size=n - 1, max_size=n - 1))
    return [start, *list(np.cumsum(steps) + start)]


@st.composite
def _efficiencies(draw, n):
    return draw(st.lists(_floats(0.5, 1.0), min_size=n, max_size=n))


@st.composite
def _backlash(draw, with_base_radius, enabled):
    if not draw(enabled):
        return {"backlash_enabled": False}
    b = draw(_floats(1e-4, 5e-3))
    p = {
        "backlash_enabled": True,
        "hard_stop_model": draw(st.sampled_from(["smooth", "full_undamped", "full_damped"])),
        "linear_backlash": b,
        "transition_region": draw(_floats(0.01, 0.4)) * b,
        "stiffness": draw(_floats(1e3, 1e7)),
        "damping": draw(_floats(0.0, 1e3)),
        "initial_backlash_position": draw(_floats(-1.0, 1.0)) * b / 2,
        "contact_no_pull": draw(st.booleans()),
        "contact_lock_enabled": draw(st.booleans()),
        "contact_speed_threshold": draw(_floats(1e-4, 1e-2)),
        "contact_release_force": draw(_floats(0.0, 10.0)),
    }
    if with_base_radius:
        p["base_radius"] = draw(_floats(0.01, 0.2))
    return p


@st.composite
def _friction(draw, block, smoothing, lossless):
    models = ["none", "constant_efficiency", "temperature_dependent_efficiency"]
    if block == "simple_gear":
        models += ["load_dependent_efficiency", "temperature_load_dependent_efficiency"]
    model = "none" if lossless else draw(st.sampled_from(models))
    p = {
        "friction_model": model,
        "loss_smoothing": draw(smoothing),
        "efficiency_const": draw(_floats(0.5, 1.0)),
        "power_threshold": draw(_floats(1e-4, 1.0)),
        "thermal_mass": draw(_floats(1.0, 100.0)),
        "initial_temperature": draw(_floats(250.0, 350.0)),
    }
    temps = draw(_table((260.0, 300.0), 5.0, 30.0))
    p["temperature_vector"] = temps
    p["efficiency_vector"] = draw(_efficiencies(len(temps)))
    if block == "simple_gear":
        eta_nom = draw(_floats(0.6, 0.99))
        tau_nom = draw(_floats(0.1, 10.0))
        g = draw(_floats(0.2, 10.0))
        p["teeth_ratio"] = g
        p["efficiency_nominal"] = eta_nom
        p["nominal_output_torque"] = tau_nom
        p["idle_torque"] = draw(_floats(0.0, 0.99)) * tau_nom * (1 / eta_nom - 1) / g
        p["speed_threshold"] = draw(_floats(1e-3, 1.0))
        loads = draw(_table((0.0, 1.0), 0.5, 20.0))
        p["load_vector"] = loads
        p["efficiency_matrix"] = [draw(_efficiencies(len(loads))) for _ in temps]
    return p


ANY_SMOOTHING = st.sampled_from(["passive", "simscape"])
ANY_BACKLASH = st.booleans()
ANY_SUBSTEPS = st.sampled_from([0, 1, 4, 16])
# contact_substeps = 1 is excluded where the loss power must be >= 0: see
# test_known_negative_contact_loss_power (a known C core issue, which also shows,
# rarely, with 2 sub-steps and under-resolved contact).
RESOLVED_SUBSTEPS = st.sampled_from([0, 2, 4, 16])


@st.composite
def rigs(
    draw, smoothing=ANY_SMOOTHING, backlash=ANY_BACKLASH, lossless=False, substeps=ANY_SUBSTEPS
):
    """(block, block_params, rig_params, dt, inputs dict).

    smoothing: strategy of loss_smoothing; backlash: strategy of
    backlash_enabled; lossless: friction_model "none" only."""
    block = draw(st.sampled_from(["simple_gear", "rack_pinion"]))
    params = draw(_friction(block, smoothing, lossless))
    params.update(draw(_backlash(block == "simple_gear", backlash)))
    if block == "simple_gear":
        params["output_shaft_rotates"] = draw(st.sampled_from(["same", "opposite"]))
        params["viscous_coefficients"] = [draw(_floats(0.0, 1e-2)), draw(_floats(0.0, 1e-2))]
        rig = {"follower_inertia": draw(_floats(1e-3, 0.5))}
        load_scale = 2.0
    else:
        if draw(st.booleans()):
            params["parameterization"] = "tooth_parameters"
            params["teeth_count"] = float(draw(st.integers(8, 60)))
            params["spacing"] = draw(_floats(1e-3, 1e-2))
        else:
            params["pinion_radius"] = draw(_floats(0.005, 0.15))
        params["rack_directionality"] = draw(st.sampled_from(["positive", "negative"]))
        params["pinion_viscous_coefficient"] = draw(_floats(0.0, 1e-2))
        params["rack_viscous_coefficient"] = draw(_floats(0.0, 10.0))
        rig = {"rack_mass": draw(_floats(0.1, 10.0))}
        load_scale = 50.0
    rig["load_coulomb_friction"] = draw(_floats(0.0, 0.2)) * load_scale
    rig["load_offset"] = draw(_floats(-0.2, 0.2)) * load_scale
    rig["accel_filter_time_constant"] = draw(st.sampled_from([0.0, 1e-3, 1e-2]))
    rig["contact_substeps"] = draw(substeps)
    if draw(st.booleans()):
        rig["thermal_resistance"] = draw(_floats(0.5, 10.0))
    torque_driven = draw(st.booleans())
    if torque_driven:
        rig["base_drive"] = "torque"
        rig["base_inertia"] = draw(_floats(1e-3, 0.1))
    dt = draw(st.sampled_from([1e-4, 5e-4, 1e-3, 2e-3]))
    n = draw(st.integers(20, 300))
    t = np.arange(n) * dt
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    amp = draw(_floats(0.0, 30.0))
    freq = draw(_floats(0.1, 20.0))
    drive = amp * np.sin(2 * np.pi * freq * t) + draw(_floats(-5.0, 5.0))
    drive = drive + rng.normal(0.0, 0.05 * (amp + 1.0), n)
    inputs = {
        "load": draw(_floats(-1.0, 1.0)) * load_scale * np.cos(2 * np.pi * freq * 0.7 * t),
        "ambient_temperature": np.full(n, draw(_floats(260.0, 340.0))),
    }
    if torque_driven:
        inputs["base_torque"] = drive * 0.05
    else:
        inputs["base_speed"] = drive
    return block, params, rig, dt, inputs


def _make(case):
    block, params, rig_params, dt, _ = case
    return gearsim.Model(block, params, rig_params).rig(dt=dt)


def _bits(result):
    return result.as_array().view(np.uint64)


@SETTINGS
@given(rigs(smoothing=st.just("passive"), substeps=RESOLVED_SUBSTEPS))
def test_loss_power_is_never_negative(case):
    out = _make(case).run(**case[4])
    assert np.all(np.isfinite(out.as_array()))
    assert np.all(out.mesh_loss_power >= 0.0)
    # The contact damping power is (f - f_spring)*u in the C core, so with damping = 0
    # it can be a round-off of -1e-17 W: allow round-off relative to the run's power.
    roundoff = 1e-12 * (1.0 + np.max(np.abs(out.port_power)))
    assert np.all(out.loss_power >= -roundoff)
    assert np.all(out.loss_power >= out.mesh_loss_power - roundoff)


def _backlash_energy_ok(out, dt):
    """Port energy >= loss energy + change of the contact energy (the backlash
    spring is relaxed before the first step; implicit integration only adds
    numerical dissipation)."""
    port = np.sum(out.port_power) * dt
    loss = np.sum(out.loss_power) * dt
    stored = out.contact_energy[-1]
    tol = 1e-6 * (np.sum(np.abs(out.port_power)) * dt + loss + abs(stored)) + 1e-12
    return port >= loss + stored - tol, (port, loss, stored)


@SETTINGS
@given(rigs(smoothing=st.just("passive"), backlash=st.just(False)))
def test_energy_balance_rigid_mesh(case):
    # rigid mesh: power in through the ports = loss power, every step
    out = _make(case).run(**case[4])
    scale = np.abs(out.base_port_torque * out.base_speed) + np.abs(out.loss_power) + 1e-9
    assert np.all(np.abs(out.port_power - out.loss_power) <= 1e-9 * scale)


@SETTINGS
@given(rigs(smoothing=st.just("passive"), backlash=st.just(True), lossless=True))
def test_energy_balance_backlash_without_meshing_loss(case):
    ok, detail = _backlash_energy_ok(_make(case).run(**case[4]), case[3])
    assert ok, detail


@SETTINGS
@given(rigs(smoothing=st.just("passive"), backlash=st.just(True)))
def test_energy_balance_backlash_with_meshing_loss(case):
    ok, detail = _backlash_energy_ok(_make(case).run(**case[4]), case[3])
    assert ok, detail


@SETTINGS
@given(rigs())
def test_batch_equals_per_step_loop_and_runs_repeat(case):
    inputs = case[4]
    batch = _make(case).run(**inputs)
    again = _make(case).run(**inputs)
    assert np.array_equal(_bits(batch), _bits(again))
    rig = _make(case)
    n = len(inputs["load"])
    rows = []
    for i in range(n):
        step = rig.step(**{k: float(v[i]) for k, v in inputs.items()})
        rows.append([step[name] for name in gearsim.OUTPUT_NAMES])
    assert np.array_equal(np.array(rows).view(np.uint64), _bits(batch))


@SETTINGS
@given(rigs(), st.floats(0.0, 1.0))
def test_snapshot_restore_is_bit_identical(case, where):
    inputs = case[4]
    n = len(inputs["load"])
    k = int(where * n)
    head = {key: v[:k] for key, v in inputs.items()}
    tail = {key: v[k:] for key, v in inputs.items()}
    rig = _make(case)
    rig.run(**head)
    snap = rig.snapshot()
    first = rig.run(**tail)
    rig.restore(snap)
    second = rig.run(**tail)
    assert np.array_equal(_bits(first), _bits(second))
    fresh = _make(case)  # a new rig with the same parameters continues identically
    fresh.restore(snap)
    assert np.array_equal(_bits(fresh.run(**tail)), _bits(first))
    # and the whole run equals the uninterrupted one
    whole = _make(case).run(**inputs)
    assert np.array_equal(_bits(whole)[k:], _bits(first))


_KNOWN_NEGATIVE_LOSS = {
    # full_damped hard stop, first contact, one sub-step, torque-driven
    "first_contact_full_damped_one_substep": (
        dict(
            teeth_ratio=6.825,
            output_shaft_rotates="same",
            base_radius=0.1028,
            viscous_coefficients=[0.01, 0.0],
            backlash_enabled=True,
            hard_stop_model="full_damped",
            linear_backlash=1e-3,
            stiffness=5.42e6,
            damping=269.8,
            contact_no_pull=False,
            follower_inertia=0.001,
            load_coulomb_friction=0.0253,
            load_offset=-0.1397,
            contact_substeps=1,
            base_drive="torque",
            base_inertia=0.0165,
            dt=2e-3,
        ),
        {"base_torque": [0.0142, 0.1138], "load": 0.0},
    ),
}


def test_first_contact_on_a_jump_has_no_negative_loss():
    """First contact of a full_* law with one sub-step: the root sits on the jump of
    the law at the stop's edge (fixed in src/hard_stop.c, was -0.11 W)."""
    params, inputs = _KNOWN_NEGATIVE_LOSS["first_contact_full_damped_one_substep"]
    out = gearsim.GearRig(**params).run(**inputs)
    assert np.all(out.loss_power >= 0.0), out.loss_power


# smooth hard stop without the no-pull clip, two sub-steps, torque-driven: found by a
# random search over torque-driven rigs (2026-11-25), when the pulling contact's solve
# could end off its root (-2.4 W of loss against +0.2 W of port power)
_NO_PULL_OFF = dict(
    teeth_ratio=6.731394915775876,
    base_radius=0.19987989774176879,
    viscous_coefficients=[0.009536333395616266, 0.001],
    backlash_enabled=True,
    hard_stop_model="smooth",
    linear_backlash=1e-3,
    transition_region=7.351477500472427e-05,
    stiffness=7663541.86215809,
    damping=74.22062198909131,
    initial_backlash_position=0.00031076953079191305,
    contact_no_pull=False,
    follower_inertia=0.00025816738943159587,
    contact_substeps=2,
    base_drive="torque",
    base_inertia=0.00811006197351084,
    dt=2e-3,
)


def test_pulling_contact_keeps_that_rig_passive():
    """Without the no-pull clip the contact solve ends on its root or on the passive
    end of its bracket (docs/model.md): the loss stays non-negative; the clip does
    change that run."""
    rng = np.random.default_rng(0)
    inputs = {"base_torque": rng.normal(0, 0.05, 40), "load": rng.normal(0, 0.5, 40)}
    out = gearsim.GearRig(**_NO_PULL_OFF).run(**inputs)
    assert np.all(out.loss_power >= 0.0), out.loss_power.min()
    clipped = gearsim.GearRig(**{**_NO_PULL_OFF, "contact_no_pull": True}).run(**inputs)
    assert not np.array_equal(out.follower_speed, clipped.follower_speed)


def test_no_pull_default_keeps_that_rig_passive():
    """The same rig and inputs with the default no-pull clip: no negative loss."""
    rng = np.random.default_rng(0)
    inputs = {"base_torque": rng.normal(0, 0.05, 40), "load": rng.normal(0, 0.5, 40)}
    out = gearsim.GearRig(**{**_NO_PULL_OFF, "contact_no_pull": True}).run(**inputs)
    assert np.all(out.loss_power >= 0.0), out.loss_power.min()
