"""Add one effect to a model (or re-fit the effects it has) and estimate the
parameters on the C simulation.

``fit_effect`` seeds the effect's parameters from the residual screening
(gearsim.analysis.signatures), re-estimates together the model parameters that
trade off against them (gearsim.analysis.effects.coestimated), and minimises

    sum over outputs o of sum_k ((measured_o[k] - simulated_o[k]) / std(measured_o))^2

over the *estimation* samples (gearsim.analysis.scoring.split_record: the
held-out validation blocks never enter the fit) with
``scipy.optimize.least_squares`` (trust region reflective, bounds), each
residual evaluation being one open-loop batch run of the C rig over the
whole record. The residual is taken on at most ``max_points`` samples per
output (default MAX_RESIDUAL_POINTS), every k-th estimation sample: a
subsample spread evenly over the whole record, never a prefix. Only outputs
that depend on the parameters enter (the driven speed of a rigid mesh is
pure kinematics). Errors are always reported on the whole record and on the
validation blocks.

Scaling: each parameter is fitted in units of its own size (x_scale), and a
parameter spanning decades (a stiffness, a smoothing speed: FitParam.log) as
its logarithm, so that the problem the optimiser and the Jacobian see is
well scaled.

Non-smooth costs: a parameter with a ``grid`` is first searched on multiples
of its seed (cost only); a parameter with ``starts`` (the backlash gap) gets,
from each start, that grid of the other parameters and a short probe of those
with starts alone, and the full fit from the best probe (multi-start: a
single start from a short gap can end in a local minimum). The probes
sub-step a contact coarsely (PROBE_H_OMEGA): they only compare basins.

Uncertainty: from the Jacobian of the scaled problem at the solution, by its
singular values: ``cov = s^2 V S^-2 V^T`` with ``s^2 = RSS/(m - p)``. A
direction whose standard deviation exceeds its own scale (or whose singular
value is zero) is not identifiable from the record: its parameters get no
standard deviation and a ``not_identifiable`` warning names them and the
excitation that would separate them. Residuals of real rigs are correlated
in time, so the others are lower bounds. Identifiability warnings:
gearsim.analysis.identifiability.

Acceptance: an effect is accepted when it lowers both the validation error
and the whole record's error (FitResult.accepted, .verdict).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import modelkit as mk
from . import scoring
from .effects import (
    EFFECTS,
    Effect,
    FitParam,
    Screening,
    build_changes,
    coestimated,
    get_effect,
    present_effects,
)
from .identifiability import (
    correlated_warnings,
    parameter_warnings,
    unidentifiable_warning,
    warning,
)
from .measurement import Measurement
from .metrics import OutputMetrics, output_metrics
from .signatures import Context
from .simulate import contact_substeps, simulate_outputs

__all__ = [
    "FitResult",
    "fit_effect",
    "refit_effects",
    "screen_effect",
    "validation_nrmse",
    "REFIT",
]

MAX_RESIDUAL_POINTS = 40_000
PENALTY = 1e3
START_NFEV = 8
#: the probes of a multi-start only compare basins: a contact sub-stepped
#: this coarsely (h*omega_n) is a fifth of the cost and orders them alike
PROBE_H_OMEGA = 0.15
#: how many of the coarse probes' best basins are probed again at the fit's
#: own sub-steps before the full fit continues from the best
REPROBE = 2
#: a ranking fit's budget (fit_effect's ranking): the probe of each start
#: and the local fit from the best, in evaluations
RANK_NFEV = 4
RANK_LOCAL_NFEV = 10
#: a direction of the scaled parameter space is not identifiable when its
#: standard deviation exceeds this many times its own scale
UNIDENTIFIABLE_STD = 1.0
#: the name a joint re-fit of the effects a model has is reported under
REFIT = "refit"


@dataclass
class FitResult:
    """Outcome of adding one effect (effect: its name), or of re-fitting
    together the effects a model has (effect: REFIT).

    nrmse_before/after: whole record; validation_nrmse_before/after: on the
    held-out blocks (the whole record when validation is off); parameters:
    the effect's parameters as the model file holds them (for a re-fit,
    every present effect's); fitted: one dict per free parameter (name,
    value, std, lower, upper, role "effect"/"coestimated", before, unit,
    at_bound; std None when the record cannot determine it); correlation:
    matrix over `fitted`; warnings: identifiability and convergence warnings
    (dicts with kind and text); judged_mse: per output, mean squared
    normalised residual on the validation blocks after the fit (the whole
    record with validation off); score: the score of
    gearsim.analysis.scoring with this fit's own effective sample count;
    accepted: both the validation error and the whole record's error fell;
    verdict: that, in one line."""

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
    fit_points: int = 0

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

    @property
    def accepted(self) -> bool:
        """Both the validation error and the whole record's error fell."""
        return bool(
            self.validation_nrmse_after < self.validation_nrmse_before
            and self.nrmse_after < self.nrmse_before
        )

    @property
    def verdict(self) -> str:
        what = "the effects re-fitted together" if self.effect == REFIT else self.effect
        errors = (
            f"validation nrmse {self.validation_nrmse_before:.4g} -> "
            f"{self.validation_nrmse_after:.4g}, whole record {self.nrmse_before:.4g} -> "
            f"{self.nrmse_after:.4g}"
        )
        verb = "lower" if self.effect == REFIT else "lowers"
        if self.accepted:
            return f"accepted: {what} {verb} both errors ({errors})"
        rose = []
        if not self.validation_nrmse_after < self.validation_nrmse_before:
            rose.append("the validation error")
        if not self.nrmse_after < self.nrmse_before:
            rose.append("the whole record's error")
        does = "do" if self.effect == REFIT else "does"
        return f"not accepted: {what} {does} not lower {' and '.join(rose)} ({errors})"

    def to_json(self) -> dict:
        return {
            "effect": self.effect,
            "nrmse_before": self.nrmse_before,
            "nrmse_after": self.nrmse_after,
            "parameters": self.parameters,
            "score": self.score,
            "accepted": self.accepted,
            "verdict": self.verdict,
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
            "fit_points": self.fit_points,
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


# ---------------------------------------------------------------- scaling


def _to_u(params: list[FitParam], x: np.ndarray) -> np.ndarray:
    """Optimiser coordinates: ln(x) for a log parameter, x otherwise."""
    return np.array([np.log(v) if p.log else v for p, v in zip(params, x, strict=True)])


def _to_x(params: list[FitParam], u: np.ndarray) -> np.ndarray:
    return np.array([np.exp(v) if p.log else v for p, v in zip(params, u, strict=True)])


def _bounds_u(params: list[FitParam]) -> tuple[np.ndarray, np.ndarray]:
    lo = [np.log(max(p.lower, 1e-300)) if p.log else p.lower for p in params]
    hi = [np.log(p.upper) if p.log else p.upper for p in params]
    return np.array(lo), np.array(hi)


def _scales_u(params: list[FitParam], x: np.ndarray) -> np.ndarray:
    """Each coordinate's own size: 1 for a logarithm (a relative change), the
    value itself otherwise (a hundredth of the range at zero)."""
    out = []
    for v, p in zip(x, params, strict=True):
        if p.log:
            out.append(1.0)
            continue
        span = p.upper - p.lower
        out.append(abs(v) if v != 0 else (0.01 * span if np.isfinite(span) else 1.0))
    arr = np.array(out, dtype=float)
    arr[~(arr > 0)] = 1.0
    return arr


def _diff_steps(params: list[FitParam]) -> np.ndarray:
    return np.array([p.diff_step for p in params])


# ---------------------------------------------------------------- the problem


@dataclass
class _Problem:
    """The least-squares problem of one fit: which samples and outputs, their
    weights, and how a parameter vector becomes a model."""

    ctx: Context
    effect: Effect | None
    params: list[FitParam]
    outputs: list[str]
    sel: np.ndarray  # estimation samples used (indices into the record)
    weights: dict[str, float]
    substeps: int | None = None
    probe_substeps: int | None = None
    evaluations: int = 0
    ranking: bool = False  # a ranking fit: the short multi-start search

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
        outs = simulate_outputs(mdl, self.ctx.meas, self.ctx.inputs, self.substeps)
        meas = self.ctx.meas
        r = np.concatenate(
            [(meas[o][self.sel] - outs[o][self.sel]) * self.weights[o] for o in self.outputs]
        )
        return r if np.all(np.isfinite(r)) else np.full(m_res, PENALTY)

    def cost(self, x: np.ndarray) -> float:
        return float(np.sum(self.residuals(x) ** 2))


def _moves_driven_speed(model: Any, effect: Effect | None) -> bool:
    costly = effect is not None and effect.costly
    return costly or any(e.costly and e.present(model) for e in EFFECTS.values())


def _problem(
    ctx: Context,
    effect: Effect | None,
    params: list[FitParam],
    split: scoring.ValidationSplit,
    max_points: int | None,
) -> _Problem:
    meas = ctx.meas
    outputs = [meas.spec.torque_output]
    if _moves_driven_speed(ctx.model, effect):
        outputs.append(meas.spec.speed_output)
    est = np.nonzero(split.estimation)[0]
    limit = max_points or MAX_RESIDUAL_POINTS
    stride = max(1, int(np.ceil(est.size * len(outputs) / limit)))
    weights = {o: 1.0 / ctx.std[o] if ctx.std[o] > 0 else 1.0 for o in outputs}
    prob = _Problem(ctx, effect, params, outputs, est[::stride], weights)
    # a contact's sub-steps, held over the fit: a count that changed with
    # the stiffness would make the cost jump under the finite differences
    try:
        seeded = prob.model_for(np.array([p.x0 for p in params]))
        prob.substeps = contact_substeps(seeded, meas.dt)
        prob.probe_substeps = contact_substeps(seeded, meas.dt, PROBE_H_OMEGA)
    except Exception:  # noqa: BLE001 - a seed the core refuses: the rig's own count
        prob.substeps = prob.probe_substeps = None
    return prob


# ---------------------------------------------------------------- the search


def _coarse_grid(prob: Any, x0: np.ndarray, skip: tuple[int, ...] = ()) -> np.ndarray:
    """Line search over each parameter's grid multipliers (cost only), the
    parameters in `skip` held."""
    x0 = x0.copy()
    for i, p in enumerate(prob.params):
        if not p.grid or i in skip:
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


def _least_squares(prob: Any, params: list[FitParam], x0: np.ndarray, full: Any, max_nfev: int):
    """least_squares over the parameters `params` in their optimiser
    coordinates; full(x_sub) gives the whole parameter vector to evaluate."""
    from scipy.optimize import least_squares

    lo, hi = _bounds_u(params)

    def run(u0: np.ndarray, nfev: int) -> Any:
        return least_squares(
            lambda u: prob.residuals(full(_to_x(params, u))),
            u0,
            bounds=(lo, hi),
            x_scale=_scales_u(params, x0),
            method="trf",
            diff_step=_diff_steps(params),
            max_nfev=nfev,
            xtol=1e-8,
            ftol=1e-8,
        )

    res = run(np.clip(_to_u(params, x0), lo, hi), max_nfev)
    if res.status == 3 and res.nfev < max_nfev:
        # Ended on xtol with budget left: the trust region can shrink onto a
        # point that is not a minimum (a backlash fit stopped after 19 of 240
        # evaluations at 1.2 times the cost it reaches from there). Once more
        # from that point, with a fresh trust region; kept if it is better.
        again = run(res.x, max_nfev - res.nfev)
        if again.cost < res.cost:
            again.nfev += res.nfev
            res = again
    res.u = res.x
    res.x = _to_x(params, res.x)
    return res


def _local_fit(prob: Any, x0: np.ndarray, max_nfev: int):
    return _least_squares(prob, prob.params, x0, lambda x: x, max_nfev)


def _probe(
    prob: Any, x: np.ndarray, free: list[int], nfev: int = START_NFEV
) -> tuple[float, np.ndarray]:
    """A short local fit (START_NFEV evaluations) of the parameters `free`
    only, the others held at x: the starts are guesses of those parameters,
    and holding the rest makes each numerical Jacobian cost len(free)
    simulations instead of one per parameter. Returns (cost, x)."""

    def full(v: np.ndarray) -> np.ndarray:
        out = x.copy()
        out[free] = v
        return out

    params = [prob.params[i] for i in free]
    res = _least_squares(prob, params, x[free], full, nfev)
    return float(res.cost), full(res.x)


def _multi_start(prob: Any, x0: np.ndarray, max_nfev: int):
    """Multi-start: from x0 and from every start of the parameters that have
    starts, the coarse grid of the other parameters at that start
    (_coarse_grid: a contact's stiffness that suits one gap does not suit
    another) and a short probe (_probe) of the parameters with starts; then
    the full local fit of every parameter from the trial with the lowest
    cost. Without starts: the coarse grid, then the local fit."""
    free = [i for i, p in enumerate(prob.params) if p.starts]
    if not free:
        return _local_fit(prob, _coarse_grid(prob, x0), max_nfev)
    if getattr(prob, "ranking", False):  # a test's stand-in problem may not have it
        return _ranking_multi_start(prob, x0, free, max_nfev)
    trials = [x0]
    for i in free:
        for start in prob.params[i].starts:
            x = x0.copy()
            x[i] = prob.params[i].clip(start)
            trials.append(x)
    fine = getattr(prob, "substeps", None)
    coarse = getattr(prob, "probe_substeps", None)
    if coarse and coarse != fine:
        prob.substeps = coarse
        try:
            probes = [_probe(prob, _coarse_grid(prob, x, tuple(free)), free) for x in trials]
        finally:
            prob.substeps = fine
        # the coarse contact shifts the optimum a little: the best few
        # basins are probed again at the fit's own sub-steps
        ranked = sorted(probes, key=lambda r: r[0])[:REPROBE]
        best = min((_probe(prob, x, free) for _, x in ranked), key=lambda r: r[0])
    else:
        best = min(
            (_probe(prob, _coarse_grid(prob, x, tuple(free)), free) for x in trials),
            key=lambda r: r[0],
        )
    return _local_fit(prob, best[1], max_nfev)


def _ranking_multi_start(prob: Any, x0: np.ndarray, free: list[int], max_nfev: int):
    """The multi-start of a ranking fit (fit_effect's ranking): the grid of
    the other parameters once, at x0; from each start a probe of RANK_NFEV
    evaluations; a local fit of at most RANK_LOCAL_NFEV from the best."""
    x0 = _coarse_grid(prob, x0, tuple(free))
    trials = [x0]
    for i in free:
        for start in prob.params[i].starts:
            x = x0.copy()
            x[i] = prob.params[i].clip(start)
            trials.append(x)
    best = min((_probe(prob, x, free, RANK_NFEV) for x in trials), key=lambda r: r[0])
    return _local_fit(prob, best[1], min(max_nfev, RANK_LOCAL_NFEV))


# ---------------------------------------------------------------- the outcome


@dataclass(frozen=True)
class _Uncertainty:
    std: np.ndarray  # NaN where the record cannot determine it
    corr: np.ndarray
    unidentifiable: tuple[tuple[int, ...], ...]  # parameter indices of each degenerate direction


def _identify(prob: Any, res: Any) -> _Uncertainty:
    """Standard deviations and correlations from the scaled Jacobian's
    singular values; the directions the record cannot determine."""
    params = prob.params
    p = len(params)
    jac = np.asarray(res.jac, dtype=float)  # d residual / d u
    m_res = jac.shape[0]
    s2 = float(2.0 * res.cost / max(m_res - p, 1))
    scale = _scales_u(params, res.x)
    js = jac * scale  # d residual / d (u / scale)
    _, sv, vt = np.linalg.svd(js, full_matrices=False)
    with np.errstate(divide="ignore"):
        std_dir = np.where(sv > 0, np.sqrt(s2) / np.where(sv > 0, sv, 1.0), np.inf)
    bad = (
        (~np.isfinite(std_dir))
        | (std_dir > UNIDENTIFIABLE_STD)
        | (sv <= 1e-12 * max(sv[0], 1e-300))
    )
    groups: list[tuple[int, ...]] = []
    involved = np.zeros(p, dtype=bool)
    for k in np.nonzero(bad)[0]:
        v = np.abs(vt[k])
        members = tuple(int(i) for i in np.nonzero(v >= 0.3 * v.max())[0])
        groups.append(members)
        involved[list(members)] = True
    good = ~bad
    cov_s = (vt[good].T * (s2 / sv[good] ** 2)) @ vt[good] if good.any() else np.zeros((p, p))
    d = np.sqrt(np.clip(np.diag(cov_s), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov_s / np.outer(d, d)
    std_u = d * scale
    std = np.array(
        [res.x[i] * std_u[i] if params[i].log else std_u[i] for i in range(p)], dtype=float
    )
    std[involved] = np.nan
    corr[involved, :] = np.nan
    corr[:, involved] = np.nan
    return _Uncertainty(std, corr, tuple(groups))


def _uncertainty(
    prob: Any, res: Any, effect_name: str
) -> tuple[np.ndarray, np.ndarray, list[dict]]:
    """Standard deviations, correlation matrix and the fit's warnings."""
    p = len(prob.params)
    warns: list[dict] = []
    try:
        unc = _identify(prob, res)
    except np.linalg.LinAlgError:  # pragma: no cover - the SVD of finite numbers converges
        unc = _Uncertainty(np.full(p, np.nan), np.full((p, p), np.nan), ())
        warns.append(warning("not_identifiable", "could not compute parameter uncertainties"))
    for group in unc.unidentifiable:
        warns.append(unidentifiable_warning([prob.params[i] for i in group], effect_name))
    active = getattr(res, "active_mask", np.zeros(p, dtype=int))
    scales_x = np.where([p.log for p in prob.params], np.abs(res.x), _scales_u(prob.params, res.x))
    warns += parameter_warnings(prob.params, res.x, active, scales_x, effect_name)
    warns += correlated_warnings(prob.params, unc.corr, effect_name)
    if not res.success:
        warns.append(
            warning("not_converged", f"the optimiser stopped without convergence: {res.message}")
        )
    return unc.std, unc.corr, warns


def _fitted_table(prob: _Problem, x: np.ndarray, std: np.ndarray, warns: list[dict]) -> list[dict]:
    bounds = {w["parameters"][0]: w["bound"] for w in warns if w["kind"] == "at_bound"}
    return [
        {
            "name": p.name,
            "value": float(x[i]),
            "std": float(std[i]) if np.isfinite(std[i]) else None,
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
    ctx: Context, effect: Effect | None, screening: Screening | None, quick: bool
) -> list[FitParam]:
    own = effect.parameters(ctx, screening) if effect is not None else []
    params = own + coestimated(ctx, effect, screening)
    return [p for p in params if not (quick and p.optional)]


def fit_effect(
    ctx: Context,
    effect_name: str,
    *,
    screen_result: Screening | None = None,
    max_points: int | None = None,
    max_nfev: int | None = None,
    quick: bool = False,
    ranking: bool = False,
    validation: bool | scoring.ValidationSplit = True,
    progress: Callable[[str], None] | None = None,
) -> FitResult:
    """Add effect_name to ctx.model, fit it with the co-estimated parameters
    on the estimation samples, and report errors on the whole record and on
    the validation blocks (see the module docstring).

    ctx: the baseline context (gearsim.analysis.signatures.build_context);
    screen_result: a previous screen_effect() of this effect (else computed);
    max_points: residual samples per fit (default MAX_RESIDUAL_POINTS), spread
    evenly over the record; quick: leave optional parameters (contact
    stiffness and damping) at their present values; ranking: a fit good
    enough to rank the candidates (diagnose): a contact is sub-stepped as
    coarsely as in the multi-start probes (PROBE_H_OMEGA) throughout, the
    errors are still those of the full resolution, and the result is marked
    incomplete (FitResult.complete) so that the report fits it again in full;
    validation: True (default split), False, or a ValidationSplit."""
    effect = get_effect(effect_name, ctx.model)
    if screen_result is None:
        screen_result = effect.screen(ctx)
    return _fit(
        ctx, effect, screen_result, max_points, max_nfev, quick, validation, progress, ranking
    )


def refit_effects(
    ctx: Context,
    *,
    max_points: int | None = None,
    max_nfev: int | None = None,
    validation: bool | scoring.ValidationSplit = True,
    progress: Callable[[str], None] | None = None,
) -> FitResult:
    """Re-fit together every effect the model has (with the driven inertia):
    the final round after effects were added one at a time, each fitted with
    the others held at what the earlier rounds found. Reported as REFIT."""
    return _fit(ctx, None, None, max_points, max_nfev, False, validation, progress)


def _fit(
    ctx: Context,
    effect: Effect | None,
    screening: Screening | None,
    max_points: int | None,
    max_nfev: int | None,
    quick: bool,
    validation: bool | scoring.ValidationSplit,
    progress: Callable[[str], None] | None,
    ranking: bool = False,
) -> FitResult:
    t_start = time.perf_counter()
    split = _split(ctx.meas.n, validation)
    params = _initial_parameters(ctx, effect, screening, quick)
    own = effect.parameters(ctx, screening) if effect is not None else []
    all_optional = any(p.optional for p in own)
    name = effect.name if effect is not None else REFIT
    prob = _problem(ctx, effect, params, split, max_points)
    # a ranking fit of an effect that brings a contact into a model without
    # one: coarse sub-steps and a short search (a model that has a contact
    # already is fitted in full: its baseline is at full resolution)
    coarse = (
        ranking
        and not _moves_driven_speed(ctx.model, None)
        and prob.probe_substeps is not None
        and prob.probe_substeps != prob.substeps
    )
    if coarse:
        prob.substeps = prob.probe_substeps
        prob.ranking = True
    if progress:
        progress(
            f"fit {name}: {len(params)} parameters ({', '.join(prob.names)}) on "
            f"{prob.sel.size} points spread over the record"
        )
    x0 = np.array([p.clipped_x0() for p in params])
    res = _multi_start(prob, x0, max_nfev or 30 * (len(params) + 1))
    std, corr, warns = _uncertainty(prob, res, name)
    new_model = prob.model_for(res.x)
    too_small = effect.negligible(ctx, new_model) if effect is not None else None
    if too_small:
        warns.append(warning("negligible", f"{name}: {too_small}", effects=[name]))
    contradicted = effect.inconsistent(ctx, new_model) if effect is not None else None
    if contradicted:
        warns.append(warning("inconsistent", f"{name}: {contradicted}", effects=[name]))
    out = _outcome(ctx, name, new_model, split, warns)
    notes = [] if effect is None else effect.notes(ctx.model)
    if coarse:
        notes.append(
            f"ranked with the contact sub-stepped coarsely (h*omega_n <= {PROBE_H_OMEGA:g}, "
            f"{prob.substeps} sub-steps); the errors are at full resolution, and `fit` or the "
            "report's round fits it in full"
        )
    if effect is None:
        reported = {}
        for e in present_effects(new_model):
            reported.update(e.report(new_model))
    else:
        reported = effect.report(new_model)
    return FitResult(
        effect=name,
        model=new_model,
        parameters=reported,
        fitted=_fitted_table(prob, res.x, std, warns),
        correlation=corr,
        warnings=warns,
        evaluations=prob.evaluations,
        seconds=time.perf_counter() - t_start,
        fit_samples=ctx.meas.n,
        fit_points=int(prob.sel.size),
        validation=split,
        complete=not (quick and all_optional) and not coarse,
        notes=notes,
        **out,
    )


def _split(n: int, validation: bool | scoring.ValidationSplit) -> scoring.ValidationSplit:
    if isinstance(validation, scoring.ValidationSplit):
        return validation
    return scoring.split_record(n, bool(validation))


def _outcome(
    ctx: Context, name: str, new_model: Any, split: scoring.ValidationSplit, warns: list
) -> dict[str, Any]:
    """Errors before and after on the whole record and the validation
    blocks; appends a no_gain warning when either did not fall."""
    meas = ctx.meas
    before = {o: meas[o] - ctx.residual[o] for o in meas.spec.outputs}
    after = simulate_outputs(new_model, meas, ctx.inputs)
    mb, nb = _metrics(meas, before)
    ma, na = _metrics(meas, after)
    vb = validation_nrmse(meas, before, split.validation)
    va = validation_nrmse(meas, after, split.validation)
    rose = [
        text for text, (b, a) in (("validation", (vb, va)), ("whole-record", (nb, na))) if not a < b
    ]
    if rose:
        what = "re-fitting the effects together" if name == REFIT else f"adding {name}"
        warns.append(
            warning(
                "no_gain",
                f"{what} did not lower the {' and '.join(rose)} error (validation {vb:.4g} -> "
                f"{va:.4g}, whole record {nb:.4g} -> {na:.4g}): not accepted",
                effects=[name],
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
