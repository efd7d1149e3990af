"""Add one effect to a model and estimate its parameters on the C simulation.

``fit_effect`` seeds the effect's parameters from the residual screening
(gearsim.analysis.signatures), re-estimates together the model parameters that
trade off against them (gearsim.analysis.effects.coestimated), and minimises

    sum over outputs o of sum_k ((measured_o[k] - simulated_o[k]) / std(measured_o))^2

over the *estimation* samples (gearsim.analysis.scoring.split_record: the
held-out validation blocks never enter the fit) with
``scipy.optimize.least_squares`` (trust region reflective, bounds), each
residual evaluation being one open-loop batch run of the C rig over the whole
record. Only outputs that depend on the parameters enter (the driven speed of
a rigid mesh is pure kinematics). For speed, residuals are evaluated on every
k-th estimation sample when the record is long, and effects whose simulation
is costly (backlash contact) are fitted on the first ``max_samples`` samples;
errors are always reported on the whole record and on the validation blocks.

Non-smooth costs: a parameter with a ``grid`` is first searched on multiples
of its seed (cost only); a parameter with ``starts`` (the backlash gap) gets
a short probe of those parameters alone from each start, and the full fit
from the best probe (multi-start: a single start from a short gap can end in
a local minimum).

Uncertainty: standard deviations from the Jacobian at the solution,
``cov = s^2 (J^T J)^-1`` with ``s^2 = RSS/(m - p)``. Residuals of real rigs are
correlated in time, so these are lower bounds. Identifiability warnings:
gearsim.analysis.identifiability.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import modelkit as mk
from . import scoring
from .effects import EFFECTS, Effect, FitParam, Screening, build_changes, coestimated, get_effect
from .identifiability import correlation_matrix, parameter_warnings, warning
from .measurement import Measurement
from .metrics import OutputMetrics, output_metrics
from .signatures import Context
from .simulate import simulate_outputs

__all__ = ["FitResult", "fit_effect", "screen_effect", "validation_nrmse"]

MAX_RESIDUAL_POINTS = 40_000
COSTLY_MAX_SAMPLES = 20_000
PENALTY = 1e3
START_NFEV = 8


@dataclass
class FitResult:
    """Outcome of adding one effect.

    nrmse_before/after: whole record; validation_nrmse_before/after: on the
    held-out blocks (the whole record when validation is off); parameters:
    the effect's parameters as the model file holds them; fitted: one dict
    per free parameter (name, value, std, lower, upper, role
    "effect"/"coestimated", before, unit, at_bound); correlation: matrix over
    `fitted`; warnings: identifiability and convergence warnings (dicts with
    kind and text); judged_mse: per output, mean squared normalised
    residual on the validation blocks after the fit (the whole record with
    validation off); score: the score of gearsim.analysis.scoring with this
    fit's own effective sample count."""

    effect: str
    model: Any
    nrmse_before: float
    nrmse_after: float
    outputs_before: dict[str, OutputMetrics]
    outputs_after: dict[str, OutputMetrics]
    parameters: dict[str, Any]
    fitted: list[dict]
    correlation: np.ndarray
    warnings: list[dict]
    evaluations: int
    seconds: float
    fit_samples: int
    validation: scoring.ValidationSplit
    validation_nrmse_before: float
    validation_nrmse_after: float
    judged_mse: dict[str, float]
    residual_after: dict[str, np.ndarray]
    complete: bool = True
    notes: list[str] = field(default_factory=list)

    @property
    def coestimated(self) -> list[str]:
        return [f["name"] for f in self.fitted if f["role"] == "coestimated"]

    @property
    def n_parameters(self) -> int:
        return len(self.fitted)

    @property
    def score(self) -> float:
        judged = self.validation.validation
        n_eff = [
            scoring.effective_samples(int(judged.sum()), scoring.lag1_autocorrelation(r[judged]))
            for r in self.residual_after.values()
        ]
        return scoring.bic_score(list(self.judged_mse.values()), n_eff, self.n_parameters)

    def to_json(self) -> dict:
        return {
            "effect": self.effect,
            "nrmse_before": self.nrmse_before,
            "nrmse_after": self.nrmse_after,
            "parameters": self.parameters,
            "score": self.score,
            "validation": {
                **self.validation.to_json(),
                "nrmse_before": self.validation_nrmse_before,
                "nrmse_after": self.validation_nrmse_after,
            },
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
            "warnings": [dict(w) for w in self.warnings],
            "notes": list(self.notes),
            "evaluations": self.evaluations,
            "fit_samples": self.fit_samples,
            "seconds": self.seconds,
        }


def screen_effect(ctx: Context, effect: Effect) -> Screening:
    """Screening of one effect on the baseline residual (seeds and evidence)."""
    return effect.screen(ctx)


def validation_nrmse(
    meas: Measurement, simulated: dict[str, np.ndarray], mask: np.ndarray
) -> float:
    """Mean over outputs of rms(measured - simulated on mask) / std(measured, whole record)."""
    vals = []
    for o in meas.spec.outputs:
        s = float(np.std(meas[o]))
        e = float(np.sqrt(np.mean((meas[o][mask] - simulated[o][mask]) ** 2)))
        vals.append(e / s if s > 0 else (0.0 if e == 0 else float("inf")))
    return float(np.mean(vals))


def _metrics(
    meas: Measurement, outs: dict[str, np.ndarray]
) -> tuple[dict[str, OutputMetrics], float]:
    m = {o: output_metrics(meas[o], outs[o], meas.time) for o in meas.spec.outputs}
    return m, float(np.mean([v.nrmse for v in m.values()]))


# ---------------------------------------------------------------- the problem


@dataclass
class _Problem:
    """The least-squares problem of one fit: which samples and outputs, their
    weights, and how a parameter vector becomes a model."""

    ctx: Context
    effect: Effect
    params: list[FitParam]
    meas_fit: Measurement
    inputs_fit: Any
    outputs: list[str]
    sel: np.ndarray  # estimation samples used (indices into the fitted part)
    weights: dict[str, float]
    evaluations: int = 0

    @property
    def names(self) -> list[str]:
        return [p.name for p in self.params]

    def model_for(self, x: np.ndarray) -> Any:
        values = dict(zip(self.names, (float(v) for v in x), strict=True))
        block, rig, analysis = build_changes(self.ctx, self.effect, values)
        return mk.changed(self.ctx.model, block, rig, analysis)

    def residuals(self, x: np.ndarray) -> np.ndarray:
        from ..errors import GearsimError

        self.evaluations += 1
        m_res = self.sel.size * len(self.outputs)
        try:
            mdl = self.model_for(x)
        except GearsimError:  # a value the C core refuses: a large, flat cost
            return np.full(m_res, PENALTY)
        outs = simulate_outputs(mdl, self.meas_fit, self.inputs_fit)
        r = np.concatenate(
            [
                (self.meas_fit[o][self.sel] - outs[o][self.sel]) * self.weights[o]
                for o in self.outputs
            ]
        )
        return r if np.all(np.isfinite(r)) else np.full(m_res, PENALTY)

    def cost(self, x: np.ndarray) -> float:
        return float(np.sum(self.residuals(x) ** 2))


def _is_costly(model: Any, effect: Effect) -> bool:
    return effect.costly or any(e.costly and e.present(model) for e in EFFECTS.values())


def _problem(
    ctx: Context,
    effect: Effect,
    params: list[FitParam],
    split: scoring.ValidationSplit,
    max_samples: int | None,
    notes: list[str],
) -> _Problem:
    meas, n = ctx.meas, ctx.meas.n
    costly = _is_costly(ctx.model, effect)
    if max_samples is None:
        max_samples = COSTLY_MAX_SAMPLES if costly else n
    n_fit = int(min(n, max(max_samples, 200)))
    meas_fit, inputs_fit = meas, ctx.inputs
    if n_fit < n:
        meas_fit, inputs_fit = meas.slice(0, n_fit), ctx.inputs.slice(0, n_fit)
        notes.append(f"fitted on the first {n_fit} of {n} samples ({n_fit * meas.dt:.3g} s)")
    outputs = [meas.spec.torque_output] + ([meas.spec.speed_output] if costly else [])
    est = np.nonzero(split.estimation[:n_fit])[0]
    stride = max(1, int(np.ceil(est.size * len(outputs) / MAX_RESIDUAL_POINTS)))
    weights = {o: 1.0 / ctx.std[o] if ctx.std[o] > 0 else 1.0 for o in outputs}
    return _Problem(ctx, effect, params, meas_fit, inputs_fit, outputs, est[::stride], weights)


# ---------------------------------------------------------------- the search


def _coarse_grid(prob: _Problem, x0: np.ndarray) -> np.ndarray:
    """Line search over each parameter's grid multipliers (cost only)."""
    x0 = x0.copy()
    for i, p in enumerate(prob.params):
        if not p.grid:
            continue
        best_cost, best = prob.cost(x0), x0[i]
        for mult in p.grid:
            trial = x0.copy()
            trial[i] = p.clip(p.x0 * mult)
            c = prob.cost(trial)
            if c < best_cost:
                best_cost, best = c, trial[i]
        x0[i] = best
    return x0


def _scales(prob: _Problem, x0: np.ndarray) -> np.ndarray:
    xs = []
    for v, p in zip(x0, prob.params, strict=True):
        span = p.upper - p.lower
        xs.append(abs(v) if v != 0 else (0.01 * span if np.isfinite(span) else 1.0))
    out = np.array(xs)
    out[out <= 0] = 1.0
    return out


def _local_fit(prob: _Problem, x0: np.ndarray, max_nfev: int):
    from scipy.optimize import least_squares

    return least_squares(
        prob.residuals,
        x0,
        bounds=(np.array([p.lower for p in prob.params]), np.array([p.upper for p in prob.params])),
        x_scale=_scales(prob, x0),
        method="trf",
        diff_step=np.array([p.diff_step for p in prob.params]),
        max_nfev=max_nfev,
        xtol=1e-8,
        ftol=1e-8,
    )


def _probe(prob: _Problem, x: np.ndarray, free: list[int]) -> tuple[float, np.ndarray]:
    """A short local fit (START_NFEV evaluations) of the parameters `free`
    only, the others held at x: the starts are guesses of those parameters,
    and holding the rest makes each numerical Jacobian cost len(free)
    simulations instead of one per parameter. Returns (cost, x)."""
    from scipy.optimize import least_squares

    def full(v: np.ndarray) -> np.ndarray:
        out = x.copy()
        out[free] = v
        return out

    params = [prob.params[i] for i in free]
    res = least_squares(
        lambda v: prob.residuals(full(v)),
        x[free],
        bounds=(np.array([p.lower for p in params]), np.array([p.upper for p in params])),
        x_scale=_scales(prob, x)[free],
        method="trf",
        diff_step=np.array([p.diff_step for p in params]),
        max_nfev=START_NFEV,
        xtol=1e-8,
        ftol=1e-8,
    )
    return float(res.cost), full(res.x)


def _multi_start(prob: _Problem, x0: np.ndarray, max_nfev: int):
    """Multi-start: a short probe (_probe) of the parameters that have starts
    from x0 and from every start, then the full local fit of every parameter
    from the probe with the lowest cost."""
    free = [i for i, p in enumerate(prob.params) if p.starts]
    trials = [x0]
    for i in free:
        for start in prob.params[i].starts:
            x = x0.copy()
            x[i] = prob.params[i].clip(start)
            trials.append(x)
    if len(trials) > 1:
        x0 = min((_probe(prob, x, free) for x in trials), key=lambda r: r[0])[1]
    return _local_fit(prob, x0, max_nfev)


# ---------------------------------------------------------------- the outcome


def _uncertainty(prob: _Problem, res: Any) -> tuple[np.ndarray, np.ndarray, list[dict]]:
    """Standard deviations, correlation matrix and the fit's warnings."""
    p = len(prob.params)
    m_res = res.fun.size
    s2 = float(2.0 * res.cost / max(m_res - p, 1))
    std, corr = np.full(p, np.nan), np.full((p, p), np.nan)
    warns: list[dict] = []
    try:
        corr, d = correlation_matrix(res.jac)
        std = d * np.sqrt(s2)
        sv = np.linalg.svd(res.jac * _scales(prob, res.x), compute_uv=False)
        if sv.size and sv[-1] <= 1e-10 * sv[0]:
            warns.append(
                warning(
                    "singular",
                    "the Jacobian is singular: some parameters cannot be told apart by this record",
                    parameters=prob.names,
                )
            )
    except np.linalg.LinAlgError:  # pragma: no cover - pinv of finite numbers converges
        warns.append(warning("singular", "could not compute parameter uncertainties"))
    active = getattr(res, "active_mask", np.zeros(p, dtype=int))
    warns += parameter_warnings(
        prob.params, res.x, corr, active, _scales(prob, res.x), prob.effect.name
    )
    if not res.success:
        warns.append(
            warning("not_converged", f"the optimiser stopped without convergence: {res.message}")
        )
    return std, corr, warns


def _fitted_table(prob: _Problem, x: np.ndarray, std: np.ndarray, warns: list[dict]) -> list[dict]:
    bounds = {w["parameters"][0]: w["bound"] for w in warns if w["kind"] == "at_bound"}
    return [
        {
            "name": p.name,
            "value": float(x[i]),
            "std": float(std[i]),
            "lower": float(p.lower),
            "upper": float(p.upper),
            "role": p.role,
            "before": p.before,
            "unit": p.unit,
            "owner": p.owner,
            "at_bound": bounds.get(p.name),
        }
        for i, p in enumerate(prob.params)
    ]


def _initial_parameters(
    ctx: Context, effect: Effect, screen_result: Any, quick: bool
) -> list[FitParam]:
    params = effect.parameters(ctx, screen_result) + coestimated(ctx, effect, screen_result)
    return [p for p in params if not (quick and p.optional)]


def fit_effect(
    ctx: Context,
    effect_name: str,
    *,
    screen_result: Any = None,
    max_samples: int | None = None,
    max_nfev: int | None = None,
    quick: bool = False,
    validation: bool | scoring.ValidationSplit = True,
    progress: Callable[[str], None] | None = None,
) -> FitResult:
    """Add effect_name to ctx.model, fit it with the co-estimated parameters
    on the estimation samples, and report errors on the whole record and on
    the validation blocks (see the module docstring).

    ctx: the baseline context (gearsim.analysis.signatures.build_context);
    screen_result: a previous screen_effect() of this effect (else computed);
    max_samples: fit on the first max_samples samples only (default: all for
    rigid meshes, 20 000 when the effect or model is costly); quick: leave
    optional parameters (contact stiffness and damping) at their present
    values (diagnose uses this); validation: True (default split), False, or
    a ValidationSplit."""
    t_start = time.perf_counter()
    effect = get_effect(effect_name, ctx.model)
    split = _split(ctx.meas.n, validation)
    if screen_result is None:
        screen_result = effect.screen(ctx)
    params = _initial_parameters(ctx, effect, screen_result, quick)
    all_optional = any(p.optional for p in effect.parameters(ctx, screen_result))
    notes: list[str] = []
    prob = _problem(ctx, effect, params, split, max_samples, notes)
    if progress:
        progress(
            f"fit {effect.name}: {len(params)} parameters ({', '.join(prob.names)}) on "
            f"{prob.sel.size} estimation points"
        )
    x0 = _coarse_grid(prob, np.array([p.clipped_x0() for p in params]))
    res = _multi_start(prob, x0, max_nfev or 30 * (len(params) + 1))
    std, corr, warns = _uncertainty(prob, res)
    new_model = prob.model_for(res.x)
    too_small = effect.negligible(ctx, new_model)
    if too_small:
        warns.append(warning("negligible", f"{effect.name}: {too_small}", effects=[effect.name]))
    out = _outcome(ctx, effect, new_model, split, warns)
    return FitResult(
        effect=effect.name,
        model=new_model,
        parameters=effect.report(new_model),
        fitted=_fitted_table(prob, res.x, std, warns),
        correlation=corr,
        warnings=warns,
        evaluations=prob.evaluations,
        seconds=time.perf_counter() - t_start,
        fit_samples=prob.meas_fit.n,
        validation=split,
        complete=not (quick and all_optional),
        notes=notes + effect.notes(ctx.model),
        **out,
    )


def _split(n: int, validation: bool | scoring.ValidationSplit) -> scoring.ValidationSplit:
    if isinstance(validation, scoring.ValidationSplit):
        return validation
    return scoring.split_record(n, bool(validation))


def _outcome(
    ctx: Context, effect: Effect, new_model: Any, split: scoring.ValidationSplit, warns: list
) -> dict[str, Any]:
    """Errors before and after on the whole record and the validation
    blocks; appends a no_gain warning when the validation error did not fall."""
    meas = ctx.meas
    before = {o: meas[o] - ctx.residual[o] for o in meas.spec.outputs}
    after = simulate_outputs(new_model, meas, ctx.inputs)
    mb, nb = _metrics(meas, before)
    ma, na = _metrics(meas, after)
    vb = validation_nrmse(meas, before, split.validation)
    va = validation_nrmse(meas, after, split.validation)
    if not va < vb:
        warns.append(
            warning(
                "no_gain",
                f"adding {effect.name} did not lower the validation error ({vb:.4g} -> "
                f"{va:.4g}): the record shows no sign of it",
                effects=[effect.name],
            )
        )
    residual = {o: meas[o] - after[o] for o in meas.spec.outputs}
    mse = {
        o: scoring.normalized_mse(residual[o], ctx.std[o], split.validation)
        for o in meas.spec.outputs
    }
    return {
        "nrmse_before": nb,
        "nrmse_after": na,
        "outputs_before": mb,
        "outputs_after": ma,
        "validation_nrmse_before": vb,
        "validation_nrmse_after": va,
        "judged_mse": mse,
        "residual_after": residual,
    }
