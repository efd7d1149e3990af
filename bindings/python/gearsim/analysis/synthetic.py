"""Synthetic measurements: a model run through the C core on a rich excitation,
then measured by imperfect sensors. For demos and tests of the analysis (the
"truth" is known), never for checking the C core against itself.

The excitation (deterministic for a seed) holds what the diagnosis needs to see:
back-and-forth motion with direction reversals, dwells near zero speed and at
high speed, a load that both resists and overruns the motion (so power flows
both ways and the transmitted torque reverses), and a slow temperature ramp.

Sensor model (``SensorModel``): white noise of a given fraction of each
signal's range (robust range: 0.5 to 99.5 percentile) on the torque and load
channels, encoder-like speeds (quantization plus a smaller white noise), a
constant offset on the torque sensor, and 0.1 K noise on the temperature.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from . import modelkit as mk
from .measurement import RIG_SPECS, Measurement

__all__ = ["Excitation", "excitation", "SensorModel", "synthesize"]


@dataclass(frozen=True)
class Excitation:
    """Clean rig inputs: time (s), base speed (rad/s), load (N*m or N),
    temperature (K, None to leave the thermal model free)."""

    time: np.ndarray
    base_speed: np.ndarray
    load: np.ndarray
    temperature: np.ndarray | None


def _smooth_steps(
    rng: np.random.Generator,
    t: np.ndarray,
    levels_fn,
    dur: tuple[float, float] = (0.25, 0.9),
    ramp: tuple[float, float] = (0.08, 0.25),
) -> np.ndarray:
    """Piecewise-constant levels joined by raised-cosine ramps (C1-continuous);
    each ramp takes at most 80 % of its segment."""
    n = t.size
    total = float(t[-1] - t[0]) if n > 1 else 0.0
    edges = [0.0]
    while edges[-1] <= total:
        edges.append(edges[-1] + rng.uniform(*dur))
    edges_a = np.asarray(edges)
    levels = np.asarray(levels_fn(len(edges)), dtype=float)
    ramps = np.minimum(
        rng.uniform(ramp[0], ramp[1], size=len(edges)), 0.8 * np.diff(np.append(edges_a, np.inf))
    )
    tau = t - t[0]
    k = np.clip(np.searchsorted(edges_a, tau, side="right") - 1, 0, len(edges) - 1)
    local = tau - edges_a[k]
    prev = levels[np.maximum(k - 1, 0)]
    frac = np.where(
        (k > 0) & (local < ramps[k]),
        0.5 - 0.5 * np.cos(np.pi * np.minimum(local / ramps[k], 1.0)),
        1.0,
    )
    return prev + (levels[k] - prev) * frac


def excitation(
    n: int,
    dt: float,
    *,
    max_speed: float,
    max_load: float,
    seed: int = 0,
    temperature: tuple[float, float] | None = (290.0, 330.0),
    ramp: tuple[float, float] = (0.15, 0.4),
) -> Excitation:
    """A deterministic excitation of n samples at step dt (see module doc).

    max_speed: peak base speed (rad/s); max_load: peak load (N*m or N);
    temperature: (start, end) of a measured temperature ramp in K, or None."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt

    def speed_levels(k):
        lv = rng.uniform(0.25, 1.0, size=k) * np.where(np.arange(k) % 2 == 0, 1.0, -1.0)
        # some dwells near zero speed and some sign keeps
        z = rng.random(k) < 0.2
        lv[z] = rng.uniform(-0.03, 0.03, size=z.sum())
        return lv * max_speed

    w = _smooth_steps(rng, t, speed_levels, ramp=ramp)
    w += 0.08 * max_speed * np.sin(2 * np.pi * 1.3 * t + rng.uniform(0, 2 * np.pi))

    def load_levels(k):
        return rng.uniform(-1.0, 1.0, size=k) * max_load

    load = 0.6 * _smooth_steps(rng, t, load_levels, dur=(0.4, 1.2), ramp=(0.1, 0.3))
    load += 0.4 * max_load * np.sin(2 * np.pi * 0.37 * t + rng.uniform(0, 2 * np.pi))
    temp = None
    if temperature is not None:
        a, b = temperature
        x = t / t[-1] if n > 1 else t
        temp = a + (b - a) * x + 0.5 * np.sin(2 * np.pi * 0.2 * t)
    return Excitation(t, w, load, temp)


@dataclass(frozen=True)
class SensorModel:
    """Imperfections of the measuring rig.

    noise: std of white noise on the torque and load channels as a fraction of
    their range (0.01 = 1 %); speed_noise: the same for the speed channels;
    speed_resolution: quantization step of the measured speeds as a fraction of
    their range; torque_offset: constant offset of the torque sensor as a
    fraction of its range; temperature_noise: K."""

    noise: float = 0.01
    speed_noise: float = 0.002
    speed_resolution: float = 0.002
    torque_offset: float = 0.005
    temperature_noise: float = 0.1


def synthesize(
    model: Any,
    exc: Excitation,
    sensors: SensorModel = SensorModel(),
    *,
    seed: int = 1,
    path: str = "<synthetic>",
) -> Measurement:
    """Run model's rig on the clean excitation and return what imperfect
    sensors would record, as a validated Measurement. Every channel is
    sampled at the same instants, as a logger samples a rig: the rig is
    stepped as the analysis steps it (gearsim.analysis.simulate: each step
    centred on a sample instant, the contact finely sub-stepped), so the
    record carries no lag of the rig's own."""
    from .simulate import contact_substeps, half_sample

    rng = np.random.default_rng(seed)
    block = mk.block_name(model)
    spec = RIG_SPECS[block]
    dt = float(exc.time[1] - exc.time[0])
    temperature = exc.temperature
    use_t = temperature is not None
    overrides: dict[str, Any] = {"base_speed_ramp": True}
    n_sub = contact_substeps(model, dt)
    if n_sub:
        overrides["contact_substeps"] = n_sub
    rig = model.rig(dt=dt, temperature_input=use_t, **overrides)
    kw = {"base_speed": half_sample(exc.base_speed, +1), "load": exc.load}
    if temperature is not None:
        kw["measured_temperature"] = temperature
    out = rig.run(**kw)
    follower_speed = half_sample(np.asarray(out.follower_speed), -1)

    def noisy(
        x: np.ndarray, q: float | None = None, offset: float = 0.0, noise: float = sensors.noise
    ) -> np.ndarray:
        lo, hi = np.percentile(x, [0.5, 99.5])
        rngx = float(hi - lo) or 1.0
        y = x + noise * rngx * rng.standard_normal(x.size) + offset * rngx
        if q:
            step = q * rngx
            y = np.round(y / step) * step
        return y

    cols = {
        spec.speed_input: noisy(
            exc.base_speed, sensors.speed_resolution, noise=sensors.speed_noise
        ),
        spec.load_input: noisy(exc.load),
        spec.torque_output: noisy(np.asarray(out.base_torque), offset=sensors.torque_offset),
        spec.speed_output: noisy(
            follower_speed, sensors.speed_resolution, noise=sensors.speed_noise
        ),
    }
    if temperature is not None:
        cols["temperature"] = temperature + sensors.temperature_noise * rng.standard_normal(
            exc.time.size
        )
    return Measurement.from_arrays(block, exc.time, path=path, **cols)
