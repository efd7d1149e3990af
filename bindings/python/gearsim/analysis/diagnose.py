"""diagnose: where the model fails, and which missing effect explains it.

1. compare: the baseline error, overall and per regime (which regimes fail).
2. screen: for every effect the model lacks, regress the driven-side residual
   on the effect's signature columns plus those of the parameters that would
   be re-estimated with it (gearsim.analysis.signatures). This seeds the fit
   and gives the evidence. Screening rules an effect out only when the record
   cannot show it (backlash without concentrated driven-speed residual after
   reversals, a temperature dependence without a temperature span).
3. fit: the best ALWAYS_FIT candidates not ruled out, the cheap ones (one
   parameter, no contact) and every other one whose screening predicts a gain
   of at least scoring.HELP_MARGIN (or the best ``top`` by screening), are
   added and fitted on the C simulation on the estimation blocks
   (gearsim.analysis.fitting), which gives their errors on the whole record
   and on the validation blocks. The others keep their screening estimate
   (a note names them).
4. rank: by the score of gearsim.analysis.scoring (a BIC on the estimation
   part with an effective sample count); fitted candidates first, screening
   estimates after them; within the noise, fewer parameters first.
5. conclude: the best candidate helps (scoring.helps, the rule the report's
   rounds use too), or "nothing left that helps".
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from . import scoring
from .compare import CompareResult, compare
from .effects import Effect, Screening, applicable_effects, coestimated, nuisance_columns
from .fitting import FitResult, fit_effect
from .identifiability import tie_warning
from .measurement import Measurement
from .regimes import FAILING_RATIO
from .signatures import Context, build_context, screen
from .simulate import Inputs, prepare_inputs
from .threads import single_blas_thread

__all__ = ["Candidate", "DiagnoseResult", "diagnose", "NOTHING_HELPS"]

NOTHING_HELPS = "nothing left that helps"
#: candidates fitted whatever screening predicts (the best few by screening)
ALWAYS_FIT = 3
#: a predicted relative gain below this: screening found no sign of the effect
NO_SIGNATURE_GAIN = 1e-3


@dataclass
class Candidate:
    """One missing effect: its errors after being added (whole record and
    validation blocks), its score, the parameters, how that was found
    (method "fit" or "screening": a screening estimate, not fitted) and the
    evidence from the residual. helps: the stopping rule's verdict;
    tied_with: candidates within the noise of it."""

    effect: str
    nrmse_after: float
    parameters: dict[str, Any]
    method: str
    evidence: dict[str, Any]
    score: float
    screen_nrmse: float
    fit: FitResult | None = None
    validation_nrmse_after: float = float("nan")
    n_parameters: int = 1
    judged_mse: dict[str, float] = field(default_factory=dict)
    helps: bool = False
    tied_with: list[str] = field(default_factory=list)
    #: the candidates it contains as a special case (Effect.nests)
    nests: tuple[str, ...] = ()

    @property
    def warnings(self) -> list[dict]:
        return list(self.fit.warnings) if self.fit is not None else []

    def to_json(self) -> dict:
        out = {
            "effect": self.effect,
            "score": self.score,
            "method": self.method,
            "nrmse_after": self.nrmse_after,
            "validation_nrmse_after": self.validation_nrmse_after,
            "parameters": self.parameters,
            "n_parameters": self.n_parameters,
            "helps": self.helps,
            "within_noise_of": list(self.tied_with),
            "screen_nrmse": self.screen_nrmse,
            "evidence": self.evidence,
            "warnings": [dict(w) for w in self.warnings],
        }
        if self.fit is not None:
            out["coestimated"] = {
                f["name"]: f["value"] for f in self.fit.fitted if f["role"] == "coestimated"
            }
        return out


@dataclass
class DiagnoseResult:
    baseline: CompareResult
    context: Context
    candidates: list[Candidate]
    skipped: dict[str, str]
    reestimate_nrmse: float
    seconds: float
    validation: scoring.ValidationSplit
    validation_baseline_nrmse: float
    baseline_score: float
    effective_samples: dict[str, float]
    tie_relative: float = scoring.TIE_RELATIVE
    warnings: list[dict] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def baseline_nrmse(self) -> float:
        return self.baseline.nrmse

    @property
    def best(self) -> Candidate | None:
        return self.candidates[0] if self.candidates else None

    @property
    def best_helps(self) -> bool:
        return bool(self.best is not None and self.best.helps)

    @property
    def conclusion(self) -> str:
        b = self.best
        if b is not None and b.helps:
            return (
                f"add {b.effect}: validation nrmse {self.validation_baseline_nrmse:.4g} -> "
                f"{b.validation_nrmse_after:.4g}, score {self.baseline_score:.1f} -> {b.score:.1f}"
            )
        return (
            f"{NOTHING_HELPS}: no fitted candidate lowers the validation error by "
            f"{100 * scoring.HELP_MARGIN:.0f} % and the score"
        )

    def to_json(self) -> dict:
        return {
            "baseline_nrmse": self.baseline.nrmse,
            "candidates": [c.to_json() for c in self.candidates],
            "validation": {
                **self.validation.to_json(),
                "baseline_nrmse": self.validation_baseline_nrmse,
            },
            "warnings": [dict(w) for w in self.warnings],
            "conclusion": self.conclusion,
            "baseline_score": self.baseline_score,
            "effective_samples": dict(self.effective_samples),
            "tie": {"score": scoring.TIE_SCORE, "relative_validation": self.tie_relative},
            "reestimate_only_nrmse": self.reestimate_nrmse,
            "baseline_outputs": {k: v.nrmse for k, v in self.baseline.outputs.items()},
            "failing_ratio": FAILING_RATIO,
            "failing_regimes": [
                {
                    "regime": r["regime"],
                    "description": r["description"],
                    "worst_ratio": r["worst_ratio"],
                    "fraction": r["fraction"],
                }
                for r in self.baseline.failing_regimes
            ],
            "regimes": self.baseline.regimes,
            "not_candidates": self.skipped,
            "seconds": self.seconds,
            "notes": list(self.notes),
        }


# ---------------------------------------------------------------- screening


@dataclass
class _Screened:
    effect: Effect
    result: Screening
    predicted: float
    evidence: dict[str, Any]
    ruled_out: str | None


def _screen_all(ctx: Context, effects: list[Effect], nuisance_nrmse: float) -> list[_Screened]:
    """Screen every candidate; sorted by the error screening predicts."""
    out = []
    for eff in effects:
        sr = eff.screen(ctx)
        why = sr.ruled_out
        ev = eff.evidence(ctx, sr)
        if why:
            ev["ruled_out"] = why
            ev["text"] = f"{ev.get('text', '')} (not fitted: {why})".strip()
        pred = nuisance_nrmse if why else float(sr.predicted_nrmse)
        out.append(_Screened(eff, sr, pred, ev, why))
    return sorted(out, key=lambda s: s.predicted)


def _worth_fitting(
    screened: list[_Screened], nuisance_nrmse: float, top: int | None, model: Any = None
) -> set[str]:
    """The candidates to fit, among those not ruled out (in screening order).
    With `top`: the first `top`. Without: the first ALWAYS_FIT, every cheap
    one (one parameter and no contact or spring, in it or in the model: a few
    fast simulations), and every other
    one whose screening predicts an error at least HELP_MARGIN below
    re-estimating the present parameters alone. A costly fit (several
    parameters, or contact) is as long as the whole screening, and one that
    screening predicts no gain for ends low in the ranking anyway (its
    screening estimate is kept and listed). The first few and the cheap ones
    are fitted whatever screening says: the linear screening reads some
    signatures poorly (a delay's gain is underestimated)."""
    not_ruled_out = [s for s in screened if not s.ruled_out]
    if top is not None:
        return {s.effect.name for s in not_ruled_out[:top]}
    gain_needed = (1.0 - scoring.HELP_MARGIN) * nuisance_nrmse
    return {
        s.effect.name
        for i, s in enumerate(not_ruled_out)
        if i < ALWAYS_FIT or _cheap_fit(s.effect, model) or s.predicted <= gain_needed
    }


def _cheap_fit(effect: Effect, model: Any) -> bool:
    """One parameter and no contact or spring to sub-step, in the candidate
    and in the model: a few fast simulations."""
    return effect.n_params == 1 and not effect.costly and not _costly_model(model)


def _costly_model(model: Any) -> bool:
    from .effects import present_effects

    return model is not None and any(e.costly for e in present_effects(model))


def _fit_candidates(
    ctx: Context,
    screened: list[_Screened],
    nuisance_nrmse: float,
    baseline_validation: float,
    split: scoring.ValidationSplit,
    top: int | None,
    fit: bool,
    say: Callable[[str], None],
    notes: list[str],
) -> dict[str, Candidate]:
    """Fit the candidates _worth_fitting picks; then, when a fitted one whose
    own signature screening found absent lowered the validation error anyway
    (_screening_underreads), the rest too. Returns the fitted ones by name."""
    if not fit:
        return {}
    chosen = _worth_fitting(screened, nuisance_nrmse, top, ctx.model)
    out: dict[str, Candidate] = {}

    def fit_all(names: set[str]) -> None:
        for s in screened:
            if s.effect.name in names and s.effect.name not in out:
                c = _fitted_candidate(ctx, s, split, say, notes)
                if c is not None:
                    out[s.effect.name] = c

    fit_all(chosen)
    if top is None and _screening_underreads(screened, out, nuisance_nrmse, baseline_validation):
        chosen = {s.effect.name for s in screened if not s.ruled_out}
        fit_all(chosen)
    _note_unfitted(screened, chosen, top, notes)
    return out


def _screening_underreads(
    screened: list[_Screened],
    fitted: dict[str, Candidate],
    nuisance_nrmse: float,
    baseline_validation: float,
) -> bool:
    """A fitted candidate whose own columns screening found empty (predicted
    gain under NO_SIGNATURE_GAIN) still lowers the validation error by
    HELP_MARGIN: the gain comes from re-estimating the present parameters,
    which the linear screening underestimates on this record, so no
    candidate may be left to its screening estimate."""
    empty = (1.0 - NO_SIGNATURE_GAIN) * nuisance_nrmse
    lowered = (1.0 - scoring.HELP_MARGIN) * baseline_validation
    return any(
        s.predicted >= empty and fitted[s.effect.name].validation_nrmse_after <= lowered
        for s in screened
        if s.effect.name in fitted
    )


def _note_unfitted(
    screened: list[_Screened], to_fit: set[str], top: int | None, notes: list[str]
) -> None:
    """One note naming the candidates left to their screening estimate."""
    unfitted = [s.effect.name for s in screened if not s.ruled_out and s.effect.name not in to_fit]
    if not unfitted:
        return
    why = (
        f"outside the best {top} by screening"
        if top is not None
        else f"costly, screening predicts less than {100 * scoring.HELP_MARGIN:.0f} % gain"
    )
    notes.append(f"not fitted ({why}): {', '.join(unfitted)}")


def _screen_parameters(ctx: Context, eff: Effect, sr: Any) -> dict[str, Any]:
    """The effect's parameters as the screening seeds them (not fitted), in
    the same form as a fitted candidate's (program names, model values)."""
    from ..errors import GearsimError

    seeds = {p.name: p.clipped_x0() for p in eff.parameters(ctx, sr)}
    try:
        from .effects import apply_changes

        return eff.report(apply_changes(ctx.model, eff.build(ctx, seeds)))
    except (GearsimError, ValueError, KeyError):  # a seed the block refuses: the raw seeds
        return seeds


def _screening_candidate(ctx: Context, s: _Screened, split: scoring.ValidationSplit) -> Candidate:
    """A candidate judged on screening alone: its errors and score are
    estimates from the linear regression, not from a simulation."""
    torque, speed = ctx.torque_output, ctx.speed_output
    reg = s.result.regression
    tn = reg.torque_nrmse if reg is not None else ctx.base_nrmse[torque]
    mse = {
        torque: float(tn) ** 2,
        speed: scoring.normalized_mse(ctx.residual[speed], ctx.std[speed], split.validation),
    }
    k = len(s.effect.parameters(ctx, s.result)) + len(coestimated(ctx, s.effect, s.result))
    return Candidate(
        s.effect.name,
        s.predicted,
        _screen_parameters(ctx, s.effect, s.result),
        "screening",
        s.evidence,
        float("nan"),
        s.predicted,
        None,
        validation_nrmse_after=s.predicted,
        n_parameters=k,
        judged_mse=mse,
        nests=s.effect.nests,
    )


def _fitted_candidate(
    ctx: Context,
    s: _Screened,
    split: scoring.ValidationSplit,
    say: Callable[[str], None],
    notes: list[str],
) -> Candidate | None:
    say(f"fit: {s.effect.name} (screening predicts nrmse {s.predicted:.4f})")
    try:
        fr = fit_effect(
            ctx,
            s.effect.name,
            screen_result=s.result,
            max_nfev=20 * (s.effect.n_params + 2),
            ranking=True,
            validation=split,
        )
    except Exception as exc:  # a candidate that cannot be fitted is reported, not fatal
        notes.append(f"{s.effect.name}: fit failed ({exc}); screening estimate kept")
        return None
    try:  # the evidence again, now quoting the fitted parameters
        evidence = s.effect.evidence(ctx, s.result, fr.model)
    except Exception:  # noqa: BLE001 - the screening's evidence stays
        evidence = s.evidence
    return Candidate(
        s.effect.name,
        fr.nrmse_after,
        fr.parameters,
        "fit",
        evidence,
        float("nan"),
        s.predicted,
        fr,
        validation_nrmse_after=fr.validation_nrmse_after,
        n_parameters=fr.n_parameters,
        judged_mse=dict(fr.judged_mse),
        nests=s.effect.nests,
    )


# ---------------------------------------------------------------- scoring


def _effective_samples(
    ctx: Context, cands: list[Candidate], split: scoring.ValidationSplit
) -> dict[str, float]:
    """Per output, n_eff from the residual of the best-fitting candidate
    (lowest estimation error), else of the baseline."""
    fitted = [(c, c.fit) for c in cands if c.fit is not None]
    if fitted:
        _best, best_fit = min(fitted, key=lambda cf: sum(cf[0].judged_mse.values()))
        residual = best_fit.residual_after
    else:
        residual = ctx.residual
    n = int(split.validation.sum())
    return {
        o: scoring.effective_samples(n, scoring.lag1_autocorrelation(r[split.validation]))
        for o, r in residual.items()
    }


def _score_all(
    ctx: Context, cands: list[Candidate], split: scoring.ValidationSplit
) -> tuple[float, dict[str, float]]:
    """Set every candidate's score; return the baseline's score and n_eff."""
    n_eff = _effective_samples(ctx, cands, split)
    outputs = list(n_eff)
    for c in cands:
        c.score = scoring.bic_score(
            [c.judged_mse[o] for o in outputs], [n_eff[o] for o in outputs], c.n_parameters
        )
    base_mse = [
        scoring.normalized_mse(ctx.residual[o], ctx.std[o], split.validation) for o in outputs
    ]
    return scoring.bic_score(base_mse, [n_eff[o] for o in outputs], 0), n_eff


def _warnings(ranked: list[Candidate]) -> list[dict]:
    """Ties among the candidates that help, then the fit warnings of the best
    one when it helps (those of a rejected candidate would only be noise)."""
    out = []
    by_name = {c.effect: c for c in ranked}
    seen: set[frozenset] = set()
    for c in ranked:
        if not c.helps:
            continue
        for other in c.tied_with:
            pair = frozenset((c.effect, other))
            if not by_name[other].helps:
                continue  # a tie with a candidate that would not be added is no choice
            if pair not in seen:
                seen.add(pair)
                out.append(tie_warning(c, by_name[other]))
    if ranked and ranked[0].helps and ranked[0].fit is not None:
        out += [{**w, "candidate": ranked[0].effect} for w in ranked[0].warnings]
    return out


@single_blas_thread
def diagnose(
    model: Any,
    meas: Measurement,
    inputs: Inputs | None = None,
    *,
    input_filter: float | str | None = "auto",
    top: int | None = None,
    fit: bool = True,
    validation: bool = True,
    validation_fraction: float = scoring.DEFAULT_FRACTION,
    progress: Callable[[str], None] | None = None,
) -> DiagnoseResult:
    """Rank the effects the model lacks (see the module docstring). top: fit
    only the best `top` by screening (None: every one not ruled out)."""
    t0 = time.perf_counter()
    say = progress or (lambda s: None)
    if inputs is None:
        inputs = prepare_inputs(meas, input_filter)
    say("compare: simulating the model on the measured inputs")
    base = compare(model, meas, inputs)
    ctx = build_context(model, meas, inputs, base.sim, base.regime_masks)
    split = scoring.split_record(meas.n, validation, validation_fraction)
    effects, skipped = applicable_effects(model)
    nuis = screen(ctx, nuisance_columns(ctx, None), [])
    say(
        f"screen: {len(effects)} candidate effects on the residual (baseline nrmse "
        f"{base.nrmse:.4f}, re-estimating present parameters alone {nuis.nrmse:.4f})"
    )
    screened = _screen_all(ctx, effects, nuis.nrmse)
    notes: list[str] = []
    base_val = _baseline_validation(ctx, split)
    fitted = _fit_candidates(ctx, screened, nuis.nrmse, base_val, split, top, fit, say, notes)
    cands = [fitted.get(s.effect.name) or _screening_candidate(ctx, s, split) for s in screened]
    baseline_score, n_eff = _score_all(ctx, cands, split)
    tie = scoring.tie_relative(sum(n_eff.values()))
    ranked = scoring.order_candidates(cands, tie)
    for c in ranked:
        c.helps = scoring.helps(c, base_val, baseline_score, base.nrmse)
    return DiagnoseResult(
        base,
        ctx,
        ranked,
        skipped,
        nuis.nrmse,
        time.perf_counter() - t0,
        split,
        base_val,
        baseline_score,
        n_eff,
        tie,
        _warnings(ranked),
        notes,
    )


def _baseline_validation(ctx: Context, split: scoring.ValidationSplit) -> float:
    from .fitting import validation_nrmse

    sim = {o: ctx.meas[o] - ctx.residual[o] for o in ctx.meas.spec.outputs}
    return validation_nrmse(ctx.meas, sim, split.validation)
