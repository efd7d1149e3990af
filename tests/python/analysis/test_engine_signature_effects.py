"""The signatures of the rig effects (physics.md 11), each on a
hand-made residual whose answer is known in closed form, the model file's
[analysis] table, and the delay applied to the simulated torque.

Every expected number below comes from the hand-made signal itself (its
delay, hump, resonance or harmonic), never from the code under test."""

from __future__ import annotations

import numpy as np
import pytest
from analysis_helpers import RIGS, base_model, measurement, truth_model

from gearsim.analysis import compare, fit
from gearsim.analysis import modelkit as mk
from gearsim.analysis.effects.compliance import resonance
from gearsim.analysis.effects.sensor_delay import delay_signature
from gearsim.analysis.effects.stribeck_friction import speed_profile
from gearsim.analysis.effects.torque_ripple import angle_harmonics, base_angle
from gearsim.analysis.measurement import Measurement
from gearsim.errors import ModelFileError

DT = 1e-3


def _multisine(t: np.ndarray, freqs_hz: np.ndarray, seed: int):
    """A band-limited signal and its exact derivative (closed form)."""
    rng = np.random.default_rng(seed)
    amp = rng.uniform(0.5, 1.0, freqs_hz.size)
    ph = rng.uniform(0, 2 * np.pi, freqs_hz.size)
    w = 2 * np.pi * freqs_hz

    def y(tt):
        return np.sum(amp[:, None] * np.sin(w[:, None] * tt + ph[:, None]), axis=0)

    def dy(tt):
        return np.sum((amp * w)[:, None] * np.cos(w[:, None] * tt + ph[:, None]), axis=0)

    return y, dy


def test_delay_signature_finds_the_lag_of_a_delayed_derivative():
    # residual = the output's derivative 3.4 samples late: the correlation
    # peaks at +3.4 samples (sub-sample) with gain 1
    t = np.arange(20_000) * DT
    y, dy = _multisine(t, np.linspace(5.0, 40.0, 12), seed=1)
    lag = 3.4 * DT
    sig = delay_signature(dy(t - lag), y(t), DT)
    assert sig.peak_lag_s == pytest.approx(lag, abs=0.1 * DT)
    assert sig.peak_r > 0.95
    # the central difference of a 40 Hz sine at 1 kHz has gain 0.974: the gain
    # of r on it is 1/0.974 at the top of the band, 1 at its bottom
    assert 0.99 < sig.gain_s < 1.03


def test_delay_signature_of_a_pure_delay():
    # measured = y(t - d): r = y(t - d) - y(t) ~ -d y'(t - d/2): gain -d
    t = np.arange(20_000) * DT
    y, _ = _multisine(t, np.linspace(1.0, 8.0, 10), seed=2)
    d = 6e-3
    sig = delay_signature(y(t - d) - y(t), y(t), DT)
    assert sig.delay_s == pytest.approx(d, rel=0.05)
    assert sig.peak_r < -0.95  # the residual is the derivative with a minus sign


def test_speed_profile_recovers_a_stribeck_hump():
    # r_d * sgn(v) = Fc + Fs exp(-(v/vs)^2): 1 + 2 exp(-(v/0.5)^2) N*m
    rng = np.random.default_rng(3)
    v = rng.choice([-1.0, 1.0], 60_000) * np.geomspace(1e-3, 20.0, 60_000)
    fc, fs, vs = 1.0, 2.0, 0.5
    r_d = np.sign(v) * (fc + fs * np.exp(-((v / vs) ** 2))) + 0.05 * rng.standard_normal(v.size)
    prof = speed_profile(r_d, v)
    assert prof.coulomb == pytest.approx(fc, rel=0.05)
    assert prof.excess == pytest.approx(fs, rel=0.05)
    assert prof.stribeck_speed == pytest.approx(vs, rel=0.1)
    # the bins themselves: near rest the level is Fc + Fs, fast it is Fc
    assert prof.level[0] == pytest.approx(fc + fs, abs=0.05)
    assert prof.level[-1] == pytest.approx(fc, abs=0.05)


def test_resonance_finds_a_damped_ring():
    # a 47 Hz mode with 3 % damping rung by steps 0.3 to 0.7 s apart (at
    # random: a strictly periodic train would have a line spectrum), in
    # noise: the spectrum peaks at the damped frequency f_n sqrt(1 - zeta^2)
    fn, zeta = 47.0, 0.03
    wn = 2 * np.pi * fn
    wd = wn * np.sqrt(1 - zeta**2)
    t = np.arange(30_000) * DT
    r = np.zeros_like(t)
    rng = np.random.default_rng(4)
    for t0 in np.cumsum(rng.uniform(0.3, 0.7, 100)):
        tau = t - t0
        on = tau >= 0
        r[on] += np.exp(-zeta * wn * tau[on]) * np.sin(wd * tau[on])
    r += 0.02 * rng.standard_normal(t.size)
    res = resonance(r, DT)
    assert res.peak_hz == pytest.approx(wd / (2 * np.pi), abs=0.5)
    assert res.prominence > 50
    assert 0.5 * zeta < res.damping_ratio < 2.0 * zeta
    assert res.band_share > 0.5


def test_resonance_of_white_noise_is_not_prominent():
    r = np.random.default_rng(5).standard_normal(30_000)
    assert resonance(r, DT).prominence < 8.0


def test_angle_harmonics_recover_amplitude_and_phase():
    # residual = 0.3 cos(theta + 0.5) + 0.1 cos(40 theta - 1) + noise, theta
    # from a speed that varies: per revolution and per tooth (Z = 40)
    t = np.arange(40_000) * DT
    w = 12.0 + 4.0 * np.sin(2 * np.pi * 0.3 * t)
    theta = np.cumsum(w) * DT
    rng = np.random.default_rng(6)
    r = 0.3 * np.cos(theta + 0.5) + 0.1 * np.cos(40 * theta - 1.0)
    r = r + 0.05 * rng.standard_normal(t.size) + 0.7  # a bias is not a harmonic
    h = angle_harmonics(r, theta, (1.0, 2.0, 40.0, 80.0))
    assert h[0].amplitude == pytest.approx(0.3, abs=0.01)
    assert h[0].phase == pytest.approx(0.5, abs=0.03)
    assert h[2].amplitude == pytest.approx(0.1, abs=0.01)
    assert h[2].phase == pytest.approx(-1.0, abs=0.1)
    # absent harmonics stay within a few standard errors of zero
    for k in (1, 3):
        assert h[k].amplitude < 4 * h[k].std_error
    # std error of an amplitude in white noise: sigma sqrt(2/n)
    assert h[0].std_error == pytest.approx(0.05 * np.sqrt(2 / t.size), rel=0.1)


def test_base_angle_is_the_mid_step_angle():
    w = np.full(5, 10.0)
    assert base_angle(w, DT) == pytest.approx(10.0 * DT * (np.arange(5) + 0.5))


# ---------------------------------------------------------------- the [analysis] table


def _model_file(tmp_path, analysis: str):
    p = tmp_path / "m.toml"
    p.write_text(
        '[rig]\nblock = "simple_gear"\nfollower_inertia = 0.05\n'
        f"[block]\nteeth_ratio = 3.0\n{analysis}"
    )
    return p


def test_analysis_table_reads_units_and_round_trips(tmp_path):
    m = mk.load_model(_model_file(tmp_path, '[analysis]\ntorque_delay = "6 ms"\n'))
    assert mk.torque_delay(m) == pytest.approx(0.006)
    back = mk.AnalysisModel.from_dict(__import__("tomllib").loads(m.dumps()))
    assert back == m and mk.torque_delay(back) == pytest.approx(0.006)
    # a change of the rig keeps the delay
    assert mk.torque_delay(mk.changed(m, rig={"follower_inertia": 0.1})) == pytest.approx(0.006)
    # without the table: a plain model, no delay, and no [analysis] written
    plain = mk.load_model(_model_file(tmp_path, ""))
    assert mk.torque_delay(plain) == 0.0 and "analysis" not in plain.dumps()


@pytest.mark.parametrize(
    "table, names",
    [
        ('[analysis]\ntorque_dlay = "6 ms"\n', "torque_dlay"),
        ('[analysis]\ntorque_delay = "6 kg"\n', "torque_delay"),
        ("[analysis]\ntorque_delay = 5.0\n", "torque_delay"),
        ("[analysis]\ntorque_delay = true\n", "torque_delay"),
    ],
)
def test_analysis_table_refuses_bad_values(tmp_path, table, names):
    with pytest.raises(ModelFileError) as exc:
        mk.load_model(_model_file(tmp_path, table))
    assert exc.value.parameter == names and "m.toml" in str(exc.value)


def test_compare_applies_the_delay_to_the_simulated_torque():
    # a 3-sample delay: the delayed simulation is the plain one 3 samples late
    meas = measurement("simple_gear", ("coulomb_friction",), samples=2000)
    plain = base_model("simple_gear")
    late = mk.AnalysisModel.of(plain, {"torque_delay": 3 * meas.dt})
    a = compare(plain, meas).sim.outputs
    b = compare(late, meas).sim.outputs
    o, s = meas.spec.torque_output, meas.spec.speed_output
    assert np.array_equal(b[o][3:], a[o][:-3]) and np.all(b[o][:3] == a[o][0])
    assert np.array_equal(b[s], a[s])  # the speed channel is the time reference


def test_fit_recovers_a_logger_delay():
    # the measured torque recorded 6 samples late (the first values held),
    # the speed channels on time: the fitted delay is 6 ms, on a sub-sample grid
    meas = measurement("simple_gear", (), samples=5000)
    spec = meas.spec
    lag = 6
    torque = meas[spec.torque_output]
    late = np.concatenate([np.full(lag, torque[0]), torque[:-lag]])
    cols = {c: meas[c] for c in (spec.speed_input, spec.load_input, spec.speed_output)}
    data = Measurement.from_arrays(
        "simple_gear", meas.time, path="<late>", **cols, **{spec.torque_output: late}
    )
    r = fit(base_model("simple_gear"), data, "sensor_delay")
    assert r.parameters["torque_delay"] == pytest.approx(lag * meas.dt, abs=0.25 * meas.dt)
    # the torque error falls to what the same model leaves on the on-time record
    # (the sensor noise): the delay explains all that was added
    o = spec.torque_output
    on_time = compare(base_model("simple_gear"), meas).outputs[o].nrmse
    assert r.outputs_before[o].nrmse > 1.4 * on_time
    assert r.outputs_after[o].nrmse < 1.05 * on_time
    assert not [w for w in r.warnings if w["kind"] == "negligible"]


# ---------------------------------------------------------------- fits on the C rig
#
# Short records of the C rig with a known truth plus the sensor model of
# gearsim.analysis.synthetic (the acceptance matrix checks the same effects
# on the independent generator's data).


def _record(truth, samples=5000, ramp=(0.15, 0.4)):
    from gearsim.analysis import synthetic as S

    _, _, speed, load = RIGS["simple_gear"]
    exc = S.excitation(samples, DT, max_speed=speed, max_load=load, seed=3, ramp=ramp)
    return S.synthesize(truth, exc, seed=5)


def test_fit_recovers_stribeck_friction():
    # breakaway 3 N*m over a 1 N*m Coulomb level, fading over 0.5 rad/s
    truth = {"load_coulomb_friction": 1.0, "load_breakaway_friction": 3.0}
    truth["load_stribeck_speed"] = 0.5
    meas = _record(base_model("simple_gear").replace(rig_params=truth))
    r = fit(base_model("simple_gear"), meas, "stribeck_friction")
    assert r.parameters["load_breakaway_friction"] == pytest.approx(3.0, rel=0.1)
    assert r.parameters["load_coulomb_friction"] == pytest.approx(1.0, rel=0.1)
    assert r.parameters["load_stribeck_speed"] == pytest.approx(0.5, rel=0.2)


def test_fit_recovers_torque_ripple():
    # 0.3 N*m once per revolution at phase 0.5 rad, 0.15 N*m per tooth (Z = 20)
    # at -1 rad; the starting model knows the teeth count
    ripple = {
        "ripple_revolution_amplitude": [0.3, 0.0],
        "ripple_revolution_phase": [0.5, 0.0],
        "ripple_mesh_amplitude": [0.15, 0.0],
        "ripple_mesh_phase": [-1.0, 0.0],
        "ripple_mesh_teeth": 20,
    }
    start = base_model("simple_gear").replace(rig_params={"ripple_mesh_teeth": 20})
    meas = _record(base_model("simple_gear").replace(rig_params=ripple))
    r = fit(start, meas, "torque_ripple")
    p = r.parameters
    assert p["ripple_revolution_amplitude"][0] == pytest.approx(0.3, rel=0.05)
    assert p["ripple_revolution_phase"][0] == pytest.approx(0.5, abs=0.05)
    assert p["ripple_mesh_amplitude"][0] == pytest.approx(0.15, rel=0.1)
    # the tooth phase is 20x as sensitive to the angle the measured speed
    # integrates to (noise, quantization): within 0.4 rad, i.e. 0.02 rad of shaft
    assert p["ripple_mesh_phase"][0] == pytest.approx(-1.0, abs=0.4)
    # the harmonics absent from the residual are not fitted
    assert p["ripple_revolution_amplitude"][1] == 0.0 and p["ripple_mesh_amplitude"][1] == 0.0


def test_fit_recovers_the_shaft_frequency():
    # eq. 11.4: omega_n = sqrt(k / (J_B + J_F/g^2)); J_B = 0.005, J_F = 0.05,
    # g = 3, k chosen for 50 Hz; sharp speed steps make the shaft ring
    jb, jf, g, fn = 0.005, 0.05, 3.0, 50.0
    j_eff = jb + jf / g**2
    k = j_eff * (2 * np.pi * fn) ** 2
    truth = {"base_inertia": jb, "compliance_stiffness": k, "compliance_damping": 0.02}
    meas = _record(base_model("simple_gear").replace(rig_params=truth), ramp=(0.01, 0.03))
    r = fit(base_model("simple_gear"), meas, "compliance")
    assert r.parameters["natural_frequency_hz"] == pytest.approx(fn, abs=0.2)
    assert r.parameters["compliance_damping"] == pytest.approx(0.02, rel=0.15)
    # only J_B + J_F/g^2 is seen: with J_B not given, the follower inertia
    # takes the rest, and the sum is the truth's
    jf_fit = r.model.resolved_rig_params["follower_inertia"]
    assert r.parameters["base_inertia"] + jf_fit / g**2 == pytest.approx(j_eff, rel=0.05)
    assert r.validation_nrmse_after < 0.15 * r.validation_nrmse_before


# ---------------------------------------------------------------- judging and warnings


def test_a_negligible_fit_does_not_help():
    from types import SimpleNamespace

    from gearsim.analysis.scoring import helps

    def cand(warnings):
        return SimpleNamespace(
            method="fit", validation_nrmse_after=0.5, score=-10.0, warnings=warnings
        )

    assert helps(cand([]), 1.0, 0.0)
    assert not helps(cand([{"kind": "negligible", "text": "under 1.5 samples"}]), 1.0, 0.0)


#: a record whose timing the model, not the sensors, decides: 0.2 % torque
#: noise, speeds resolved to 0.02 % of their range, no offset
QUIET = dict(noise=0.002, speed_noise=0.0002, speed_resolution=0.0002, torque_offset=0.0)


@pytest.mark.parametrize("block", ["simple_gear", "rack_pinion"])
@pytest.mark.parametrize("effects", [(), ("coulomb_friction",), ("backlash",)])
def test_no_lag_of_our_own(block, effects):
    """The true model on a record without a delay: the fitted delay is 0 to
    a tenth of a sample. The rig steps centred on the samples and the driven
    speed, an end-of-step value, is taken back half a sample, so nothing the
    rig reports is late. The records are sampled at instants (synthesize
    steps the rig as the analysis does) on the rigid, the friction and the
    backlash paths; the Coulomb friction is smoothed over 5 % of the driven
    speed's range, so that the record resolves when it reverses."""
    from gearsim.analysis import synthetic as S

    _, _, speed, load = RIGS[block]
    truth = truth_model(block, effects)
    if effects == ("coulomb_friction",):
        v_th = 0.05 * speed * abs(mk.kinematic_ratio(truth))
        truth = truth.replace(rig_params={"load_coulomb_speed_threshold": v_th})
    exc = S.excitation(5000, DT, max_speed=speed, max_load=load, seed=3)
    meas = S.synthesize(truth, exc, S.SensorModel(**QUIET), seed=5)
    r = fit(truth, meas, "sensor_delay")
    assert abs(r.parameters["torque_delay"]) <= 0.1 * meas.dt, r.parameters


@pytest.mark.parametrize(
    "a, b, words",
    [
        ("stribeck_friction", "coulomb_friction", "several low speeds"),
        ("sensor_delay", "inertia", "steps of acceleration"),
        ("sensor_delay", "compliance", "steps of acceleration"),
        ("compliance", "inertia", "steps of acceleration"),
        ("torque_ripple", "load_offset", "several revolutions at constant speed"),
    ],
)
def test_separating_excitations(a, b, words):
    from gearsim.analysis.effects import separating_excitation

    assert words in separating_excitation(a, b)
    assert words in separating_excitation(b, a)
