"""diagnose: where the model fails, and which missing effect explains it.

1. compare: the baseline error, overall and per regime (which regimes fail).
2. screen: for every effect the model lacks, regress the driven-side residual
   on the effect's signature columns plus those of the parameters that would
   be re-estimated with it (gearsim.analysis.signatures). This predicts the
   error after fitting, seeds the fit and gives the evidence (correlation with
   the signature, coefficients, the regime where the effect shows most).
   Backlash is screened by the concentration of the residual after torque
   reversals and the gap the driven-speed residual integrates to.
3. fit: the best few screened candidates (``top``, plus backlash when its
   evidence is strong) are added and fitted on the C simulation
   (gearsim.analysis.fitting), which gives their error after fitting.
4. rank: by error after fitting, with a 3 % handicap per extra parameter so
   that an effect with more parameters (load- or temperature-dependent
   efficiency) only ranks above a simpler one that fits as well when it
   explains clearly more. Candidates that were only screened follow the
   fitted ones.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import modelkit as mk
from .compare import CompareResult, compare
from .effects import EFFECTS, Effect, applicable_effects, nuisance_columns, present_mesh_loss
from .fitting import FitResult, fit_effect, screen_effect
from .measurement import Measurement
from .signatures import BacklashEvidence, Context, ScreenResult, build_context, screen
from .simulate import Inputs, prepare_inputs

__all__ = ["Candidate", "DiagnoseResult", "diagnose", "PARAMETER_HANDICAP"]

PARAMETER_HANDICAP = 0.03
BACKLASH_STRENGTH = 1.5


@dataclass
class Candidate:
    """One missing effect: its error after being added, the parameters, how
    that was found ("fit" or "screening") and the evidence from the residual."""

    effect: str
    nrmse_after: float
    parameters: dict[str, Any]
    method: str
    evidence: dict[str, Any]
    score: float
    screen_nrmse: float
    fit: FitResult | None = None

    def to_json(self) -> dict:
        out = {
            "effect": self.effect,
            "nrmse_after": self.nrmse_after,
            "parameters": self.parameters,
            "method": self.method,
            "screen_nrmse": self.screen_nrmse,
            "score": self.score,
            "evidence": self.evidence,
        }
        if self.fit is not None:
            out["coestimated"] = {
                f["name"]: f["value"] for f in self.fit.fitted if f["role"] == "coestimated"
            }
            out["warnings"] = list(self.fit.warnings)
        return out


@dataclass
class DiagnoseResult:
    baseline: CompareResult
    context: Context
    candidates: list[Candidate]
    skipped: dict[str, str]
    reestimate_nrmse: float
    seconds: float
    notes: list[str] = field(default_factory=list)

    @property
    def baseline_nrmse(self) -> float:
        return self.baseline.nrmse

    @property
    def best(self) -> Candidate | None:
        return self.candidates[0] if self.candidates else None

    def to_json(self) -> dict:
        return {
            "baseline_nrmse": self.baseline.nrmse,
            "candidates": [c.to_json() for c in self.candidates],
            "reestimate_only_nrmse": self.reestimate_nrmse,
            "baseline_outputs": {k: v.nrmse for k, v in self.baseline.outputs.items()},
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


def _fmt(x: float) -> str:
    return f"{x:.4g}"


def _own_regime(ctx: Context, part: np.ndarray) -> tuple[str | None, float]:
    """The regime where an effect's contribution is largest relative to its
    overall rms."""
    tot = float(np.sqrt(np.mean(part**2)))
    best, ratio = None, 0.0
    if tot <= 0:
        return None, 0.0
    for reg in ctx.regimes:
        if reg.mask.sum() < max(10, 0.01 * reg.mask.size):
            continue
        r = float(np.sqrt(np.mean(part[reg.mask] ** 2))) / tot
        if r > ratio:
            best, ratio = reg.name, r
    return best, ratio


def _evidence_linear(ctx: Context, effect: Effect, sr: ScreenResult) -> dict[str, Any]:
    unit = ctx.meas.spec.driven_force_unit
    nn = sr.nuisance
    own = {n: float(c) for n, c in zip(sr.names[nn:], sr.coef[nn:], strict=True)}
    regime, ratio = _own_regime(ctx, sr.explained)
    ev: dict[str, Any] = {
        "signature": effect.signature_text,
        "correlation": sr.partial_r,
        "explained_share": sr.r2_gain,
        "coefficients": own,
        "regime": regime,
        "regime_ratio": ratio,
    }
    n = effect.name
    r = sr.partial_r
    if abs(r) < 0.1 or not np.any(sr.explained):
        ev["text"] = (
            f"no sign of it in the residual: {effect.signature_text} is not seen "
            f"(partial correlation r = {r:.2f})"
        )
        return ev
    if n == "coulomb_friction":
        fc = own.get("sign", 0.0)
        ev["text"] = (
            f"residual follows sign(speed) (r = {r:.2f}): a step of 2 x {_fmt(fc)} {unit} at each "
            f"direction reversal; largest in {regime}"
        )
    elif n == "viscous_friction":
        ev["text"] = (
            f"residual grows in proportion to speed (r = {r:.2f}, slope "
            f"{_fmt(own.get('speed', 0.0))} "
            f"{unit} per {ctx.meas.spec.driven_speed_unit} of driven speed); largest in {regime}"
        )
    elif n == "load_offset":
        bias = -own.get("constant", 0.0)
        per = []
        for reg in ctx.regimes:
            if reg.mask.any() and reg.name in (
                "driving",
                "overrunning",
                "direction_reversal",
                "high_speed",
            ):
                per.append(f"{reg.name} {_fmt(float(np.mean(ctx.r_d[reg.mask])))}")
        ev["text"] = (
            f"constant bias of the driven-side residual: {_fmt(bias)} {unit} of missing load "
            f"offset (r = {r:.2f}); mean residual by regime: {', '.join(per)}"
        )
    elif n == "meshing_efficiency":
        ev.update(_flow_split(ctx))
        ev["text"] = (
            f"residual proportional to |transmitted torque| x sign(speed) (r = {r:.2f}): "
            "loss factor "
            f"{_fmt(ev.get('loss_factor_driving', float('nan')))} while driving, "
            f"{_fmt(ev.get('loss_factor_overrunning', float('nan')))} while overrunning "
            f"(efficiency ~ {_fmt(1.0 - own.get('mesh', 0.0))}); largest in {regime}"
        )
    elif n == "load_dependent_efficiency":
        idle = own.get("idle", 0.0)
        k = own.get("mesh", 0.0)
        tmax = float(np.percentile(np.abs(ctx.T), 95)) or 1.0
        eff = {}
        for frac in (0.1, 1.0):
            t = frac * tmax
            eff[f"{int(frac * 100)}%"] = t / (t + idle + k * t) if t > 0 else float("nan")
        ev["efficiency_at_load"] = eff
        ev["text"] = (
            f"loss = {_fmt(idle)} {unit} at no load + {_fmt(k)} x |transmitted torque| (r = "
            f"{r:.2f}): "
            f"efficiency {_fmt(eff['10%'])} at 10 % of the peak load vs {_fmt(eff['100%'])} at "
            f"the peak; largest in {regime}"
        )
    elif n == "temperature_dependent_efficiency":
        L0 = present_mesh_loss(ctx.model)
        pts = []
        for name, c in own.items():
            pts.append(f"{1.0 - (L0 + c):.3f} at {name.split('@')[1]}")
        span = float(np.ptp(ctx.temperature))
        ev["temperature_span_K"] = span
        ev["temperature_source"] = ctx.temperature_source
        ev["text"] = (
            f"the torque-proportional loss changes with temperature (r = {r:.2f}): efficiency "
            f"{', '.join(pts)} ({ctx.temperature_source} temperature spans {span:.1f} K); largest "
            f"in {regime}"
        )
    return ev


def _flow_split(ctx: Context) -> dict[str, float]:
    """Mesh-loss coefficient fitted separately where the drive drives the load
    and where the load overruns (power-flow direction)."""
    x = ctx.columns["mesh"]
    y = ctx.r_d
    # remove the inertia part first
    a = ctx.columns["acceleration"]
    p = ctx.T * ctx.v
    out = {}
    for name, m in (("driving", p < 0), ("overrunning", p > 0)):
        if m.sum() < 20:
            continue
        A = np.column_stack([x[m], a[m]])
        coef, *_ = np.linalg.lstsq(A, y[m], rcond=None)
        out[f"loss_factor_{name}"] = float(coef[0])
    return out


def _evidence_backlash(ctx: Context, be: BacklashEvidence) -> dict[str, Any]:
    ms = be.window * ctx.meas.dt * 1e3
    conc = {k: float(v) for k, v in be.concentration.items()}
    so = ctx.speed_output
    return {
        "signature": EFFECTS["backlash"].signature_text,
        "reversals": int(be.events.size),
        "window_ms": ms,
        "time_fraction": be.time_fraction,
        "concentration": conc,
        "gap_estimate_m": be.gap_estimate,
        "regime": "torque_reversal",
        "text": (
            f"{100 * be.time_fraction:.1f} % of the time (the {ms:.0f} ms after "
            f"{be.events.size} torque "
            f"reversals) holds {conc.get(so, 0) * be.time_fraction * 100:.0f} % of the {so} "
            "residual "
            f"energy ({conc.get(so, 0):.1f}x its share) and "
            f"{conc.get(ctx.torque_output, 0) * be.time_fraction * 100:.0f} % of the "
            f"{ctx.torque_output} residual energy; the {so} residual integrates to a gap of "
            f"{be.gap_estimate * 1e3:.3g} mm"
        ),
    }


def diagnose(
    model: Any,
    meas: Measurement,
    inputs: Inputs | None = None,
    *,
    input_filter: float | str | None = "auto",
    top: int = 3,
    fit: bool = True,
    progress: Callable[[str], None] | None = None,
) -> DiagnoseResult:
    """Rank the effects the model lacks (see the module docstring)."""
    t0 = time.perf_counter()
    say = progress or (lambda s: None)
    if inputs is None:
        inputs = prepare_inputs(meas, input_filter)
    say("compare: simulating the model on the measured inputs")
    base = compare(model, meas, inputs)
    ctx = build_context(model, meas, inputs, base.sim, base.regime_masks)
    effects, skipped = applicable_effects(model)
    nuis = screen(ctx, nuisance_columns(ctx, None), [])
    say(
        f"screen: {len(effects)} candidate effects on the residual "
        f"(baseline nrmse {base.nrmse:.4f}, re-estimating present parameters alone "
        f"{nuis.nrmse:.4f})"
    )
    notes: list[str] = []
    screened: dict[str, tuple[Effect, Any, float, dict]] = {}
    for eff in effects:
        sr = screen_effect(ctx, eff)
        if isinstance(sr, BacklashEvidence):
            ev = _evidence_backlash(ctx, sr)
            pred = sr.predicted_nrmse if sr.strength >= BACKLASH_STRENGTH else nuis.nrmse
        else:
            if eff.name == "temperature_dependent_efficiency" and not sr.names[sr.nuisance :]:
                span = float(np.ptp(ctx.temperature))
                ev = {
                    "signature": eff.signature_text,
                    "temperature_span_K": span,
                    "temperature_source": ctx.temperature_source,
                    "text": f"the {ctx.temperature_source} temperature spans only {span:.2f} K: a "
                    f"temperature dependence cannot be seen in this record",
                }
                pred = nuis.nrmse
            else:
                ev = _evidence_linear(ctx, eff, sr)
                pred = sr.nrmse
        screened[eff.name] = (eff, sr, pred, ev)

    def handicap(eff: Effect) -> float:
        return 1.0 + PARAMETER_HANDICAP * (eff.n_params - 1)

    order = sorted(screened, key=lambda k: screened[k][2] * handicap(screened[k][0]))
    to_fit: list[str] = []
    if fit:
        for name in order:
            if len(to_fit) >= top:
                break
            pred = screened[name][2]
            # no point fitting what the residual shows no sign of
            if to_fit and pred >= 0.98 * nuis.nrmse:
                continue
            if name == "backlash" and not (screened[name][1].strength >= BACKLASH_STRENGTH):
                continue
            to_fit.append(name)
        if (
            "backlash" in screened
            and "backlash" not in to_fit
            and screened["backlash"][1].strength >= BACKLASH_STRENGTH
        ):
            to_fit.append("backlash")
    cands: list[Candidate] = []
    for name in order:
        eff, sr, pred, ev = screened[name]
        if name in to_fit:
            say(f"fit: {name} (screening predicts nrmse {pred:.4f})")
            try:
                fr = fit_effect(ctx, name, screen_result=sr, max_nfev=20 * (eff.n_params + 2))
            except Exception as exc:  # a candidate that cannot be fitted is reported, not fatal
                notes.append(f"{name}: fit failed ({exc}); screening estimate kept")
                fr = None
            if fr is not None:
                cands.append(
                    Candidate(
                        name,
                        fr.nrmse_after,
                        fr.parameters,
                        "fit",
                        ev,
                        fr.nrmse_after * handicap(eff),
                        pred,
                        fr,
                    )
                )
                continue
        params = _screen_parameters(ctx, eff, sr)
        cands.append(Candidate(name, pred, params, "screening", ev, pred * handicap(eff), pred))

    # fitted and improving first, then screened only, then fitted without gain
    def improves(c: Candidate) -> bool:
        return c.nrmse_after < 0.995 * base.nrmse

    fitted = sorted((c for c in cands if c.method == "fit" and improves(c)), key=lambda c: c.score)
    rest = sorted((c for c in cands if c.method != "fit"), key=lambda c: c.score)
    worse = sorted(
        (c for c in cands if c.method == "fit" and not improves(c)), key=lambda c: c.score
    )
    for c in worse:
        c.evidence["note"] = "fitting it did not lower the error"
    return DiagnoseResult(
        base, ctx, fitted + rest + worse, skipped, nuis.nrmse, time.perf_counter() - t0, notes
    )


def _screen_parameters(ctx: Context, eff: Effect, sr: Any) -> dict[str, Any]:
    """The effect's parameters as the screening seeds them (not fitted), in
    the same form as a fitted candidate's (program names, model values)."""
    try:
        values = {p.name: p.clipped_x0() for p in eff.parameters(ctx, sr)}
        block, rig = eff.build(ctx, values)
        return eff.report(mk.changed(ctx.model, block, rig))
    except Exception:  # a seed the block refuses: show the raw seeds
        try:
            return {p.name: p.clipped_x0() for p in eff.parameters(ctx, sr)}
        except Exception:  # pragma: no cover - defensive
            return {}
