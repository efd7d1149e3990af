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


def _linear_moves(t: np.ndarray, starts: list[float], levels: list[float], ramps: list[float]):
    """Hold each level from its start; move to it from the previous level
    over its ramp time at a constant rate (a step of acceleration at each
    end of a ramp)."""
    y = np.zeros_like(t)
    prev = 0.0
    for t0, level, ramp in zip(starts, levels, ramps, strict=True):
        y += (level - prev) * np.clip((t - t0) / ramp, 0.0, 1.0)
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


#: the slow holds of `creep`, in multiples of its low_speed
SLOW_LEVELS = (0.25, 0.5, 1.0, 1.5)


def creep(
    duration_s: float,
    dt: float,
    max_speed: float,
    max_load: float,
    low_speed: float,
    seed: int,
    temperature_K: tuple[float, float] = (299.0, 301.0),
) -> Profile:
    """Blocks of three holds of 0.5-0.9 s, each reached over 0.15-0.3 s: fast
    (35-100 % of max_speed), slow (a random one of SLOW_LEVELS times
    `low_speed`, rad/s at the base), fast again, all in the block's direction,
    which is random; the load as in `rich`. The slow holds are what a
    breakaway hump needs: a friction that falls from rest to its sliding
    level over a few low_speed shows only while the driven side moves that
    slowly. Reversals happen only between fast holds, so the speed passes
    zero quickly: a slow reversal under a high friction at rest winds up the
    mesh for tens of ms, which no rigid model follows."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(round(duration_s / dt))) * dt
    starts, levels, ramps = [], [], []
    now = 0.1
    while now < t[-1]:
        sign = rng.choice([-1.0, 1.0])
        for kind in ("fast", "slow", "fast"):
            if kind == "slow":
                level = sign * low_speed * rng.choice(SLOW_LEVELS)
            else:
                level = sign * max_speed * rng.uniform(0.35, 1.0)
            starts.append(now)
            levels.append(level)
            ramps.append(rng.uniform(0.15, 0.3))
            now += rng.uniform(0.5, 0.9)
    speed = _cosine_moves(t, starts, levels, ramps)
    n_loads = len(np.arange(0.3, t[-1], 0.7))
    load_starts = list(np.arange(0.3, t[-1], 0.7) + rng.uniform(0, 0.3, size=n_loads))
    load_levels = list(rng.uniform(-0.7, 0.7, size=n_loads) * max_load)
    load = _cosine_moves(t, load_starts, load_levels, [0.2] * n_loads)
    load += 0.3 * max_load * np.sin(2 * np.pi * 0.31 * t + rng.uniform(0, 2 * np.pi))
    return Profile(t, speed, load, _temperature(t, temperature_K))


def steps(
    duration_s: float,
    dt: float,
    max_speed: float,
    max_load: float,
    seed: int,
    temperature_K: tuple[float, float] = (299.0, 301.0),
) -> Profile:
    """Holds of 0.4-0.9 s at random levels of either sign (35-100 % of
    max_speed, one in five at zero), reached at a constant acceleration over
    0.05-0.12 s, so that every move starts and ends with a step of
    acceleration; the load steps between random levels within 10 ms. What
    rings a drive train's resonance: a smooth move hardly excites it."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(round(duration_s / dt))) * dt
    starts, levels, ramps = [], [], []
    now = 0.1
    while now < t[-1]:
        if rng.uniform() < 0.2:
            level = 0.0
        else:
            level = rng.choice([-1.0, 1.0]) * max_speed * rng.uniform(0.35, 1.0)
        starts.append(now)
        levels.append(level)
        ramps.append(rng.uniform(0.05, 0.12))
        now += rng.uniform(0.4, 0.9)
    speed = _linear_moves(t, starts, levels, ramps)
    n_loads = len(np.arange(0.3, t[-1], 0.7))
    load_starts = list(np.arange(0.3, t[-1], 0.7) + rng.uniform(0, 0.3, size=n_loads))
    load_levels = list(rng.uniform(-0.7, 0.7, size=n_loads) * max_load)
    load = _linear_moves(t, load_starts, load_levels, [0.01] * n_loads)
    return Profile(t, speed, load, _temperature(t, temperature_K))
