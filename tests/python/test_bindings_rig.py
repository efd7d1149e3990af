"""Rig per-step and batch calls, RigResult, snapshot/restore, block stepping."""

import pickle

import numpy as np
import pytest

import gearsim


def _speed(n, amp=10.0):
    t = np.arange(n) * 1e-3
    return amp * np.sin(2 * np.pi * 2.0 * t) + 0.3


def test_run_returns_named_arrays():
    rig = gearsim.GearRig(teeth_ratio=3.0, friction_model="constant_efficiency")
    out = rig.run(base_speed=_speed(100), load=0.5)
    assert isinstance(out, gearsim.RigResult)
    assert len(out) == 100
    for name in gearsim.OUTPUT_NAMES:
        arr = out[name]
        assert isinstance(arr, np.ndarray) and arr.dtype == np.float64 and arr.shape == (100,)
        assert np.all(np.isfinite(arr))
    assert set(out.to_dict()) == set(gearsim.OUTPUT_NAMES) == set(out.keys())
    assert out.as_array().shape == (100, 15)
    # kinematics of the rigid gear (opposite rotation, ratio 3)
    np.testing.assert_allclose(out.follower_speed, -out.base_speed / 3.0, rtol=1e-12)


def test_output_names_are_the_documented_ones():
    assert gearsim.OUTPUT_NAMES == (
        "base_torque",
        "base_speed",
        "base_angle",
        "follower_speed",
        "follower_position",
        "base_port_torque",
        "follower_port_torque",
        "mesh_loss_power",
        "loss_power",
        "port_power",
        "contact_energy",
        "temperature",
        "backlash_position",
        "contact_force",
        "follower_acceleration",
    )
    assert gearsim.INPUT_NAMES == (
        "base_speed",
        "base_torque",
        "load",
        "ambient_temperature",
        "measured_temperature",
    )


def test_names_units_and_docs_come_from_the_c_tables():
    from gearsim import rig as rig_module

    assert gearsim.INPUT_NAMES == tuple(f.name for f in rig_module.INPUT_FIELDS)
    assert gearsim.OUTPUT_NAMES == tuple(f.name for f in rig_module.OUTPUT_FIELDS)
    gear, rack = gearsim.GearRig(), gearsim.RackRig()
    assert gear.output_units["follower_speed"] == "rad/s"
    assert rack.output_units["follower_speed"] == "m/s"
    assert rack.output_units["follower_port_torque"] == "N"
    assert gear.input_units == {
        "base_speed": "rad/s",
        "base_torque": "N*m",
        "load": "N*m",
        "ambient_temperature": "K",
        "measured_temperature": "K",
    }
    assert rack.input_units["load"] == "N"
    assert set(gear.state_units) == set(rig_module.STATE_NAMES)
    doc = gearsim.RigResult.follower_speed.__doc__
    assert "rad/s gear rig" in doc and "m/s rack rig" in doc
    assert gearsim.RigResult.loss_power.__doc__.endswith("(W)")


def test_state_by_name():
    from gearsim import rig as rig_module

    rig = gearsim.GearRig(backlash_enabled=True, friction_model="constant_efficiency")
    state = rig.state
    assert tuple(state) == rig_module.STATE_NAMES
    assert state["started"] == 0 and isinstance(state["started"], int)
    assert state["temperature"] == 300.0
    out = rig.run(base_speed=_speed(200), load=0.3)
    state = rig.state
    assert state["started"] == 1 and state["contact_locked"] in (0, 1)
    for name in ("base_speed", "base_angle", "follower_speed", "follower_position"):
        assert state[name] == out[name][-1], name
    for name in ("temperature", "backlash_position"):
        assert state[name] == out[name][-1], name
    state["base_speed"] = 1e9  # a copy: the rig is unchanged
    assert rig.state["base_speed"] == out.base_speed[-1]
    rig.reset()
    assert rig.state["started"] == 0 and rig.state["base_angle"] == 0.0
    assert rig.follower_per_base == pytest.approx(-0.5)
    assert gearsim.RackRig(pinion_radius=0.02).follower_per_base == pytest.approx(0.02)


def test_step_returns_scalars_and_matches_run():
    a = gearsim.RackRig(friction_model="constant_efficiency", rack_mass=2.0)
    b = gearsim.RackRig(friction_model="constant_efficiency", rack_mass=2.0)
    w = _speed(50)
    load = np.linspace(-3, 3, 50)
    batch = a.run(base_speed=w, load=load)
    for i in range(50):
        one = b.step(base_speed=w[i], load=load[i])
        assert isinstance(one.base_torque, float)
        assert len(one) == 1
        for name in gearsim.OUTPUT_NAMES:
            assert one[name] == batch[name][i]  # bit-identical


def test_scalars_broadcast_and_n():
    rig = gearsim.GearRig()
    out = rig.run(base_speed=2.0, load=0.1, n=7)
    assert len(out) == 7
    np.testing.assert_array_equal(out.base_speed, 2.0)
    with pytest.raises(gearsim.InputError, match="n"):
        rig.run(base_speed=2.0)
    assert len(rig.run(base_speed=np.zeros(0))) == 0


def test_input_errors():
    rig = gearsim.GearRig()
    with pytest.raises(gearsim.InputError) as e:
        rig.run(load=np.zeros(3))
    assert e.value.parameter == "base_speed"
    with pytest.raises(gearsim.InputError) as e:
        rig.step(load=1.0)
    assert e.value.parameter == "base_speed"
    with pytest.raises(gearsim.InputError) as e:
        rig.run(base_speed=np.zeros(3), load=np.zeros(4))
    assert e.value.parameter == "load"
    with pytest.raises(gearsim.InputError) as e:
        rig.run(base_speed=np.array([0.0, np.nan, 1.0]))
    assert e.value.parameter == "base_speed" and "sample 1" in str(e.value)
    with pytest.raises(gearsim.InputError) as e:
        rig.step(base_speed=np.inf)
    assert e.value.parameter == "base_speed"
    with pytest.raises(gearsim.InputError):
        rig.run(base_speed=np.zeros((3, 2)))
    with pytest.raises(ValueError):  # InputError is a ValueError
        rig.run_array(np.zeros((3, 4)))
    torque_rig = gearsim.GearRig(base_drive="torque", base_inertia=0.01)
    with pytest.raises(gearsim.InputError) as e:
        torque_rig.step(base_speed=1.0)
    assert e.value.parameter == "base_torque"
    temp_rig = gearsim.GearRig(temperature_input=True)
    with pytest.raises(gearsim.InputError) as e:
        temp_rig.run(base_speed=np.zeros(3))
    assert e.value.parameter == "measured_temperature"


def test_run_array_matches_run_and_accepts_out():
    a = gearsim.GearRig(friction_model="load_dependent_efficiency")
    b = gearsim.GearRig(friction_model="load_dependent_efficiency")
    w = _speed(200)
    inputs = a.inputs(base_speed=w, load=0.2)
    assert inputs.shape == (200, 5)
    out = np.empty((200, 15))
    res = a.run_array(inputs, out=out)
    assert res is out
    ref = b.run(base_speed=w, load=0.2)
    np.testing.assert_array_equal(ref.as_array(), out)
    with pytest.raises(gearsim.InputError):
        a.run_array(inputs, out=np.empty((200, 15), dtype=np.float32))


def test_torque_driven_rig_accelerates():
    rig = gearsim.GearRig(base_drive="torque", base_inertia=0.01, follower_inertia=0.02)
    out = rig.run(base_torque=np.full(100, 0.5))
    assert out.base_speed[-1] > 0.0
    np.testing.assert_array_equal(out.base_torque, 0.5)
    assert rig.step(base_torque=0.5).base_speed > out.base_speed[-1]


def test_temperature_input_and_heat_path():
    rig = gearsim.GearRig(friction_model="temperature_dependent_efficiency", temperature_input=True)
    out = rig.run(base_speed=_speed(10), measured_temperature=np.full(10, 310.0))
    np.testing.assert_array_equal(out.temperature, 310.0)
    hot = gearsim.GearRig(
        friction_model="temperature_dependent_efficiency",
        thermal_resistance=0.01,
        ambient_temperature=350.0,
        thermal_mass=1.0,
    )
    out = hot.run(base_speed=np.zeros(2000))
    assert 300.0 < out.temperature[-1] <= 350.0
    cold = gearsim.GearRig(
        friction_model="temperature_dependent_efficiency", thermal_resistance=0.01, thermal_mass=1.0
    )
    out = cold.run(base_speed=np.zeros(2000), ambient_temperature=np.full(2000, 250.0))
    assert 250.0 <= out.temperature[-1] < 300.0


def test_reset_restarts_the_run():
    rig = gearsim.GearRig(backlash_enabled=True, friction_model="constant_efficiency")
    w = _speed(300)
    first = rig.run(base_speed=w).as_array()
    rig.reset()
    np.testing.assert_array_equal(rig.run(base_speed=w).as_array(), first)


def test_snapshot_restore_and_copy():
    rig = gearsim.RackRig(backlash_enabled=True, rack_mass=1.5)
    w = _speed(400)
    rig.run(base_speed=w[:200])
    snap = rig.snapshot()
    clone = rig.copy()
    tail = rig.run(base_speed=w[200:]).as_array()
    rig.restore(snap)
    np.testing.assert_array_equal(rig.run(base_speed=w[200:]).as_array(), tail)
    np.testing.assert_array_equal(clone.run(base_speed=w[200:]).as_array(), tail)
    # a snapshot survives pickling and restores into a rig with the same parameters
    other = gearsim.RackRig(backlash_enabled=True, rack_mass=1.5)
    other.restore(pickle.loads(pickle.dumps(snap)))
    np.testing.assert_array_equal(other.run(base_speed=w[200:]).as_array(), tail)
    # a snapshot is the state alone: a rig with other parameters continues from
    # it under its own (a re-tuned rig), like a fresh rig stepped to that state
    heavy = gearsim.RackRig(backlash_enabled=True, rack_mass=2.0)
    heavy.restore(snap)
    assert heavy.snapshot() == snap and heavy.state == other_state(snap)
    retuned = heavy.run(base_speed=w[200:]).as_array()
    assert np.all(np.isfinite(retuned)) and not np.array_equal(retuned, tail)
    # but not into a rig of the other block
    with pytest.raises(gearsim.GearsimError, match="rack_pinion"):
        gearsim.GearRig(backlash_enabled=True).restore(snap)


def other_state(snap):
    """Rig.state of a fresh rig of the snapshot's kind restored from it."""
    rig = gearsim.RackRig(backlash_enabled=True, rack_mass=1.5)
    rig.restore(snap)
    return rig.state


def test_rig_from_block_object_and_split_keywords():
    gear = gearsim.SimpleGear(teeth_ratio=4.0)
    rig = gearsim.Rig(gear, dt=2e-3, follower_inertia=0.1)
    assert rig.block is gear and rig.dt == 2e-3 and rig.params["follower_inertia"] == 0.1
    rig2 = gearsim.GearRig(gear, friction_model="constant_efficiency", load_offset=0.1)
    assert rig2.block.teeth_ratio == 4.0
    assert rig2.block.friction_model == "constant_efficiency"
    assert rig2.params["load_offset"] == 0.1
    with pytest.raises(TypeError):
        gearsim.GearRig(gearsim.RackPinion())
    rig3 = gearsim.GearRig(dt="2 ms")
    assert rig3.dt == pytest.approx(2e-3)


def test_block_level_step():
    gear = gearsim.SimpleGear(
        teeth_ratio=2.0, friction_model="constant_efficiency", efficiency_const=0.9
    )
    out = gear.step(1e-3, base_speed=10.0, follower_torque=1.0)
    assert out["follower_speed"] == pytest.approx(-5.0)
    power_in = out["base_torque"] * 10.0 + out["follower_torque"] * out["follower_speed"]
    assert power_in == pytest.approx(out["loss_power"], rel=1e-12, abs=1e-12)
    assert out["loss_power"] >= 0.0
    rack = gearsim.RackPinion(friction_model="constant_efficiency")
    out = rack.step(1e-3, pinion_speed=10.0, rack_force=-5.0)
    assert out["rack_velocity"] == pytest.approx(1.0)
    power_in = out["pinion_torque"] * 10.0 + out["rack_force"] * out["rack_velocity"]
    assert power_in == pytest.approx(out["loss_power"], rel=1e-12, abs=1e-12)
    state = rack.snapshot()
    rack.reset()
    rack.restore(state)


def test_model_rig_keeps_the_model():
    model = gearsim.Model("rack_pinion", {"pinion_radius": 0.02}, {"rack_mass": 3.0})
    rig = model.rig(dt=1e-3)
    assert isinstance(rig, gearsim.Rig) and isinstance(rig, gearsim.RackRig)
    assert rig.model is model
    assert rig.params["rack_mass"] == 3.0
    torque_rig = model.rig(base_drive="torque", base_inertia=1e-3)
    assert torque_rig.base_drive == "torque"


# -- Rig.step: the C per-step entry point (gspy_rig_step) and its slow path ------


def _step_rigs():
    """Speed- and torque-driven rigs of both blocks, with and without temperature input."""
    return [
        gearsim.GearRig(friction_model="constant_efficiency", backlash_enabled=True),
        gearsim.GearRig(
            friction_model="temperature_dependent_efficiency",
            thermal_resistance=2.0,
            ambient_temperature=290.0,
        ),
        gearsim.GearRig(
            friction_model="temperature_dependent_efficiency",
            temperature_input=True,
            base_drive="torque",
            base_inertia=0.01,
        ),
        gearsim.RackRig(rack_mass=2.0, base_drive="torque", base_inertia=1e-3),
        gearsim.RackRig(friction_model="constant_efficiency", temperature_input=True),
    ]


_VALID_INPUTS = {
    "base_speed": 3.0,
    "base_torque": 0.2,
    "load": -0.5,
    "ambient_temperature": 295.0,
    "measured_temperature": 310.0,
}


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf, np.float64("nan"), float("-inf")])
@pytest.mark.parametrize("name", gearsim.INPUT_NAMES)  # Rig.step's keywords
def test_step_rejects_non_finite_inputs_naming_them(name, bad):
    for rig in _step_rigs():
        rig.step(**_VALID_INPUTS)
        before = rig.snapshot().state
        with pytest.raises(gearsim.InputError, match="finite") as e:
            rig.step(**{**_VALID_INPUTS, name: bad})
        assert e.value.parameter == name
        assert rig.snapshot().state == before  # a rejected call does not step


def test_step_names_the_first_bad_input_and_rejects_non_numbers():
    rig = gearsim.GearRig(temperature_input=True)
    with pytest.raises(gearsim.InputError) as e:
        rig.step(base_speed=1.0, load=np.nan, measured_temperature=np.inf)
    assert e.value.parameter == "load"
    for value in (None, "fast", object(), [1.0]):
        with pytest.raises(gearsim.InputError, match="number") as e:
            rig.step(base_speed=1.0, load=value, measured_temperature=300.0)
        assert e.value.parameter == "load"
    with pytest.raises(gearsim.InputError) as e:
        rig.step(base_speed=1.0, ambient_temperature="warm", measured_temperature=300.0)
    assert e.value.parameter == "ambient_temperature"
    # the required inputs are still named when missing
    with pytest.raises(gearsim.InputError) as e:
        rig.step(base_speed=1.0)
    assert e.value.parameter == "measured_temperature"


def test_step_accepts_numbers_of_other_types():
    a = gearsim.GearRig(friction_model="constant_efficiency")
    b = gearsim.GearRig(friction_model="constant_efficiency")
    for x, y in ((2, 1), (np.float32(2.5), np.int64(-1)), (np.float64(0.25), True)):
        one = a.step(base_speed=x, load=y)
        two = b.step(base_speed=float(x), load=float(y))
        assert one.to_dict() == two.to_dict()
    # finite inputs whose sum overflows are finite inputs
    a.step(base_speed=1e308, load=1e308)


def test_step_sequence_equals_gs_rig_run():
    """Rig.step over a short sequence, with inputs given or defaulted, is bit for
    bit gs_rig_run (Rig.run_array) on the same inputs."""
    n = 40
    w = _speed(n)
    tau = np.linspace(-0.3, 0.5, n)
    load = np.linspace(1.0, -1.0, n)
    amb = np.linspace(280.0, 320.0, n)
    meas = np.linspace(300.0, 330.0, n)
    for i, (stepped, batch) in enumerate(zip(_step_rigs(), _step_rigs(), strict=True)):
        speed_driven = stepped.base_drive == "speed"
        rows = []
        columns = np.zeros((n, 5))
        for k in range(n):
            kw = {"base_speed": w[k]} if speed_driven else {"base_torque": tau[k]}
            kw["load"] = load[k]
            if k % 2:  # every other step leaves the optional inputs to their defaults
                kw["ambient_temperature"] = amb[k]
                if not stepped.temperature_input:
                    kw["measured_temperature"] = meas[k]
            if stepped.temperature_input:
                kw["measured_temperature"] = meas[k]
            out = stepped.step(**kw)
            assert type(out) is gearsim.RigResult and len(out) == 1
            rows.append([out[name] for name in gearsim.OUTPUT_NAMES])
            given = {
                "base_speed": 0.0,
                "base_torque": 0.0,
                "ambient_temperature": batch.ambient_temperature,
                **kw,
            }
            given.setdefault("measured_temperature", given["ambient_temperature"])
            columns[k] = [given[name] for name in gearsim.INPUT_NAMES]
        ref = batch.run_array(columns)
        assert np.array_equal(np.array(rows).view(np.uint64), ref.view(np.uint64)), i


def test_step_after_copy_restore_and_reset():
    rig = gearsim.GearRig(backlash_enabled=True, friction_model="constant_efficiency")
    w = _speed(60)
    for k in range(30):
        rig.step(base_speed=w[k])
    clone = rig.copy()
    snap = rig.snapshot()
    tail = [rig.step(base_speed=w[k]).to_dict() for k in range(30, 60)]
    assert [clone.step(base_speed=w[k]).to_dict() for k in range(30, 60)] == tail
    rig.restore(snap)
    assert [rig.step(base_speed=w[k]).to_dict() for k in range(30, 60)] == tail
    rig.reset()
    fresh = gearsim.GearRig(backlash_enabled=True, friction_model="constant_efficiency")
    assert rig.step(base_speed=w[0]).to_dict() == fresh.step(base_speed=w[0]).to_dict()
    # the clone steps its own C state: stepping it leaves the original alone
    before = rig.snapshot().state
    clone.step(base_speed=1.0)
    assert rig.snapshot().state == before


def test_substep_cap_warns_with_the_figure():
    """A stiff contact on a light follower at dt = 1 ms: 16 automatic sub-steps
    leave h*omega_n = 1e-3/16 * sqrt(1e9 * 0.2**2 / 1e-4) = 39.5 (by hand), above
    the target gearsim.AUTO_H_OMEGA_N_MAX, so the rig warns and reports the figure."""
    with pytest.warns(gearsim.SubstepWarning, match=r"h\*omega_n = 39\.5"):
        rig = gearsim.GearRig(backlash_enabled=True, stiffness=1e9, follower_inertia=1e-4)
    assert rig.substeps == 16
    assert rig.substeps_capped
    by_hand = 1e-3 / 16 * (1e9 * 0.2**2 / 1e-4) ** 0.5
    assert rig.contact_h_omega_n == pytest.approx(by_hand, rel=1e-9)


def test_no_substep_warning_when_resolved_or_chosen():
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # defaults: omega_n = sqrt(1e6 * 0.04 / 0.05) = 894 rad/s, 1 sub-step gives 0.894
        rig = gearsim.GearRig(backlash_enabled=True)
        # the same stiff rig with the count chosen by the user: nothing to report
        chosen = gearsim.GearRig(
            backlash_enabled=True, stiffness=1e9, follower_inertia=1e-4, contact_substeps=64
        )
        rigid = gearsim.GearRig()
    assert rig.substeps == 1 and not rig.substeps_capped
    assert rig.contact_h_omega_n == pytest.approx(1e-3 * (1e6 * 0.04 / 0.05) ** 0.5, rel=1e-9)
    assert rig.contact_h_omega_n <= gearsim.AUTO_H_OMEGA_N_MAX
    assert chosen.substeps == 64 and not chosen.substeps_capped
    assert rigid.contact_h_omega_n == 0.0 and rigid.substeps == 1


@pytest.mark.parametrize("hard_stop_model", ["smooth", "full_damped", "full_undamped"])
@pytest.mark.parametrize("contact_no_pull", [True, False])
@pytest.mark.parametrize("contact_lock_enabled", [False, True])
@pytest.mark.parametrize(("efficiency", "contact_substeps"), [(0.5, 0), (0.5, 1), (0.1, 3)])
def test_backlash_options_keep_the_settled_torques(
    hard_stop_model, contact_no_pull, contact_lock_enabled, efficiency, contact_substeps
):
    """The backlash options the C matrix (tests/c/test_settled.c) does not vary: the
    contact lock and the no-pull clip, with a load offset; and, through the
    package, the low efficiencies and odd sub-step counts of
    test_settled_low_efficiency. Once the teeth rest against each other the base
    torque is the rigid law's, by hand (g = 2, opposite rotation, load + offset =
    1 N*m on the follower): base drives (omega_B = +10, the load opposes
    omega_F = -5): 1/(g*eta); follower drives (omega_B = -10, the load aids
    omega_F = +5): eta/g. (With the meshing loss lagging the contact force by a
    sub-step, eta = 0.5 on locked teeth at 1 sub-step alternated between 0.383
    and 0.117 instead of 0.25.)"""
    model = gearsim.Model(
        block="simple_gear",
        block_params=dict(
            teeth_ratio=2.0,
            friction_model="constant_efficiency",
            efficiency_const=efficiency,
            backlash_enabled=True,
            hard_stop_model=hard_stop_model,
            contact_no_pull=contact_no_pull,
            contact_lock_enabled=contact_lock_enabled,
        ),
        rig_params=dict(load_offset=0.3, contact_substeps=contact_substeps),
    )
    for speed, expected in ((10.0, 1.0 / (2.0 * efficiency)), (-10.0, efficiency / 2.0)):
        rig = model.rig(dt=1e-3)
        out = rig.run(base_speed=np.full(3000, speed), load=np.full(3000, 0.7))
        assert out.base_torque[-1] == pytest.approx(expected, rel=1e-9)
        assert out.follower_speed[-1] == pytest.approx(-speed / 2.0, rel=1e-12)
