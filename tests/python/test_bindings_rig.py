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
    np.testing.assert_allclose(out.driven_speed, -out.base_speed / 3.0, rtol=1e-12)


def test_output_names_are_the_documented_ones():
    assert gearsim.OUTPUT_NAMES == (
        "base_torque",
        "base_speed",
        "base_angle",
        "driven_speed",
        "driven_position",
        "base_port_torque",
        "driven_port_torque",
        "mesh_loss_power",
        "loss_power",
        "port_power",
        "contact_energy",
        "temperature",
        "backlash_position",
        "contact_force",
        "driven_acceleration",
    )
    assert gearsim.INPUT_NAMES == (
        "base_speed",
        "base_torque",
        "load",
        "ambient_temperature",
        "measured_temperature",
    )


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
    # but not into a rig with other parameters
    with pytest.raises(gearsim.GearsimError):
        gearsim.RackRig(backlash_enabled=True, rack_mass=2.0).restore(snap)


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
