"""The rig's regularised driven-side friction, the compliant mesh
(compliance with no base inertia) and the step-mean speed, seen from Python
(docs/physics.md 11). Each key reaches the C rig with its unit converted;
every expected number is derived by hand from the physics, with the
parameters given in units other than SI where a wrong conversion would show.
"""

import math

import numpy as np
import pytest

import gearsim


def _free_rack(regularised, **extra):
    """A lossless rack rig whose pinion is torque-driven with no motor torque:
    r_P = 20 mm, rack 2 kg, pinion 4e-4 kg*m^2 (3 kg at the rack); Coulomb
    friction 0.4 kN smoothed over 8 mm/s."""
    return gearsim.RackRig(
        friction_model="none",
        pinion_radius="20 mm",
        rack_mass="2 kg",
        base_inertia="4e-4 kg*m**2",
        base_drive="torque",
        load_coulomb_friction="0.4 kN",
        load_coulomb_speed_threshold="8 mm/s",
        load_friction_regularised=regularised,
        **extra,
    )


@pytest.mark.parametrize("load", [100.0, -300.0])
def test_rack_creeps_under_a_load_below_the_friction(load):
    """Regularised: the rack creeps at v* = (v_th/4) atanh(L/F); set-valued:
    it stays at rest."""
    rig = _free_rack(True)
    assert rig.params["load_friction_regularised"] is True
    res = rig.run(base_torque=np.zeros(3000), load=load)
    v_star = 0.25 * 8e-3 * math.atanh(load / 400.0)
    assert res.follower_speed[-1] == pytest.approx(v_star, rel=1e-9)
    held = _free_rack(False).run(base_torque=np.zeros(3000), load=load)
    assert np.all(held.follower_speed == 0.0)


def test_compliant_mesh_carries_the_load_after_creeping():
    """Gear, teeth ratio 2 opposite (a = -1/2), base_inertia 0: the spring
    k = 50 N*m/rad acts at the mesh. A load of 0.2 N*m below the 4 N*m
    friction: regularised, the follower creeps until the spring carries it,
    twist -a*L/k = 2 mrad and a drive torque -a*L = 0.1 N*m; set-valued, the
    follower never moves and the spring stays unloaded."""
    kw = dict(
        friction_model="none",
        teeth_ratio=2,
        output_shaft_rotates="opposite",
        follower_inertia="500 g*m**2",
        base_inertia=0.0,
        compliance_stiffness="50 N*m/rad",
        compliance_damping="0.5 N*m*s/rad",
        load_coulomb_friction="4 N*m",
        load_coulomb_speed_threshold="2 rad/s",
    )
    creep = gearsim.GearRig(**kw, load_friction_regularised=True).run(
        base_speed=np.zeros(20000), load=0.2
    )
    assert creep.base_torque[-1] == pytest.approx(0.1, rel=1e-6)
    assert creep.follower_position[-1] == pytest.approx(0.25 * 0.2 / 50.0, rel=1e-6)
    held = gearsim.GearRig(**kw).run(base_speed=np.zeros(2000), load=0.2)
    assert np.all(held.follower_speed == 0.0) and np.all(held.base_torque == 0.0)


def test_step_mean_speed_on_a_ramp():
    """Rack r_P = 50 mm (a = 0.05 m/rad), rack 3 kg, rack viscous 20 N*s/m,
    no loss, no load, the pinion speed ramped at 40 rad/s^2: with
    base_speed_ramp the drive pays a^2 (J_F alpha + mu_F w_mean), w_mean the
    mean of the last two samples; the angle is alpha t^2/2."""
    dt, alpha = 1e-3, 40.0
    w = alpha * dt * np.arange(101)
    kw = dict(
        friction_model="none", pinion_radius="5 cm", rack_mass=3.0, rack_viscous_coefficient=20.0
    )
    ramp = gearsim.RackRig(**kw, base_speed_ramp=True).run(base_speed=w, load=0.0)
    plain = gearsim.RackRig(**kw).run(base_speed=w, load=0.0)
    a2 = 0.05**2
    w_mean = 0.5 * (w[1:] + w[:-1])
    assert ramp.base_torque[1:] == pytest.approx(a2 * (3.0 * alpha + 20.0 * w_mean), rel=1e-9)
    assert plain.base_torque[1:] == pytest.approx(a2 * (3.0 * alpha + 20.0 * w[1:]), rel=1e-9)
    assert ramp.base_speed == pytest.approx(w, rel=1e-12)
    assert ramp.base_angle[-1] == pytest.approx(0.5 * alpha * (100 * dt) ** 2, rel=1e-9)


def test_switches_are_off_by_default_and_saved():
    m = gearsim.Model("simple_gear")
    rp = m.resolved_rig_params
    assert rp["load_friction_regularised"] is False and rp["base_speed_ramp"] is False
    on = m.replace(rig_params={"load_friction_regularised": True, "base_speed_ramp": True})
    back = gearsim.Model.loads(on.dumps())
    assert back.rig_params["load_friction_regularised"] is True
    assert back.rig_params["base_speed_ramp"] is True
