"""What a real rig's sensors make of the true signals, and the data's own
noise floor.

- Speeds come from incremental encoders: the position is counted in whole
  increments (floor of angle/quantum) and the speed is the count difference
  over one sample period, so it is quantized to quantum/dt and lags by half a
  sample.
- The drive-torque sensor adds white noise and a constant offset; the load
  sensor white noise; the temperature probe white noise.
- An optional delay (whole samples) on every channel but time, and an
  optional delay of the torque channel alone (any fraction of a sample: a
  torque logged by another device than the speeds), read from the true
  torque at the integrator's fine step.

The noise floor is what a perfect model would still show: the nrmse of the
true, noise-free outputs against the measured ones, rms(meas - true) / std(meas)
per output, and the mean over the two outputs (the overall nrmse of
docs/measurement-format.md section 4).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Sensors:
    base_counts_per_rev: int = 1 << 16
    driven_quantum: float = 2 * np.pi / (1 << 16)  # rad (gear) or m (rack)
    torque_noise: float = 0.01  # std as a fraction of the true torque's range
    torque_offset: float = 0.005  # fraction of the true torque's range
    load_noise: float = 0.01  # std as a fraction of the true load's range
    temperature_noise_K: float = 0.1
    delay_samples: int = 0
    torque_delay_s: float = 0.0  # s, how much the torque reading lags the speeds


def robust_range(x: np.ndarray) -> float:
    lo, hi = np.percentile(x, [0.5, 99.5])
    return float(hi - lo) or 1.0


def encoder_speed(position: np.ndarray, quantum: float, dt: float) -> np.ndarray:
    """Speed from an incremental encoder: whole counts, differenced over one
    sample (the first sample reads 0, the rig starts at rest)."""
    counts = np.floor(position / quantum)
    speed = np.zeros_like(position)
    speed[1:] = np.diff(counts) * quantum / dt
    return speed


def delayed(x: np.ndarray, samples: int) -> np.ndarray:
    if samples <= 0:
        return x
    return np.concatenate([np.full(samples, x[0]), x[:-samples]])


def delayed_reading(fine_signal: np.ndarray, fine_dt: float, n: int, dt: float, delay_s: float):
    """The signal as a sensor that lags by delay_s reads it at the n sample
    instants k*dt: the fine-step signal (spacing fine_dt, starting at 0) at
    k*dt - delay_s, linear between fine steps; before the record starts, its
    first value (the rig is at rest)."""
    fine_time = np.arange(fine_signal.size) * fine_dt
    return np.interp(np.arange(n) * dt - delay_s, fine_time, fine_signal)


def nrmse(measured: np.ndarray, reference: np.ndarray) -> float:
    """rms(measured - reference) / std(measured)."""
    scale = float(np.std(measured))
    return float(np.sqrt(np.mean((measured - reference) ** 2)) / scale) if scale > 0 else 0.0
