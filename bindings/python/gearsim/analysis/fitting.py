"""Add one effect to a model and estimate its parameters on the C simulation.

``fit_effect`` seeds the effect's parameters from the residual screening
(gearsim.analysis.signatures), re-estimates together the model parameters that
trade off against them (gearsim.analysis.effects.coestimated), and minimises

    sum over outputs o of sum_k ((measured_o[k] - simulated_o[k]) / std(measured_o))^2

with ``scipy.optimize.least_squares`` (trust region reflective, bounds), each
residual evaluation being one open-loop batch run of the C rig. Only outputs
that depend on the parameters enter (the driven speed of a rigid mesh is pure
kinematics). For speed, residuals are evaluated on every k-th sample when the
record is long, and effects whose simulation is costly (backlash contact) are
fitted on the first ``max_samples`` samples; the errors before and after are
always reported on the whole record.

Uncertainty: standard deviations from the Jacobian at the solution,
``cov = s^2 (J^T J)^-1`` with ``s^2 = RSS/(m - p)``. Residuals of real rigs are
correlated in time, so these are lower bounds; use them to compare parameters,
not as confidence intervals. A parameter is reported as not identifiable when
it ends at a bound or correlates with another with |r| > 0.95.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import modelkit as mk
from .effects import Effect, FitParam, build_changes, coestimated, get_effect, nuisance_columns
from .measurement import Measurement
from .metrics import OutputMetrics, output_metrics
from .signatures import Context, ScreenResult, backlash_evidence, screen
from .simulate import simulate_outputs

__all__ = ["FitResult", "fit_effect", "screen_effect", "CORRELATION_LIMIT"]

CORRELATION_LIMIT = 0.95
MAX_RESIDUAL_POINTS = 40_000
BACKLASH_MAX_SAMPLES = 20_000


@dataclass
class FitResult:
    """Outcome of adding one effect.

    parameters: the effect's parameters as the model file holds them;
    fitted: one dict per free parameter (name, value, std, lower, upper,
    role "effect"/"coestimated", before, at_bound); correlation: matrix over
    `fitted`; warnings: identifiability and convergence notes."""

    effect: str
    model: Any
    nrmse_before: float
    nrmse_after: float
    outputs_before: dict[str, OutputMetrics]
    outputs_after: dict[str, OutputMetrics]
    parameters: dict[str, Any]
    fitted: list[dict]
    correlation: np.ndarray
    warnings: list[str]
    evaluations: int
    seconds: float
    fit_samples: int
    notes: list[str] = field(default_factory=list)

    @property
    def coestimated(self) -> list[str]:
        return [f["name"] for f in self.fitted if f["role"] == "coestimated"]

    def to_json(self) -> dict:
        return {
            "effect": self.effect,
            "nrmse_before": self.nrmse_before,
            "nrmse_after": self.nrmse_after,
            "parameters": self.parameters,
            "uncertainty": {f["name"]: f["std"] for f in self.fitted if f["role"] == "effect"},
            "coestimated": {
                f["name"]: {"before": f["before"], "after": f["value"], "std": f["std"]}
                for f in self.fitted
                if f["role"] == "coestimated"
            },
            "outputs_before": {k: v.to_dict() for k, v in self.outputs_before.items()},
            "outputs_after": {k: v.to_dict() for k, v in self.outputs_after.items()},
            "correlation": {
                "parameters": [f["name"] for f in self.fitted],
                "matrix": self.correlation.tolist(),
            },
            "warnings": list(self.warnings),
            "notes": list(self.notes),
            "evaluations": self.evaluations,
            "fit_samples": self.fit_samples,
            "seconds": self.seconds,
        }


def screen_effect(ctx: Context, effect: Effect) -> ScreenResult | Any:
    """Screening of one effect on the baseline residual (seeds and evidence).
    For backlash, its BacklashEvidence."""
    if effect.name == "backlash":
        return backlash_evidence(ctx)
    return screen(ctx, nuisance_columns(ctx, effect), effect.columns(ctx))


def _metrics(
    meas: Measurement, outs: dict[str, np.ndarray]
) -> tuple[dict[str, OutputMetrics], float]:
    m = {o: output_metrics(meas[o], outs[o], meas.time) for o in meas.spec.outputs}
    return m, float(np.mean([v.nrmse for v in m.values()]))


def fit_effect(
    ctx: Context,
    effect_name: str,
    *,
    screen_result: Any = None,
    max_samples: int | None = None,
    max_nfev: int | None = None,
    quick: bool = False,
    progress: Callable[[str], None] | None = None,
) -> FitResult:
    """Add effect_name to ctx.model, fit it with the co-estimated parameters,
    and report errors on the whole record (see the module docstring).

    ctx: the baseline context (gearsim.analysis.signatures.build_context);
    screen_result: a previous screen_effect() of this effect (else computed);
    max_samples: fit on the first max_samples samples only (default: all for
    rigid meshes, 20 000 when the effect or model has backlash); quick: leave
    secondary parameters (contact stiffness and damping) at their present
    values (diagnose uses this)."""
    from scipy.optimize import least_squares

    from ..errors import GearsimError

    t_start = time.perf_counter()
    model = ctx.model
    meas = ctx.meas
    effect = get_effect(effect_name, model)
    if screen_result is None:
        screen_result = screen_effect(ctx, effect)
    params: list[FitParam] = effect.parameters(ctx, screen_result) + coestimated(
        ctx, effect, screen_result
    )
    if quick:
        params = [p for p in params if not p.optional]
    names = [p.name for p in params]
    notes: list[str] = []

    backlash_after = effect.name == "backlash" or bool(
        mk.block_values(model).get("backlash_enabled", False)
    )
    n = meas.n
    if max_samples is None:
        max_samples = BACKLASH_MAX_SAMPLES if backlash_after else n
    n_fit = int(min(n, max(max_samples, 200)))
    if n_fit < n:
        meas_fit = meas.slice(0, n_fit)
        inputs_fit = ctx.inputs.slice(0, n_fit)
        notes.append(f"fitted on the first {n_fit} of {n} samples ({n_fit * meas.dt:.3g} s)")
    else:
        meas_fit, inputs_fit = meas, ctx.inputs
    outputs = [meas.spec.torque_output] + ([meas.spec.speed_output] if backlash_after else [])
    stride = max(1, int(np.ceil(n_fit * len(outputs) / MAX_RESIDUAL_POINTS)))
    sel = np.arange(0, n_fit, stride)
    y = {o: meas_fit[o][sel] for o in outputs}
    w = {o: 1.0 / ctx.std[o] if ctx.std[o] > 0 else 1.0 for o in outputs}
    m_res = sel.size * len(outputs)
    penalty = np.full(m_res, 1e3)
    evals = [0]

    def model_for(x: np.ndarray) -> Any:
        values = dict(zip(names, (float(v) for v in x), strict=True))
        block, rig = build_changes(ctx, effect, values)
        return mk.changed(model, block, rig)

    def fun(x: np.ndarray) -> np.ndarray:
        evals[0] += 1
        try:
            mdl = model_for(x)
        except GearsimError:
            return penalty
        outs = simulate_outputs(mdl, meas_fit, inputs_fit)
        r = np.concatenate([(y[o] - outs[o][sel]) * w[o] for o in outputs])
        if not np.all(np.isfinite(r)):
            return penalty
        return r

    x0 = np.array([p.clipped_x0() for p in params])
    for i, p in enumerate(params):
        if p.grid:
            # coarse search along a parameter whose cost is not smooth (contact)
            best = (float(np.sum(fun(x0) ** 2)), x0[i])
            for mult in p.grid:
                if mult == 1.0:
                    continue
                trial = x0.copy()
                trial[i] = min(max(p.x0 * mult, p.lower), p.upper)
                c = float(np.sum(fun(trial) ** 2))
                if c < best[0]:
                    best = (c, trial[i])
            params[i].x0 = float(best[1])
            x0[i] = params[i].clipped_x0()
    lb = np.array([p.lower for p in params])
    ub = np.array([p.upper for p in params])
    xs = np.array(
        [
            abs(v) if v != 0 else (0.01 * (hi - lo) if np.isfinite(hi - lo) else 1.0)
            for v, lo, hi in zip(x0, lb, ub, strict=True)
        ]
    )
    xs[xs <= 0] = 1.0
    diff_step = 1e-3 if effect.name == "backlash" else 1e-6
    if progress:
        progress(
            f"fit {effect.name}: {len(params)} parameters ({', '.join(names)}) on {n_fit} samples"
        )
    res = least_squares(
        fun,
        x0,
        bounds=(lb, ub),
        x_scale=xs,
        method="trf",
        diff_step=diff_step,
        max_nfev=max_nfev or 30 * (len(params) + 1),
        xtol=1e-8,
        ftol=1e-8,
    )
    x = res.x
    # uncertainty and identifiability
    warnings: list[str] = []
    J = res.jac
    dof = max(m_res - len(params), 1)
    s2 = float(2.0 * res.cost / dof)
    std = np.full(len(params), np.nan)
    corr = np.full((len(params), len(params)), np.nan)
    try:
        JtJ = J.T @ J
        cov = np.linalg.pinv(JtJ) * s2
        d = np.sqrt(np.clip(np.diag(cov), 0, None))
        std = d
        with np.errstate(invalid="ignore", divide="ignore"):
            corr = cov / np.outer(d, d)
        sv = np.linalg.svd(J * xs, compute_uv=False)
        if sv.size and sv[-1] <= 1e-10 * sv[0]:
            warnings.append(
                "the Jacobian is singular: some parameters cannot be told apart by this record"
            )
    except np.linalg.LinAlgError:  # pragma: no cover
        warnings.append("could not compute parameter uncertainties")
    fitted = []
    active = getattr(res, "active_mask", np.zeros(len(params), dtype=int))
    for i, p in enumerate(params):

        def near(bound: float, xi: float = float(x[i]), si: float = float(xs[i])) -> bool:
            return bool(np.isfinite(bound) and abs(xi - bound) <= 1e-3 * max(abs(bound), si))

        at_lo = active[i] < 0 or near(p.lower)
        at_hi = active[i] > 0 or near(p.upper)
        at_bound = "lower" if at_lo else ("upper" if at_hi else None)
        if at_bound:
            warnings.append(
                f"{p.name} = {x[i]:.6g} stays at its {at_bound} bound "
                f"({p.lower if at_lo else p.upper:.6g}): not identifiable from this record"
            )
        fitted.append(
            {
                "name": p.name,
                "value": float(x[i]),
                "std": float(std[i]),
                "lower": float(p.lower),
                "upper": float(p.upper),
                "role": p.role,
                "before": p.before,
                "unit": p.unit,
                "at_bound": at_bound,
            }
        )
    for i in range(len(params)):
        for j in range(i + 1, len(params)):
            c = corr[i, j]
            if np.isfinite(c) and abs(c) > CORRELATION_LIMIT:
                warnings.append(
                    f"{names[i]} and {names[j]} are strongly correlated (r = {c:+.3f}): "
                    f"the record cannot tell them apart"
                )
    if not res.success:
        warnings.append(f"the optimiser stopped without convergence: {res.message}")
    if effect.name == "viscous_friction" and mk.block_name(model) == "simple_gear":
        notes.append(
            "base and follower viscous coefficients act alike on a rigid, speed-driven mesh; "
            "the fit puts the whole viscous loss on the follower side (viscous_coefficients[1])"
        )

    new_model = model_for(x)
    # errors on the whole record
    outs_before = {o: ctx.meas[o] - ctx.residual[o] for o in meas.spec.outputs}
    mb, nb = _metrics(meas, outs_before)
    outs_after = simulate_outputs(new_model, meas, ctx.inputs)
    ma, na = _metrics(meas, outs_after)
    if na >= nb:
        warnings.append(
            f"adding {effect.name} did not lower the error ({nb:.4g} -> {na:.4g}): the record "
            f"shows no sign of it"
        )
    return FitResult(
        effect=effect.name,
        model=new_model,
        nrmse_before=nb,
        nrmse_after=na,
        outputs_before=mb,
        outputs_after=ma,
        parameters=effect.report(new_model),
        fitted=fitted,
        correlation=corr,
        warnings=warnings,
        evaluations=evals[0],
        seconds=time.perf_counter() - t_start,
        fit_samples=n_fit,
        notes=notes,
    )
