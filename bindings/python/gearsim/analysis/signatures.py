"""Residual signatures: the regressors that tell physical effects apart.

The drive torque residual ``r = measured - simulated`` is referred to the
driven side (follower shaft N*m, or rack N): ``r_d = r / k`` with ``k`` the
signed kinematic ratio driven speed / base speed. By power balance, any extra
force ``F`` that the drive must overcome on the driven side shows up as
``r_d = F``, whatever the gear ratio and directions. Each effect of the
contract has a signature in ``r_d`` that holds for any real rig:

==============================  ==========================================================
column                          physics
==============================  ==========================================================
``acceleration``  a             inertia error: ``dJ * a``
``speed``         v             viscous friction: ``mu * v``
``sign``          sgn(v)        Coulomb friction: ``Fc * sgn(v)`` (tanh-smoothed)
``constant``      -1            constant load offset: ``-offset`` (a load pushing along +)
``mesh``          abs(T)*sgn(v) meshing loss proportional to the transmitted torque T:
                                ``L*abs(T)*sgn(v)`` with L = 1-eta (load overruns) or
                                1/eta-1 (drive drives)
``mesh@Ti``       mesh*h_i(T)   mesh loss weighted by linear-interpolation hats of the
                                temperature: a loss that changes with temperature
==============================  ==========================================================

Load-dependent efficiency is ``tau_idle*sgn(v) + k*abs(T)*sgn(v)``: a Coulomb
part plus a part that grows with load. Backlash has no linear signature: its
evidence is residual energy concentrated right after reversals of the
transmitted torque, and a driven-speed residual whose integral over such a
window is the gap (:func:`backlash_evidence`).

Screening (:func:`screen`) regresses ``r_d`` on the columns of the parameters
the model already has (they are re-estimated when an effect is fitted) plus
the candidate's own columns, with the physical sign constraints, by bounded
linear least squares. It predicts the error after fitting, seeds the fit, and
gives the evidence: the candidate's partial correlation with the residual,
its coefficients, and the regime where its contribution is largest.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from . import modelkit as mk
from .measurement import Measurement
from .regimes import Regime, sign_changes
from .simulate import Inputs, Simulation

__all__ = [
    "Context",
    "build_context",
    "ScreenResult",
    "screen",
    "backlash_evidence",
    "temperature_hats",
]


@dataclass
class Context:
    """Everything the signatures need, computed once per baseline.

    Arrays are per sample, driven-side units (N*m and rad/s for the gear's
    follower, N and m/s for the rack) unless noted."""

    model: Any
    meas: Measurement
    inputs: Inputs
    sim: Simulation
    kin: float  # driven speed / base speed (signed)
    residual: dict[str, np.ndarray]  # measured - simulated per output (output units)
    std: dict[str, float]  # std of each measured output
    base_nrmse: dict[str, float]
    v: np.ndarray  # driven speed (simulated from the measured input)
    a: np.ndarray  # driven acceleration
    T: np.ndarray  # transmitted torque/force at the driven port (w/o viscous)
    temperature: np.ndarray  # K, measured or simulated (or proxy)
    temperature_source: str
    regimes: list[Regime]
    idx: np.ndarray  # samples used by the regressions
    columns: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def torque_output(self) -> str:
        return self.meas.spec.torque_output

    @property
    def speed_output(self) -> str:
        return self.meas.spec.speed_output

    @property
    def r_d(self) -> np.ndarray:
        return self.residual[self.torque_output] / self.kin

    @cached_property
    def nominal_torque(self) -> float:
        """A round nominal transmitted torque/force: the 90th percentile of |T|
        to two significant digits (tau_nom of a fitted load-dependent
        efficiency). Cached: every evaluation of that fit asks for it."""
        tn = float(np.percentile(np.abs(self.T), 90.0)) if self.T.size else 0.0
        if tn <= 0:
            tn = 1.0
        exp = np.floor(np.log10(tn))
        return float(np.round(tn / 10**exp, 1) * 10**exp)

    def overall_nrmse(self, torque_nrmse: float, speed_nrmse: float | None = None) -> float:
        s = self.base_nrmse[self.speed_output] if speed_nrmse is None else speed_nrmse
        return 0.5 * (torque_nrmse + s)


def _sgn(x: np.ndarray, threshold: float) -> np.ndarray:
    return np.tanh(4.0 * x / max(threshold, 1e-12))


def temperature_hats(temp: np.ndarray, breakpoints: np.ndarray) -> np.ndarray:
    """Linear-interpolation basis: column i is the weight of breakpoint i in
    interp(temp, breakpoints, values), clamped at the ends. Shape (n, len(bp))."""
    bp = np.asarray(breakpoints, dtype=float)
    eye = np.eye(bp.size)
    return np.column_stack([np.interp(temp, bp, eye[i]) for i in range(bp.size)])


def temperature_breakpoints(temp: np.ndarray) -> np.ndarray:
    lo, hi = float(np.percentile(temp, 1)), float(np.percentile(temp, 99))
    if hi - lo < 1e-6:
        hi = lo + 1.0
    return np.round(np.array([lo, 0.5 * (lo + hi), hi]), 2)


def build_context(
    model: Any,
    meas: Measurement,
    inputs: Inputs,
    sim: Simulation,
    regimes: list[Regime],
    max_rows: int = 200_000,
) -> Context:
    spec = meas.spec
    kin = mk.kinematic_ratio(model)
    residual = {o: meas[o] - sim.outputs[o] for o in spec.outputs}
    std = {o: float(np.std(meas[o])) for o in spec.outputs}
    base_nrmse = {
        o: float(np.sqrt(np.mean(residual[o] ** 2)) / std[o]) if std[o] > 0 else float("inf")
        for o in spec.outputs
    }
    sig = sim.signals
    v = sig.get("follower_speed", sim.outputs[spec.speed_output])
    if mk.block_values(model).get("backlash_enabled", False):
        v = inputs.base_speed * kin  # rigid kinematics: the signatures describe the mesh motion
    a = sig.get("follower_acceleration")
    if a is None:
        a = np.gradient(v, meas.dt)
    tau_f = sig.get("follower_port_torque")
    mu_f = mk.viscous_value(model)
    if tau_f is None:
        tau_f = -sim.outputs[spec.torque_output] / kin
    T = tau_f - mu_f * v
    if meas.has_temperature:
        temp, tsrc = meas["temperature"], "measured"
    else:
        temp = sig.get("temperature")
        tsrc = "simulated"
        if temp is None:
            temp = np.full(meas.n, float(mk.block_values(model).get("initial_temperature", 300.0)))
    n = meas.n
    step = max(1, int(np.ceil(n / max_rows)))
    idx = np.arange(0, n, step)
    ctx = Context(
        model=model,
        meas=meas,
        inputs=inputs,
        sim=sim,
        kin=kin,
        residual=residual,
        std=std,
        base_nrmse=base_nrmse,
        v=v,
        a=a,
        T=T,
        temperature=np.asarray(temp, float),
        temperature_source=tsrc,
        regimes=regimes,
        idx=idx,
    )
    rig = mk.rig_values(model)
    blk = mk.block_values(model)
    vmax = float(np.percentile(np.abs(v), 99)) or 1.0
    vth = float(rig.get("load_coulomb_speed_threshold", 1e-3))
    # smoothing of the sign: the model's threshold, but never sharper than the
    # speed resolution of the data (0.5 % of the speed range)
    sgn = _sgn(v, max(vth, 0.005 * vmax))
    mesh = np.abs(T) * sgn
    ctx.columns = {
        "acceleration": a,
        "speed": v,
        "sign": sgn,
        "constant": -np.ones(n),
        "mesh": mesh,
        "idle": _sgn(v, max(float(blk.get("speed_threshold", 0.01)), 0.005 * vmax)),
    }
    return ctx


@dataclass
class ScreenResult:
    """One bounded linear regression of the driven-side residual.

    names: the columns; coef: their fitted coefficients (deltas to the present
    values); nuisance: how many leading columns are re-estimated existing
    parameters; torque_nrmse/nrmse: predicted errors after the fit;
    explained: the fitted residual of the candidate's own columns (driven
    units, all samples); partial_r: correlation of the candidate's part with the
    residual left by the nuisance columns."""

    names: list[str]
    coef: np.ndarray
    nuisance: int
    torque_nrmse: float
    nrmse: float
    explained: np.ndarray
    partial_r: float
    r2_gain: float

    def coefficient(self, name: str) -> float:
        return float(self.coef[self.names.index(name)])


def screen(
    ctx: Context,
    nuisance: list[tuple[str, np.ndarray, tuple[float, float]]],
    own: list[tuple[str, np.ndarray, tuple[float, float]]],
) -> ScreenResult:
    """Bounded least squares of r_d on nuisance + own columns (each given as
    (name, column over all samples, (lower, upper) bound of its coefficient))."""
    from scipy.optimize import lsq_linear

    cols = nuisance + own
    idx = ctx.idx
    y = ctx.r_d[idx]
    if not cols:
        tn = ctx.base_nrmse[ctx.torque_output]
        return ScreenResult(
            [], np.zeros(0), 0, tn, ctx.overall_nrmse(tn), np.zeros(ctx.meas.n), 0.0, 0.0
        )
    X = np.column_stack([c[1][idx] for c in cols])
    scale = np.sqrt(np.mean(X * X, axis=0))
    scale[scale == 0] = 1.0
    lb = np.array([c[2][0] for c in cols]) * scale
    ub = np.array([c[2][1] for c in cols]) * scale
    Xs = X / scale
    res = lsq_linear(
        Xs, y, bounds=(lb, ub), method="bvls" if Xs.shape[1] <= 12 else "trf", lsmr_tol="auto"
    )
    beta = res.x / scale
    fitted_all = np.column_stack([c[1] for c in cols]) @ beta
    r_after = ctx.r_d - fitted_all
    tn = float(np.sqrt(np.mean((r_after * ctx.kin) ** 2)) / ctx.std[ctx.torque_output])
    nn = len(nuisance)
    own_part = (np.column_stack([c[1] for c in own]) @ beta[nn:]) if own else np.zeros(ctx.meas.n)
    # partial correlation of the own part with the residual left by the nuisance
    if nn:
        Xn = Xs[:, :nn]
        bn, *_ = np.linalg.lstsq(Xn, y, rcond=None)
        y_perp = y - Xn @ bn
    else:
        y_perp = y
    op = own_part[idx]
    if nn and np.any(op):
        bo, *_ = np.linalg.lstsq(Xs[:, :nn], op, rcond=None)
        op = op - Xs[:, :nn] @ bo
    den = float(np.linalg.norm(y_perp) * np.linalg.norm(op))
    pr = float(np.dot(y_perp, op) / den) if den > 0 else 0.0
    ss_perp = float(np.dot(y_perp, y_perp))
    r_fin = r_after[idx]
    gain = 1.0 - float(np.dot(r_fin, r_fin)) / ss_perp if ss_perp > 0 else 0.0
    return ScreenResult(
        [c[0] for c in cols], beta, nn, tn, ctx.overall_nrmse(tn), own_part, pr, gain
    )


@dataclass
class BacklashEvidence:
    """Residual concentration after reversals of the transmitted torque.

    events: sample indices of the reversals; window: samples after each;
    concentration: (share of residual energy inside the windows) / (share of
    time inside them), per output; gap_estimate: median |integral of the
    driven-speed residual| over a window, converted to pitch-line metres;
    predicted_nrmse: overall nrmse if the excess energy in the windows were
    explained."""

    events: np.ndarray
    window: int
    concentration: dict[str, float]
    time_fraction: float
    gap_estimate: float
    predicted_nrmse: float
    mask: np.ndarray

    speed_output: str = ""
    gap_range: tuple[float, float] = (0.0, 0.0)  # m: smallest and largest gap of the upper cluster

    @property
    def strength(self) -> float:
        """Concentration of the driven-speed residual: a rigid mesh cannot
        make the driven speed deviate from the kinematics, so this is the
        evidence specific to backlash (~1 without it)."""
        return float(self.concentration.get(self.speed_output, 0.0))


def backlash_evidence(ctx: Context) -> BacklashEvidence:
    """Backlash screening: where does the residual sit relative to reversals
    of the transmitted torque (and of the motion)?

    The event-locked mean of the normalised squared residual (both outputs)
    over the time since the last reversal shows a burst right after the
    reversal when teeth cross the gap and hit the other flank; the burst's end
    (where the profile falls back under 1.5x its overall level) sets the
    window. Without backlash-like physics the profile is flat and the
    concentration ~ 1."""
    meas = ctx.meas
    n = meas.n
    dt = meas.dt
    T = ctx.T
    tmax = float(np.percentile(np.abs(T), 99)) or 1.0
    ev = sign_changes(T, 0.05 * tmax)
    spd = ctx.v
    ev_v = sign_changes(spd, 0.05 * (float(np.percentile(np.abs(spd), 99)) or 1.0))
    events = np.unique(np.concatenate([ev, ev_v]))
    # merge events closer than 5 samples
    if events.size > 1:
        keep = np.concatenate([[True], np.diff(events) >= 5])
        events = events[keep]
    mask = np.zeros(n, dtype=bool)
    outputs = meas.spec.outputs
    if events.size == 0:
        tn = ctx.base_nrmse[ctx.torque_output]
        return BacklashEvidence(
            events,
            0,
            {o: 1.0 for o in outputs},
            0.0,
            0.0,
            ctx.overall_nrmse(tn),
            mask,
            ctx.speed_output,
        )
    norm = {o: ctx.residual[o] ** 2 / (ctx.std[o] ** 2 or 1.0) for o in outputs}
    e2 = norm[outputs[0]] + norm[outputs[1]]
    level = float(np.mean(e2))
    gaps = np.diff(np.concatenate([events, [n]]))
    wmax = int(max(5, min(round(0.25 / dt), np.median(gaps))))
    prof = np.zeros(wmax)
    cnt = np.zeros(wmax)
    for e in events:
        seg = e2[e : e + wmax]
        prof[: seg.size] += seg
        cnt[: seg.size] += 1
    prof = prof / np.maximum(cnt, 1)
    k = np.convolve(prof, np.ones(3) / 3.0, mode="same")
    peak = int(np.argmax(k))
    window = 5
    if k[peak] > 2.0 * level:
        below = np.nonzero(k[peak:] < 1.5 * level)[0]
        window = peak + (int(below[0]) if below.size else wmax - peak)
    window = int(min(max(window, 5), wmax))
    for e in events:
        mask[e : e + window] = True
    frac = float(mask.mean())
    conc = {}
    after = {}
    for o in outputs:
        r = ctx.residual[o]
        tot = float(np.sum(r * r))
        inside = float(np.sum(r[mask] ** 2))
        conc[o] = (inside / tot) / frac if tot > 0 and frac > 0 else 1.0
        if mask.any() and float(np.sqrt(inside / mask.sum())) < 0.005 * (ctx.std[o] or 1.0):
            # the output matches within 0.5 % of its spread even right after
            # the reversals: no evidence in it
            conc[o] = 0.0
        out_level = float(np.mean(r[~mask] ** 2)) if (~mask).any() else 0.0
        excess = max(0.0, inside - out_level * mask.sum())
        e_after = max(0.0, tot - excess)
        after[o] = float(np.sqrt(e_after / n)) / ctx.std[o] if ctx.std[o] > 0 else 0.0
    # gap: integral of the driven-speed residual over each window
    rs = ctx.residual[ctx.speed_output]
    # reversals where the teeth crossed the gap integrate to ~b, the others
    # (motion reversals under a load that keeps the contact) to ~0: take the
    # median of the upper cluster
    disp = np.array([abs(float(np.sum(rs[e : e + window]) * dt)) for e in events])
    gap = 0.0
    gap_range = (0.0, 0.0)
    if disp.size:
        radius = mk.driven_radius(ctx.model)
        upper = disp[disp >= 0.5 * np.percentile(disp, 90)]
        gap = float(np.median(upper)) * radius
        gap_range = (float(upper.min()) * radius, float(upper.max()) * radius)
    pred = ctx.overall_nrmse(after[ctx.torque_output], after[ctx.speed_output])
    return BacklashEvidence(
        events, window, conc, frac, gap, pred, mask, ctx.speed_output, gap_range
    )


# ---------------------------------------------------------------- signatures of the effects beyond the seed blocks
#
# The four effects beyond the seed blocks have signatures that are not (only)
# columns of r_d; these functions compute what a person checks, on plain
# arrays, so that each can be tested on a hand-made residual.


def parabolic_peak(y: np.ndarray, i: int) -> tuple[float, float]:
    """Sub-sample position and height of the extremum at index i of y: the
    vertex of the parabola through y[i-1], y[i], y[i+1] (i itself at an end)."""
    if i <= 0 or i >= y.size - 1:
        return float(i), float(y[i])
    a, b, c = float(y[i - 1]), float(y[i]), float(y[i + 1])
    den = a - 2.0 * b + c
    if den == 0.0:
        return float(i), b
    off = 0.5 * (a - c) / den
    return i + off, b - 0.25 * (a - c) * off


@dataclass
class DelaySignature:
    """Cross-correlation of the torque residual with the derivative of the
    simulated torque.

    lags_s: the lags (s); correlation: the normalised cross-correlation
    sum r(t) y'(t - lag) / (|r| |y'|) at each lag; peak_lag_s: where its
    magnitude peaks (sub-sample, parabolic interpolation); peak_r: its value
    there; gain_s: the regression coefficient of r on y'(t - peak_lag).
    A measured torque that lags the model by d gives r(t) = y(t - d) - y(t)
    ~ -d y'(t - d/2): a peak at d/2 with gain -d, so delay_s = -gain_s."""

    lags_s: np.ndarray
    correlation: np.ndarray
    peak_lag_s: float
    peak_r: float
    gain_s: float

    @property
    def delay_s(self) -> float:
        return -self.gain_s


def _xcorr(r: np.ndarray, d: np.ndarray, max_lag: int) -> np.ndarray:
    """c[L + max_lag] = sum_k r[k] d[k - L] for L in -max_lag..max_lag (FFT)."""
    n = r.size
    size = 1 << int(np.ceil(np.log2(2 * n)))
    full = np.fft.irfft(np.fft.rfft(r, size) * np.conj(np.fft.rfft(d, size)), size)
    return np.concatenate([full[size - max_lag :], full[: max_lag + 1]])


def delay_signature(
    residual: np.ndarray, output: np.ndarray, dt: float, max_lag_s: float = 0.1
) -> DelaySignature:
    """The cross-correlation lag between a residual and the derivative of an
    output (see DelaySignature). max_lag_s is cut to a quarter of the record."""
    r = np.asarray(residual, dtype=float) - np.mean(residual)
    d = np.gradient(np.asarray(output, dtype=float), dt)
    d = d - d.mean()
    m = int(max(1, min(round(max_lag_s / dt), r.size // 4)))
    den = float(np.linalg.norm(r) * np.linalg.norm(d))
    c = _xcorr(r, d, m) / den if den > 0 else np.zeros(2 * m + 1)
    lags = np.arange(-m, m + 1) * dt
    i = int(np.argmax(np.abs(c)))
    pos, height = parabolic_peak(c, i)
    peak_lag = (pos - m) * dt
    from .simulate import delayed

    shifted = delayed(d, peak_lag / dt)
    ss = float(np.dot(shifted, shifted))
    gain = float(np.dot(r, shifted) / ss) if ss > 0 else 0.0
    return DelaySignature(lags, c, float(peak_lag), float(height), gain)


@dataclass
class SpeedProfile:
    """The driven-side residual against |speed|: r_d * sgn(v) averaged in
    log-spaced bins of |v| (a friction level per speed).

    speed: bin centres (driven units); level: mean r_d*sgn(v) per bin;
    count: samples per bin; coulomb / excess / stribeck_speed: the curve
    level = coulomb + excess*exp(-(speed/stribeck_speed)^2) fitted to the
    bins (weighted by their counts)."""

    speed: np.ndarray
    level: np.ndarray
    count: np.ndarray
    coulomb: float
    excess: float
    stribeck_speed: float


def speed_profile(r_d: np.ndarray, v: np.ndarray, bins: int = 30) -> SpeedProfile:
    """Binned r_d*sgn(v) against |v| and the Stribeck curve that fits it
    best (grid over the Stribeck speed, linear least squares for the two
    levels at each)."""
    u = np.abs(np.asarray(v, dtype=float))
    y = np.asarray(r_d, dtype=float) * np.sign(v)
    vmax = float(np.percentile(u, 99)) if u.size else 0.0
    if vmax <= 0:
        return SpeedProfile(np.zeros(0), np.zeros(0), np.zeros(0), 0.0, 0.0, 0.0)
    edges = np.geomspace(2e-3 * vmax, vmax, bins + 1)
    which = np.digitize(u, edges) - 1
    ok = (which >= 0) & (which < bins)
    count = np.bincount(which[ok], minlength=bins).astype(float)
    total = np.bincount(which[ok], weights=y[ok], minlength=bins)
    keep = count >= 5
    centre = np.sqrt(edges[:-1] * edges[1:])[keep]
    level = total[keep] / count[keep]
    w = np.sqrt(count[keep])
    best = (np.inf, 0.0, 0.0, 0.0)
    for vs in np.geomspace(edges[0], 0.5 * vmax, 60):
        X = np.column_stack([np.ones_like(centre), np.exp(-((centre / vs) ** 2))])
        coef, *_ = np.linalg.lstsq(X * w[:, None], level * w, rcond=None)
        if coef[1] < 0:  # a friction that rises towards rest only
            continue
        sse = float(np.sum((w * (level - X @ coef)) ** 2))
        if sse < best[0]:
            best = (sse, float(coef[0]), float(coef[1]), float(vs))
    return SpeedProfile(centre, level, count[keep], best[1], best[2], best[3])


@dataclass
class Resonance:
    """The residual's power spectrum (Welch) and its strongest peak.

    freq_hz, psd: the spectrum; peak_hz: the peak (parabolic interpolation
    on log power); prominence: peak power / median power of the band
    searched; damping_ratio: half the relative -3 dB width of the peak
    (NaN when the peak is not resolved); band_share: share of the
    residual's power within the peak's -3 dB band widened 2x."""

    freq_hz: np.ndarray
    psd: np.ndarray
    peak_hz: float
    prominence: float
    damping_ratio: float
    band_share: float


def resonance(residual: np.ndarray, dt: float, min_hz: float | None = None) -> Resonance:
    """Spectrum of a residual and its strongest peak above min_hz (default:
    four frequency bins) and below 0.4/dt."""
    from scipy.signal import welch

    r = np.asarray(residual, dtype=float)
    n = r.size
    nper = int(min(n, max(256, 2 ** int(np.log2(max(n // 8, 2))))))
    f, p = welch(r - r.mean(), fs=1.0 / dt, nperseg=nper, detrend="linear")
    lo = 4.0 * f[1] if min_hz is None else max(min_hz, f[1])
    band = (f >= lo) & (f <= 0.4 / dt)
    if not band.any() or not np.any(p[band] > 0):
        return Resonance(f, p, float("nan"), 0.0, float("nan"), 0.0)
    idx = np.nonzero(band)[0]
    i = int(idx[np.argmax(p[idx])])
    logp = np.log(np.maximum(p, 1e-300))
    pos, _ = parabolic_peak(logp, i)
    df = f[1] - f[0]
    peak_hz = float(f[0] + pos * df)
    # prominence against the local floor: the median power over an octave on
    # each side, the peak's own bins left out (a residual's broad low-frequency
    # content is no resonance)
    local = (f >= 0.5 * f[i]) & (f <= 2.0 * f[i]) & (np.abs(f - f[i]) > 3.0 * (f[1] - f[0]))
    floor = np.median(p[local]) if local.any() else np.median(p[idx])
    prominence = float(p[i] / max(floor, 1e-300))
    # -3 dB width: walk down each side to half the peak power
    half = 0.5 * p[i]
    left = i
    while left > 0 and p[left] > half:
        left -= 1
    right = i
    while right < p.size - 1 and p[right] > half:
        right += 1
    width = (right - left) * df
    zeta = float(0.5 * width / peak_hz) if right - left > 2 and peak_hz > 0 else float("nan")
    wide = (f >= peak_hz - width) & (f <= peak_hz + width)
    share = float(p[wide].sum() / p.sum()) if p.sum() > 0 else 0.0
    return Resonance(f, p, peak_hz, prominence, zeta, share)


@dataclass
class Harmonic:
    """One harmonic of a residual against an angle: residual ~
    amplitude*cos(order*theta + phase); std_error: of the amplitude."""

    order: float
    amplitude: float
    phase: float
    std_error: float


def angle_harmonics(
    residual: np.ndarray, theta: np.ndarray, orders: tuple[float, ...]
) -> list[Harmonic]:
    """Harmonic regression of a residual on cos/sin(order*theta) for each
    order (plus a constant), by least squares. A cos(k theta + phi) =
    A cos(phi) cos(k theta) - A sin(phi) sin(k theta). The standard errors
    use the effective sample count of the left-over residual (lag-1
    autocorrelation), as the score does."""
    from .scoring import effective_samples, lag1_autocorrelation

    r = np.asarray(residual, dtype=float)
    th = np.asarray(theta, dtype=float)
    cols = [np.ones_like(th)]
    for k in orders:
        cols += [np.cos(k * th), np.sin(k * th)]
    X = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(X, r, rcond=None)
    left = r - X @ coef
    n_eff = effective_samples(r.size, lag1_autocorrelation(left))
    sigma = float(np.std(left))
    out = []
    for j, k in enumerate(orders):
        a, b = float(coef[1 + 2 * j]), float(coef[2 + 2 * j])
        amp = float(np.hypot(a, b))
        # each of a, b has a std of ~ sigma*sqrt(2/n) for a full-cycle cover
        out.append(Harmonic(float(k), amp, float(np.arctan2(-b, a)), sigma * np.sqrt(2.0 / n_eff)))
    return out


def base_angle(speed: np.ndarray, dt: float) -> np.ndarray:
    """The base-shaft angle (rad) at the middle of each step of a rig that
    starts at angle 0 and holds each speed sample for one step (the rig's
    evaluation angle of the ripple, docs/physics.md 11.5)."""
    w = np.asarray(speed, dtype=float)
    return dt * (np.cumsum(w) - 0.5 * w)
