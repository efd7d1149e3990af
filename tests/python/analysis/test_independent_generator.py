"""The independent generator (tests/python/analysis/independent) checked on
its own physics: settled torques against hand-derived values, the encoder's
quantum, the noise floor, the compliant mesh's natural frequency. The expected
numbers are worked out in the comments from the rig's constants, not taken
from the generator or from gearsim."""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from independent import RIGS, Losses, generate, simulate_true
from independent import sensors as S

DT = 1e-3


def _settle(mech, speed_rad_s: float, load: float, seconds: float = 1.5):
    """Ramp the commanded base speed to `speed_rad_s` in 0.2 s, hold it with a
    constant load; the mean true base torque and driven speed over the last
    0.3 s."""
    t = np.arange(int(seconds / DT)) * DT
    u = np.clip(t / 0.2, 0.0, 1.0)
    command = speed_rad_s * u * u * (3 - 2 * u)
    run = simulate_true(mech, t, command, np.full(t.size, load), np.full(t.size, 300.0))
    tail = t > seconds - 0.3
    return float(np.mean(run.base_torque[tail])), float(np.mean(run.driven_speed[tail]))


def test_gear_settled_torque_base_driving() -> None:
    # gear g = 3, opposite rotation (s = -1), r_B = 0.05 m, r_F = 0.15 m.
    # base at 20 rad/s -> follower -20/3 = -6.667 rad/s. Load +2 N*m resists
    # (load*omega_F < 0). Follower balance: T_F = load - mu*omega_F - Fc*sign(omega_F)
    # = 2 + 0.15*6.667 + 0.5 = 3.5 N*m. Base drives: T_F0 = T_F/eta = 4.375,
    # f = -T_F0/(s*r_F) = 29.17 N, tau_B = r_B*f = 1.4583 N*m (= T_F/(eta*g)).
    mech = dataclasses.replace(
        RIGS["simple_gear"], losses=Losses(efficiency=0.8, viscous=0.15, coulomb=0.5)
    )
    torque, speed = _settle(mech, 20.0, 2.0)
    assert speed == pytest.approx(-20.0 / 3.0, rel=1e-4)
    assert torque == pytest.approx(3.5 / (0.8 * 3.0), rel=2e-3)


def test_gear_settled_torque_follower_driving() -> None:
    # the same gear, load -4 N*m overruns (load*omega_F > 0):
    # T_F = -4 + 1 + 0.5 = -2.5 N*m; the follower drives: T_F0 = eta*T_F = -2.0,
    # f = -T_F0/(s*r_F) = -13.33 N, tau_B = -0.6667 N*m: the base receives
    # 13.33 W of the 16.67 W the load puts into the mesh.
    mech = dataclasses.replace(
        RIGS["simple_gear"], losses=Losses(efficiency=0.8, viscous=0.15, coulomb=0.5)
    )
    torque, _ = _settle(mech, 20.0, -4.0)
    assert torque == pytest.approx(-0.8 * 2.5 / 3.0, rel=2e-3)


def test_gear_settled_torque_load_dependent_efficiency() -> None:
    # eq. 2.3: tau_Coul = g*idle + k*|T_F| = 0.9 + 0.1286*2 = 1.1571 N*m
    # (idle 0.3 N*m, k = 1/0.7 - 1 - 0.3), against omega_F < 0:
    # T_F0 = T_F + tau_Coul = 3.1571, tau_B = r_B*T_F0/r_F = 1.0524 N*m;
    # efficiency 2/3.1571 = 0.6335, as eq. 2.4 gives.
    k = 1 / 0.7 - 1 - 0.3
    mech = dataclasses.replace(RIGS["simple_gear"], losses=Losses(idle_torque_Nm=0.3, load_slope=k))
    torque, _ = _settle(mech, 20.0, 2.0)
    assert torque == pytest.approx((2.0 + 0.9 + k * 2.0) / 3.0, rel=2e-3)


def test_rack_settled_force_balance() -> None:
    # rack: r_P = 0.05 m, positive direction; pinion 10 rad/s -> 0.5 m/s.
    # load -50 N resists; viscous 40 N/(m/s) -> 20 N, Coulomb 30 N:
    # T_F = -50 - 20 - 30 = -100 N; the pinion drives: T_F0 = -125 N,
    # tau_P = r_P*125 = 6.25 N*m (62.5 W in, 50 W to the rack: eta 0.8).
    mech = dataclasses.replace(
        RIGS["rack_pinion"], losses=Losses(efficiency=0.8, viscous=40.0, coulomb=30.0)
    )
    torque, speed = _settle(mech, 10.0, -50.0)
    assert speed == pytest.approx(0.5, rel=1e-4)
    assert torque == pytest.approx(6.25, rel=2e-3)


def test_encoder_quantum_and_its_noise() -> None:
    # 65536 counts per revolution at 1 kHz: one count per sample is
    # 2*pi/65536/1e-3 = 0.095874 rad/s. At 20.3 rad/s the shaft turns
    # 211.735 counts per sample, so a reading is 212 counts with probability
    # p = 0.735 and 211 otherwise: its std is quantum*sqrt(p*(1 - p)), and the
    # readings average to the true speed.
    quantum = 2 * math.pi / 65536 / DT
    t = np.arange(20_000) * DT
    speed = S.encoder_speed(20.3 * t + 0.123, 2 * math.pi / 65536, DT)[1:]
    counts = speed / quantum
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-9)
    assert set(np.round(counts).astype(int)) == {211, 212}
    p = 20.3 * DT * 65536 / (2 * math.pi) - 211
    assert float(np.std(speed)) == pytest.approx(quantum * math.sqrt(p * (1 - p)), rel=0.01)
    assert float(np.mean(speed)) == pytest.approx(20.3, abs=quantum / 1000)


def test_noise_floor_is_the_sensor_error() -> None:
    # Torque floor: white noise 1 % and offset 0.5 % of the true range R:
    # rms error = R*sqrt(0.01^2 + 0.005^2); divided by std(measured).
    # Speed floor: encoder error against the instantaneous true speed.
    rec = generate("simple_gear", ("viscous_friction",))
    floor = rec.noise_floor()
    true_torque = rec.true_run.base_torque
    measured = rec.measured_outputs["base_torque"]
    expected = S.robust_range(true_torque) * math.hypot(0.01, 0.005) / float(np.std(measured))
    assert floor["base_torque"] == pytest.approx(expected, rel=0.05)
    err = rec.measured_outputs["follower_speed"] - rec.true_run.driven_speed
    assert floor["follower_speed"] == pytest.approx(
        float(np.sqrt(np.mean(err**2)) / np.std(rec.measured_outputs["follower_speed"])),
        rel=1e-12,
    )
    assert floor["overall"] == pytest.approx(
        0.5 * (floor["base_torque"] + floor["follower_speed"]), rel=1e-12
    )
    # an encoder resolves far better than the torque sensor
    assert 0.0 < floor["follower_speed"] < floor["base_torque"]


def test_compliant_mesh_rings_at_its_natural_frequency() -> None:
    # drive loop practically off, light damping, a load step on the follower:
    # the mesh rings at sqrt(K*(1/m_B + 1/m_F)) with the inertias at the
    # pitch line, m_B = 0.002/0.05^2 = 0.8 kg, m_F = 0.05/0.15^2 = 2.222 kg:
    # sqrt(2e5*(1.25 + 0.45)) = 583.1 rad/s = 92.80 Hz (damping ratio 0.008).
    mech = dataclasses.replace(
        RIGS["simple_gear"], mesh_damping_Ns_m=5.0, drive_bandwidth_rad_s=1e-6
    )
    expected_hz = math.sqrt(2e5 * (1 / 0.8 + 1 / (0.05 / 0.15**2))) / (2 * math.pi)
    assert mech.mesh_natural_frequency_rad_s / (2 * math.pi) == pytest.approx(expected_hz)
    dt = 1e-4
    t = np.arange(2000) * dt
    run = simulate_true(mech, t, np.zeros(t.size), np.full(t.size, 1.0), np.full(t.size, 300.0))
    swing = run.base_torque - np.mean(run.base_torque)
    crossings = np.nonzero(np.diff(np.sign(swing)) != 0)[0]
    periods = np.diff(crossings[::2]) * dt
    assert float(1.0 / np.median(periods)) == pytest.approx(expected_hz, rel=0.02)


def test_generator_never_loads_gearsim_core() -> None:
    """The true mechanism, the sensors and the excitation import without
    gearsim: a finder that refuses gearsim proves it."""
    here = Path(__file__).parent
    code = (
        "import sys, importlib.abc\n"
        "class Block(importlib.abc.MetaPathFinder):\n"
        "    def find_spec(self, name, path, target=None):\n"
        "        if name.split('.')[0] == 'gearsim': raise ImportError('gearsim is off limits')\n"
        "sys.meta_path.insert(0, Block())\n"
        f"sys.path.insert(0, {str(here)!r})\n"
        "import independent.plant, independent.sensors, independent.excitation\n"
        "assert not any(m.startswith('gearsim') for m in sys.modules)\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=60)
