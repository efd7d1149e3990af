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
part plus a part that grows with load. The signatures that are not columns of
``r_d`` (backlash, the delay, the Stribeck profile, the resonance, the ripple's
harmonics) live with their effect in gearsim.analysis.effects.

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
from .regimes import Regime
from .simulate import Inputs, Simulation

__all__ = [
    "Context",
    "build_context",
    "ScreenResult",
    "screen",
    "parabolic_peak",
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
    speed_resolution: float = 0.0  # driven-speed units: SPEED_RESOLUTION of the robust maximum

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


#: the driven speed a record resolves, as a fraction of its robust maximum: a
#: friction reversing over a narrower band reverses where input noise and
#: quantization put the zero crossing
SPEED_RESOLUTION = 0.005


def _sgn(x: np.ndarray, threshold: float) -> np.ndarray:
    return np.tanh(4.0 * x / max(threshold, 1e-12))


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
        simulated = sig.get("temperature")
        tsrc = "simulated"
        if simulated is not None:
            temp = simulated
        else:
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
    ctx.speed_resolution = SPEED_RESOLUTION * vmax
    vth = float(rig.get("load_coulomb_speed_threshold", 1e-3))
    # smoothing of the sign: the model's threshold, but never sharper than the
    # speed resolution of the data (0.5 % of the speed range)
    sgn = _sgn(v, max(vth, ctx.speed_resolution))
    mesh = np.abs(T) * sgn
    ctx.columns = {
        "acceleration": a,
        "speed": v,
        "sign": sgn,
        "constant": -np.ones(n),
        "mesh": mesh,
        "idle": _sgn(v, max(float(blk.get("speed_threshold", 0.01)), ctx.speed_resolution)),
    }
    return ctx


@dataclass(frozen=True)
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


# ---------------------------------------------------------------- shared by the effects' signatures


def parabolic_peak(y: np.ndarray, i: int) -> tuple[float, float]:
    """Sub-sample position and height of the extremum at index i of y: the
    vertex of the parabola through y[i-1], y[i], y[i+1] (i itself at an end)."""
    if i <= 0 or i >= y.size - 1:
        return float(i), float(y[i])
    a, b, c = float(y[i - 1]), float(y[i]), float(y[i + 1])
    den = a - 2.0 * b + c
    if den == 0.0:
        return float(i), b
    # within half a sample of i: at a local extremum the vertex is there; an
    # i that is not one (the edge of a searched band) must not send the
    # vertex off the grid (a peak above the Nyquist frequency)
    off = min(max(0.5 * (a - c) / den, -0.5), 0.5)
    return i + off, b - 0.25 * (a - c) * off
