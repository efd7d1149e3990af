"""Commanded base speed, true load and true temperature of a test record.

The rich profile holds what separates the effects: reversals of the speed,
dwells at zero speed and holds at two speed levels, and a load that both
resists and overruns the motion (so power flows both ways through the mesh).
The stroke profile is the hard case: one direction at near-constant
acceleration against a near-constant load, where Coulomb friction, a load
offset and a mesh efficiency all look like one constant force.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Profile:
    time: np.ndarray  # s, uniform
    speed_command: np.ndarray  # rad/s at the base shaft, starts at 0
    load: np.ndarray  # N*m on the follower / N on the rack
    temperature: np.ndarray  # K


def _cosine_moves(t: np.ndarray, starts: list[float], levels: list[float], ramps: list[float]):
    """Hold each level from its start; move to it from the previous level over
    its ramp time with a raised cosine (continuous value and slope)."""
    y = np.zeros_like(t)
    prev = 0.0
    for t0, level, ramp in zip(starts, levels, ramps, strict=True):
        u = np.clip((t - t0) / ramp, 0.0, 1.0)
        y += (level - prev) * (0.5 - 0.5 * np.cos(np.pi * u))
        prev = level
    return y


def _temperature(t: np.ndarray, span_K: tuple[float, float]) -> np.ndarray:
    start, end = span_K
    return start + (end - start) * t / t[-1] + 0.5 * np.sin(2 * np.pi * 0.2 * t)


def rich(
    duration_s: float,
    dt: float,
    max_speed: float,
    max_load: float,
    seed: int,
    temperature_K: tuple[float, float] = (290.0, 330.0),
) -> Profile:
    """Segments of 0.4-0.9 s: reversal, dwell at zero, a hold at a second
    level, in a seeded random order, each reached over 0.15-0.3 s; the load
    steps between random levels of either sign, with a slow sine on top."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(round(duration_s / dt))) * dt
    starts, levels, ramps = [], [], []
    now, sign = 0.1, 1.0
    while now < t[-1]:
        kind = rng.choice(["reverse", "dwell", "second_level"], p=[0.5, 0.2, 0.3])
        if kind == "dwell":
            level = 0.0
        else:
            sign = -sign if kind == "reverse" else sign
            level = sign * max_speed * rng.uniform(0.35, 1.0)
        starts.append(now)
        levels.append(level)
        ramps.append(rng.uniform(0.15, 0.3))
        now += rng.uniform(0.4, 0.9)
    speed = _cosine_moves(t, starts, levels, ramps)
    load_starts = list(
        np.arange(0.3, t[-1], 0.7) + rng.uniform(0, 0.3, size=len(np.arange(0.3, t[-1], 0.7)))
    )
    load_levels = list(rng.uniform(-0.7, 0.7, size=len(load_starts)) * max_load)
    load = _cosine_moves(t, load_starts, load_levels, [0.2] * len(load_starts))
    load += 0.3 * max_load * np.sin(2 * np.pi * 0.31 * t + rng.uniform(0, 2 * np.pi))
    return Profile(t, speed, load, _temperature(t, temperature_K))


def stroke(
    duration_s: float,
    dt: float,
    max_speed: float,
    load: float,
    temperature_K: tuple[float, float] = (299.0, 301.0),
) -> Profile:
    """One stroke in the positive direction: reach 5 % of max_speed in 0.2 s,
    then accelerate at a constant rate to max_speed at the end, against a
    constant load (N*m or N, sign as given) with a 2 % ripple."""
    t = np.arange(int(round(duration_s / dt))) * dt
    start = 0.05 * max_speed * np.clip(t / 0.2, 0, 1) ** 2 * (3 - 2 * np.clip(t / 0.2, 0, 1))
    ramp = np.clip((t - 0.2) / (t[-1] - 0.2), 0.0, 1.0) * 0.95 * max_speed
    force = load * (1.0 + 0.02 * np.sin(2 * np.pi * 0.7 * t))
    return Profile(t, start + ramp, force, _temperature(t, temperature_K))
