"""The independent generator (tests/python/analysis/independent) checked on
its own physics: settled torques against hand-derived values, the encoder's
quantum, the noise floor, the compliant mesh's natural frequency; and the
rig effects: a compliant shaft's ring, the breakaway load
of a Stribeck friction, a torque ripple at constant speed, a delayed torque
channel. The expected numbers are worked out in the comments from the rig's
constants, not taken from the generator or from gearsim."""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from independent import RIGS, Losses, generate, mechanism, simulate_true
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


def _zero_crossing_hz(signal: np.ndarray, dt: float) -> float:
    crossings = np.nonzero(np.diff(np.sign(signal)) != 0)[0]
    return float(1.0 / np.median(np.diff(crossings[::2]) * dt))


def test_compliant_shaft_rings_at_its_natural_frequency() -> None:
    # the gear's shaft truth (k = 600 N*m/rad, c = 0.2 N*m*s/rad, base gear
    # 0.001 kg*m^2) with the motor held (1000 kg*m^2, drive loop off), the
    # mesh 100x stiffer (so rigid to 0.1 %) and a 1 N*m load step on the
    # follower. With the motor held and a rigid mesh (physics.md 11.4):
    # a = -1/3, J_eff = 0.001 + 0.05/9 = 0.0065556 kg*m^2,
    # omega_n = sqrt(600/J_eff) = 302.53 rad/s = 48.15 Hz,
    # zeta = 0.2/(2*sqrt(600*J_eff)) = 0.05042: each period the swing shrinks
    # by exp(-2*pi*zeta/sqrt(1 - zeta^2)) = 0.7284;
    # the shaft settles at the torque that holds the load, -a*L = 1/3 N*m.
    mech = dataclasses.replace(
        mechanism("simple_gear", ("compliance",)),
        base_inertia=1e3,
        drive_bandwidth_rad_s=1e-6,
        mesh_stiffness_N_m=2e8,
    )
    dt = 1e-4
    t = np.arange(3000) * dt
    run = simulate_true(mech, t, np.zeros(t.size), np.full(t.size, 1.0), np.full(t.size, 300.0))
    swing = run.base_torque - 1.0 / 3.0
    assert _zero_crossing_hz(swing, dt) == pytest.approx(48.15, rel=0.01)
    period = int(round(1.0 / 48.15 / dt))
    peaks = [float(np.max(np.abs(swing[i * period : (i + 1) * period]))) for i in range(1, 8)]
    decay = np.exp(np.mean(np.diff(np.log(peaks))))
    assert decay == pytest.approx(0.7284, abs=0.02)
    # settled at -a*L: the mean over the last whole periods
    tail = swing[-10 * period :]
    assert float(np.mean(tail)) == pytest.approx(0.0, abs=0.01 / 3)
    # the encoder's shaft (the motor) practically stayed put: 1/3 N*m on
    # 1000 kg*m^2 for 0.3 s is 1e-4 rad/s
    assert float(np.max(np.abs(run.base_speed))) == pytest.approx(1e-4, rel=0.05)
    assert run.gear_speed is not None and float(np.max(np.abs(run.gear_speed))) > 0.01


def test_stribeck_friction_holds_below_breakaway_and_breaks_away_at_it() -> None:
    # the rack's Stribeck truth (Coulomb 30 N, breakaway 60 N, v_S = 0.05 m/s)
    # with the drive loop off and a load ramped by 100 N/s from rest. The
    # generator's friction is (30 + 30*exp(-(v/v_S)^2))*tanh(v/v_c); with
    # v_c = 1 mm/s (v_S/v_c = 50) its largest value over v is within 0.5 % of
    # 60 N: at v = 3, 4 and 5 v_c, 0.9951*59.89 = 59.60 N,
    # 0.99933*59.81 = 59.77 N and 0.99991*59.70 = 59.70 N. Below it the rack
    # creeps inside the tanh band: at 0.9*60 N, tanh(v/v_c) <= 0.9 gives
    # v <= 1.47 mm/s. Above it nothing holds the rack: the friction falls
    # toward 30 N as it speeds up.
    mech = dataclasses.replace(
        mechanism("rack_pinion", ("coulomb_friction", "stribeck_friction")),
        coulomb_speed=1e-3,
        drive_bandwidth_rad_s=1e-6,
    )
    dt = 2e-4
    t = np.arange(5000) * dt
    load = 100.0 * t
    run = simulate_true(mech, t, np.zeros(t.size), load, np.full(t.size, 300.0))
    below = load < 0.9 * 60.0
    assert float(np.max(np.abs(run.driven_speed[below]))) < 1.6e-3
    # the creep reaches 3*v_c where the friction is 59.60 N: at that load
    # (plus what accelerates the rack, ramped at 100 N/s)
    broke = int(np.argmax(run.driven_speed > 3e-3))
    assert load[broke] == pytest.approx(59.6, rel=0.015)
    # and then slides away: 0.1 s later it is far beyond any creep (the net
    # force grows from zero at the peak, so it starts slowly)
    assert run.driven_speed[broke + int(0.1 / dt)] > 0.1


def test_torque_ripple_seen_at_constant_speed() -> None:
    # the gear's ripple truth, the base held at 10 rad/s (a 1000 kg*m^2 motor
    # started at that speed, drive loop off) with no load and no loss: the
    # mesh carries nothing, so the torque sensor reads the ripple alone,
    # 0.08*cos(theta + 0.6) + 0.03*cos(2*theta - 1.1)
    # + 0.05*cos(16*theta + 0.3) + 0.02*cos(32*theta + 2.0), theta = 10*t.
    # A least-squares fit of cos/sin of each harmonic of 10*t over 2 s
    # (3.2 revolutions) must give those amplitudes and phases.
    mech = dataclasses.replace(
        mechanism("simple_gear", ("torque_ripple",)), base_inertia=1e3, drive_bandwidth_rad_s=1e-6
    )
    t = np.arange(2000) * DT
    run = simulate_true(mech, t, np.full(t.size, 10.0), np.zeros(t.size), np.full(t.size, 300.0))
    theta = 10.0 * t
    # the ripple barely moves the heavy motor: switched on at t = 0 it leaves
    # a speed offset of about A_1*sin(phi_1)/(J*omega) = 4.5e-6 rad/s, 1e-5 rad
    # over 2 s
    assert float(np.max(np.abs(run.base_angle - theta))) < 2e-5
    harmonics = (1, 2, 16, 32)
    columns = [f(h * theta) for h in harmonics for f in (np.cos, np.sin)]
    coef, *_ = np.linalg.lstsq(np.column_stack(columns), run.base_torque, rcond=None)
    expected = {1: (0.08, 0.6), 2: (0.03, -1.1), 16: (0.05, 0.3), 32: (0.02, 2.0)}
    for i, h in enumerate(harmonics):
        # A*cos(x + phi) = A*cos(phi)*cos(x) - A*sin(phi)*sin(x)
        c, s = coef[2 * i], coef[2 * i + 1]
        amplitude, phase = expected[h]
        assert math.hypot(c, s) == pytest.approx(amplitude, abs=1e-4), h
        assert math.atan2(-s, c) == pytest.approx(phase, abs=2e-3), h


def _correlation_peak(late: np.ndarray, early: np.ndarray, max_lag: int = 20) -> int:
    """The whole-sample lag at which `early` shifted best matches `late`."""
    a, b, n = late - np.mean(late), early - np.mean(early), late.size
    corr = [
        np.dot(a[max_lag + k : n - max_lag + k], b[max_lag : n - max_lag])
        for k in range(-max_lag, max_lag + 1)
    ]
    return int(np.argmax(corr)) - max_lag


def _phase_slope_lag(late: np.ndarray, early: np.ndarray, max_hz: float) -> float:
    """The delay (samples) from the cross-spectrum: a pure delay tau turns
    the phase of late*conj(early) into -omega*tau. Weighted least-squares
    slope through zero below max_hz (Hann window against the record's ends).
    A parabola through the correlation's peak would be biased: the torque's
    autocorrelation has a cusp, not a parabola, at its top."""
    window = np.hanning(late.size)
    spec_late = np.fft.rfft((late - np.mean(late)) * window)
    spec_early = np.fft.rfft((early - np.mean(early)) * window)
    freq = np.fft.rfftfreq(late.size, DT)
    band = (freq > 0) & (freq < max_hz)
    cross = spec_late[band] * np.conj(spec_early[band])
    omega, weight = 2 * np.pi * freq[band], np.abs(cross)
    return float(-np.sum(weight * omega * np.angle(cross)) / np.sum(weight * omega**2) / DT)


def test_torque_delay_is_the_cross_correlation_lag() -> None:
    # sensor_delay: the torque logged 6.4 ms late (6.4 samples at 1 kHz), the
    # speeds on time. The same record without the delay has the same motion
    # and the same noise draws, so: the delayed torque's cross-correlation
    # with the on-time one peaks at 6.4 samples; the speeds are unchanged;
    # and a whole-sample reading of the fine grid is the on-time torque
    # shifted by those samples.
    late = generate("simple_gear", ("sensor_delay",))
    on_time = generate("simple_gear", ())
    true_late, true_on_time = late.true_outputs["base_torque"], on_time.true_run.base_torque
    assert _correlation_peak(true_late, true_on_time) in (6, 7)
    assert _phase_slope_lag(true_late, true_on_time, 20.0) == pytest.approx(6.4, abs=0.05)
    # the measured torques share their noise draws at lag 0, which pulls the
    # estimate toward 0 where noise dominates: the band below 10 Hz
    measured = [r.measured_outputs["base_torque"] for r in (late, on_time)]
    assert _phase_slope_lag(*measured, 10.0) == pytest.approx(6.4, abs=0.1)
    np.testing.assert_array_equal(
        late.measured_outputs["follower_speed"], on_time.measured_outputs["follower_speed"]
    )
    run = late.true_run
    six = S.delayed_reading(run.fine_torque, run.fine_dt, run.time.size, DT, 6e-3)
    np.testing.assert_allclose(six[6:], run.base_torque[:-6], rtol=0, atol=1e-9)


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
