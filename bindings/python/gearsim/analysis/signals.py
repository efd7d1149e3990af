"""Signal helpers: zero-phase low-pass filtering and its automatic cut-off.

Offline analysis may filter without delay. ``zero_phase_lowpass`` applies the
squared magnitude of an order-``order`` Butterworth low-pass in the frequency
domain, which is what ``scipy.signal.filtfilt`` of that Butterworth filter does
(zero phase, -6 dB at the cut-off), with odd reflection of ``pad`` samples at
both ends, as filtfilt does, so that edges keep their value and slope. It needs
numpy only (no scipy import on the ``compare`` path).

``auto_cutoff`` picks a cut-off from the signal's own spectrum: the noise floor
is the median power density in the upper half of the band; the cut-off is twice
the highest frequency whose (smoothed) density still stands 30x above that
floor, clamped to [fs/500, fs/8]. Quantized or noisy speeds get filtered where
they are only noise; clean signals are barely touched. ``contact_cutoff`` is
the cut-off for a speed that drives a spring (a backlash contact or a
compliant base shaft) rather than a rigid mesh (3x instead of 30x, clamped to
[the rigid cut-off, fs/4]; see there).

``is_held`` recognises a held input: a command recorded with a zero-order
hold (a CSV converted from a HIL log, a setpoint logged at a slower rate than
the samples) is a staircase whose steps are the signal itself, not noise.
Filtering would smear every step over the filter's length and feed the rig
inputs it never saw, so the automatic choice leaves such an input alone. A
held input has at least ``HELD_REPEAT_FRACTION`` of its consecutive samples
exactly equal, and its changes are not mostly a single smallest step (that is
what a quantized sensor at low speed looks like: an encoder toggling between
two neighbouring counts).

``sampling_gaps`` finds the holes of a time axis (runs of missing samples of
the median step), so that resampling can refuse to invent data across a long
one (``gearsim --resample --max-gap N``) and say what it filled.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = [
    "zero_phase_lowpass",
    "auto_cutoff",
    "contact_cutoff",
    "is_held",
    "HELD_REPEAT_FRACTION",
    "derivative",
    "smooth_sign",
    "Gap",
    "sampling_gaps",
    "describe_gap",
]


def _next_pow2(n: int) -> int:
    return 1 << max(0, int(n - 1).bit_length())


def zero_phase_lowpass(x: np.ndarray, cutoff_hz: float, fs_hz: float, order: int = 4) -> np.ndarray:
    """Zero-phase low-pass of x (same unit), cut-off in Hz, sample rate fs in Hz.

    Equivalent in magnitude to forward-backward filtering with an order-`order`
    Butterworth filter: |H(f)|^2 = 1 / (1 + (f/fc)^(2*order))."""
    x = np.asarray(x, dtype=float)
    n = x.size
    if n < 3 or not (cutoff_hz > 0.0) or cutoff_hz >= 0.5 * fs_hz:
        return x.copy()
    pad = int(min(n - 1, max(16, round(3.0 * fs_hz / cutoff_hz))))
    head = 2.0 * x[0] - x[pad:0:-1]
    tail = 2.0 * x[-1] - x[-2 : -pad - 2 : -1]
    xe = np.concatenate([head, x, tail])
    nfft = _next_pow2(xe.size)
    spec = np.fft.rfft(xe, nfft)
    f = np.fft.rfftfreq(nfft, d=1.0 / fs_hz)
    spec *= 1.0 / (1.0 + (f / cutoff_hz) ** (2 * order))
    y = np.fft.irfft(spec, nfft)[: xe.size]
    return y[pad : pad + n]


def _psd(x: np.ndarray, fs_hz: float, nseg: int = 1024) -> tuple[np.ndarray, np.ndarray]:
    """Averaged periodogram (Hann window, 50 % overlap); returns f (Hz), P."""
    x = np.asarray(x, dtype=float)
    x = x - np.mean(x)
    nseg = int(min(nseg, _next_pow2(x.size) // 2 if x.size >= 64 else x.size))
    nseg = max(nseg, 16)
    if x.size < nseg:
        x = np.pad(x, (0, nseg - x.size))
    step = nseg // 2
    starts = np.arange(0, x.size - nseg + 1, step)
    # bound the cost on long records: at most 400 segments, spread evenly
    if starts.size > 400:
        starts = starts[np.linspace(0, starts.size - 1, 400).astype(int)]
    w = np.hanning(nseg)
    idx = starts[:, None] + np.arange(nseg)[None, :]
    segs = x[idx]
    segs = segs - segs.mean(axis=1, keepdims=True)
    p = np.mean(np.abs(np.fft.rfft(segs * w, axis=1)) ** 2, axis=0)
    return np.fft.rfftfreq(nseg, d=1.0 / fs_hz), p


def noise_rms(x: np.ndarray, fs_hz: float) -> float:
    """The rms of the broadband noise in a measured signal: the median
    density of its upper half band (where a rig's physics has little power)
    taken as white over the whole band, sigma^2 = median(P)/sum(w^2) for the
    Hann-windowed periodogram of _psd. 0 for a record too short to tell."""
    x = np.asarray(x, dtype=float)
    if x.size < 64 or float(np.ptp(x)) == 0.0:
        return 0.0
    f, p = _psd(x, fs_hz)
    nseg = 2 * (f.size - 1)
    w2 = float(np.sum(np.hanning(nseg) ** 2))
    upper = f >= 0.5 * f[-1]
    return float(np.sqrt(max(float(np.median(p[upper])), 0.0) / w2))


#: density above the high-band floor that still counts as signal, and the
#: upper clamp (fraction of fs): for the rigid rig, which differentiates the
#: speed, and for a backlash contact or a compliant shaft, which do not
#: (see contact_cutoff)
RIGID_SIGNAL_RATIO, RIGID_MAX_FRACTION = 30.0, 1.0 / 8.0
CONTACT_SIGNAL_RATIO, CONTACT_MAX_FRACTION = 3.0, 1.0 / 4.0


def _cutoff(x: np.ndarray, fs_hz: float, signal_ratio: float, max_fraction: float) -> float | None:
    """Twice the highest frequency whose smoothed density stands
    `signal_ratio` times above the high-band floor, clamped to
    [fs/500, max_fraction*fs]; None for a constant x."""
    x = np.asarray(x, dtype=float)
    if x.size < 64 or float(np.ptp(x)) == 0.0:
        return None
    f, p = _psd(x, fs_hz)
    upper = f >= 0.5 * f[-1]
    floor = float(np.median(p[upper]))
    lo, hi = fs_hz / 500.0, fs_hz * max_fraction
    if floor <= 0.0:
        return hi
    # light smoothing of the density over 5 bins
    ps = np.convolve(p, np.ones(5) / 5.0, mode="same")
    above = np.nonzero(ps > signal_ratio * floor)[0]
    if above.size == 0:
        return lo
    f_sig = float(f[above[-1]])
    return float(min(max(2.0 * f_sig, lo), hi))


def auto_cutoff(x: np.ndarray, fs_hz: float) -> float | None:
    """Cut-off (Hz) that separates x from its broadband noise, or None when x is
    constant. See the module docstring for the rule."""
    return _cutoff(x, fs_hz, RIGID_SIGNAL_RATIO, RIGID_MAX_FRACTION)


def contact_cutoff(x: np.ndarray, fs_hz: float) -> float | None:
    """Cut-off (Hz) for a speed that drives a spring, a backlash contact or
    a compliant base shaft: twice the highest frequency still 3x above the
    high-band floor, in [the rigid cut-off, fs/4]. The rigid rig
    differentiates the speed for the inertia torque, which multiplies the
    noise by the frequency, so it cuts where the signal is still 30x above
    the noise. A contact integrates the speed into the tooth position, a
    shaft into its twist, and the inertia behind the spring filters its own
    acceleration: only the band where an encoder's quantization noise
    (rising with frequency) outweighs the motion needs to go. The impacts
    and the shaft's ring keep their fast content: a rigid cut-off near the
    ring's frequency would take part of the ring out of the input that
    excites it."""
    rigid = auto_cutoff(x, fs_hz)
    if rigid is None:
        return None
    contact = _cutoff(x, fs_hz, CONTACT_SIGNAL_RATIO, CONTACT_MAX_FRACTION)
    return max(rigid, contact if contact is not None else rigid)


HELD_REPEAT_FRACTION = 0.5


def is_held(x: np.ndarray) -> bool:
    """True when x is a zero-order-hold staircase (see the module docstring):
    most consecutive samples repeat exactly, and fewer than half of the
    changes are the smallest step (a quantized sensor's toggling)."""
    x = np.asarray(x, dtype=float)
    if x.size < 3:
        return False
    steps = np.abs(np.diff(x))
    changes = steps[steps > 0.0]
    if changes.size == 0 or 1.0 - changes.size / steps.size < HELD_REPEAT_FRACTION:
        return False
    smallest = float(np.min(changes))
    single = np.abs(changes - smallest) <= 1e-9 * max(smallest, float(np.max(np.abs(x))))
    return float(np.mean(single)) < 0.5


def derivative(x: np.ndarray, dt: float) -> np.ndarray:
    """Central-difference derivative (one-sided at the ends), unit of x per s."""
    x = np.asarray(x, dtype=float)
    if x.size < 2:
        return np.zeros_like(x)
    return np.gradient(x, dt)


def smooth_sign(x: np.ndarray, threshold: float) -> np.ndarray:
    """tanh(4 x / threshold): the smoothed sign used by the C core's friction laws."""
    if threshold <= 0.0:
        return np.sign(x)
    return np.tanh(4.0 * np.asarray(x, dtype=float) / threshold)


class Gap(NamedTuple):
    """A hole in a time axis: ``missing`` samples of step dt lack between the
    samples at ``start`` and ``end`` (s); ``index`` is the sample before it."""

    # the field shadows tuple.index (mypy objects); it is public API, so it stays
    index: int  # type: ignore[assignment]
    start: float
    end: float
    missing: int


def sampling_gaps(time: np.ndarray, dt: float | None = None, longer_than: int = 0) -> list[Gap]:
    """The gaps of a strictly increasing time axis with more than
    ``longer_than`` missing samples of step ``dt`` (default: the median step),
    in time order. A step of k*dt misses k - 1 samples (rounded)."""
    t = np.asarray(time, dtype=float)
    if t.size < 2:
        return []
    d = np.diff(t)
    step = float(np.median(d)) if dt is None else float(dt)
    if not step > 0.0:
        return []
    missing = np.rint(d / step).astype(np.int64) - 1
    idx = np.nonzero(missing > max(0, int(longer_than)))[0]
    return [Gap(int(i), float(t[i]), float(t[i + 1]), int(missing[i])) for i in idx]


def describe_gap(gap: Gap) -> str:
    """'0.05 s (49 samples) missing after t = 1.234 s' for messages."""
    return (
        f"{gap.end - gap.start:.6g} s ({gap.missing} sample{'s' if gap.missing != 1 else ''}) "
        f"missing after t = {gap.start:.6g} s"
    )
