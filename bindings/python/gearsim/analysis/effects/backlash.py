"""Backlash: a gap in the mesh. No linear signature: its evidence is residual
energy concentrated right after reversals of the transmitted torque, and a
driven-speed residual whose integral over such a window is the gap
(:func:`backlash_evidence`)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from .. import modelkit as mk
from ..regimes import sign_changes
from .base import Changes, Effect, FitParam, Screening


@dataclass(frozen=True)
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


def backlash_evidence(ctx: Any) -> BacklashEvidence:
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


#: relative finite-difference step of the contact's parameters: a gap, a
#: stiffness or a damping changed by less moves the impacts by less than a
#: contact sub-step, and the cost then changes in steps, not smoothly (a
#: 1e-3 step made the fit stop in such a step on an external test record,
#: 1.7x its noise floor; 1e-2 reaches 1.4x from the same start)
CONTACT_DIFF_STEP = 1e-2


@dataclass(frozen=True)
class BacklashScreening(Screening):
    """Backlash's screening: the residual's concentration after reversals."""

    evidence: BacklashEvidence | None = None


class Backlash(Effect):
    name = "backlash"
    summary = (
        "backlash: a gap in the mesh, with the contact's stiffness and damping and, unless the "
        "model gives another law, the smooth law's onset (transition_region)"
    )
    signature_text = (
        "residual concentrated right after reversals of the transmitted torque, with a "
        "driven-speed residual whose integral is the gap"
    )
    costly = True
    excitation = "dwell at zero speed, then reverse the load slowly"
    separated_from: ClassVar[Mapping[str, str]] = {}
    #: what separates its own parameters (gap, contact stiffness, damping)
    internal_excitation = (
        "reverse the load slowly (the gap shows) and quickly (contact stiffness and damping show)"
    )
    #: concentration of the driven-speed residual after reversals below which
    #: the screening rules backlash out (~1 without backlash-like physics)
    MIN_STRENGTH = 1.5
    #: local fits started from this many gaps spread over the evidence's range
    STARTS = 5

    def present(self, model: Any) -> bool:
        return bool(mk.block_values(model).get("backlash_enabled", False))

    def unavailable(self, model: Any) -> str | None:
        if float(mk.rig_values(model).get("compliance_stiffness", 0.0)) > 0.0:
            return "backlash needs a rigid base shaft (the model has a compliant one)"
        return None

    def screen(self, ctx: Any) -> BacklashScreening:
        be = backlash_evidence(ctx)
        why = None
        if be.strength < self.MIN_STRENGTH:
            why = (
                f"the driven-speed residual is not concentrated after reversals "
                f"({be.strength:.2f}x its share, {self.MIN_STRENGTH}x needed)"
            )
        return BacklashScreening(float(be.predicted_nrmse), None, why, be)

    def start_gaps(self, be: BacklashEvidence | None) -> tuple[float, ...]:
        """First guesses of the gap (m): geometric steps over the range the
        evidence gives, widened by 2 on each side (the integral of the speed
        residual over a window under- or over-shoots the gap)."""
        lo, hi = be.gap_range if be is not None else (0.0, 0.0)
        if not (np.isfinite(lo) and np.isfinite(hi)) or hi <= 0:
            return (1e-4, 3e-4, 1e-3, 3e-3)
        lo = max(lo, 0.05 * hi, 1e-7)
        return tuple(float(g) for g in np.geomspace(0.5 * lo, 2.0 * hi, self.STARTS))

    def parameters(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        be = getattr(screening, "evidence", None)
        gap = be.gap_estimate if be is not None else None
        if not gap or not np.isfinite(gap) or gap <= 0:
            gap = 1e-3
        v = mk.block_values(ctx.model)
        k0, d0 = float(v["stiffness"]), float(v["damping"])
        o = self.name
        onset = self._onset(ctx, float(gap))
        return onset + [
            FitParam(
                "linear_backlash",
                float(gap),
                1e-7,
                max(100.0 * gap, 0.05),
                "m",
                owner=o,
                starts=self.start_gaps(be),
                diff_step=CONTACT_DIFF_STEP,
            ),
            # stiffness and damping span decades: fitted as logarithms, each
            # start of the gap searching them on a coarse grid first (a grid
            # tried once, at the seed gap, chose a compromise with that gap
            # that the local fit could not leave)
            FitParam(
                "stiffness",
                k0,
                1e-3 * k0,
                1e3 * k0,
                "N/m",
                owner=o,
                grid=(0.1, 0.3, 1.0, 3.0),
                optional=True,
                diff_step=CONTACT_DIFF_STEP,
                log=True,
            ),
            FitParam(
                "damping",
                max(d0, 1e-3),
                1e-3,
                1e3 * max(d0, 1.0),
                "N*s/m",
                owner=o,
                grid=(0.3, 1.0, 3.0),
                optional=True,
                diff_step=CONTACT_DIFF_STEP,
                log=True,
            ),
        ]

    #: the range of the smooth law's onset, as a fraction of the gap: from a
    #: contact that is a spring from first touch (the full_damped law's) to a
    #: soft one
    ONSET = (1e-3, 0.25)

    def _onset(self, ctx: Any, gap: float) -> list[FitParam]:
        """The smooth law's transition region as a fraction of the gap, fitted
        when the model leaves the law to the fit (no hard_stop_model given)
        or gives the smooth one: real meshes differ in how the contact force
        starts, from a linear spring at first touch (a compliant mesh with a
        gap) to a soft onset, and the record tells them apart (2.6x against
        1.0x the noise floor on an external test record)."""
        v = mk.block_values(ctx.model)
        law = v.get("hard_stop_model", "smooth")
        if "hard_stop_model" in ctx.model.block_params and law != "smooth":
            return []
        lo, hi = self.ONSET
        if "transition_region" in ctx.model.block_params:
            x0 = min(max(float(v["transition_region"]) / gap, lo), hi)
            grid: tuple[float, ...] = ()
        else:
            x0, grid = 0.1, (0.01, 0.1, 1.0, 2.5)
        return [
            FitParam(
                "transition_fraction",
                x0,
                lo,
                hi,
                "",
                owner=self.name,
                grid=grid,
                optional=True,
                diff_step=CONTACT_DIFF_STEP,
                log=True,
            )
        ]

    def build(self, ctx: Any, values: Mapping[str, float]) -> Changes:
        if "linear_backlash" not in values:
            return {}, {}
        b = float(values["linear_backlash"])
        v = mk.block_values(ctx.model)
        block: dict[str, Any] = {"backlash_enabled": True, "linear_backlash": b}
        for key in ("stiffness", "damping"):
            if key in values:
                block[key] = float(values[key])
        if "transition_fraction" in values:
            block["hard_stop_model"] = "smooth"
            block["transition_region"] = float(values["transition_fraction"]) * b
        elif v.get("hard_stop_model", "smooth") == "smooth":
            d = float(v.get("transition_region", 1e-4))
            if d >= 0.25 * b:
                block["transition_region"] = 0.25 * b
        # Behind the contact's spring the driven side's frictions (the load's
        # and the meshing loss) creep rather than hold, as behind a compliance:
        # the set-valued laws held at each contact reversal where measured
        # rigs and the outside records' simulator slide (docs/analysis.md).
        return block, {"load_friction_regularised": True}

    def report(self, model: Any) -> dict[str, Any]:
        v = mk.block_values(model)
        out = {k: v[k] for k in ("linear_backlash", "stiffness", "damping", "hard_stop_model")}
        if v["hard_stop_model"] == "smooth":
            out["transition_region"] = v["transition_region"]
        if mk.block_name(model) == "simple_gear":
            out["base_radius"] = v["base_radius"]
        return out

    def coestimated(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        # the present gap, stiffness and damping are re-estimated with a new
        # effect: fitted without it (a friction missing), the contact absorbs
        # part of the missing loss
        v = mk.block_values(ctx.model)
        out = []
        for p in self.parameters(ctx, None):
            if p.name == "transition_fraction":
                if v["hard_stop_model"] != "smooth":
                    continue
                now = float(v["transition_region"]) / float(v["linear_backlash"])
            else:
                now = float(v[p.name])
            p.x0, p.before, p.role = now, now, "coestimated"
            p.lower, p.upper = min(p.lower, now), max(p.upper, now)
            p.starts, p.grid, p.optional = (), (), False
            out.append(p)
        return out

    def evidence(self, ctx: Any, screening: Screening, model: Any = None) -> dict[str, Any]:
        if not isinstance(screening, BacklashScreening):
            raise TypeError(f"{self.name}: evidence needs this effect's own screening")
        be = screening.evidence
        if be is None:  # screen() sets it
            raise ValueError(f"{self.name}: the screening lacks its evidence")
        ms = be.window * ctx.meas.dt * 1e3
        conc = {k: float(v) for k, v in be.concentration.items()}
        share = {k: float(v) * be.time_fraction for k, v in conc.items()}
        so, to = ctx.speed_output, ctx.torque_output
        ev: dict[str, Any] = {
            "signature": self.signature_text,
            "reversals": int(be.events.size),
            "window_ms": ms,
            "time_fraction": be.time_fraction,
            "concentration": conc,
            "energy_share": share,
            "gap_estimate_m": be.gap_estimate,
            "gap_range_m": list(be.gap_range),
            "min_strength": self.MIN_STRENGTH,
            "regime": "torque_reversal",
        }
        ev["text"] = (
            f"{100 * be.time_fraction:.1f} % of the time (the {ms:.0f} ms after "
            f"{be.events.size} torque reversals) holds {100 * share.get(so, 0):.0f} % of the {so} "
            f"residual energy ({conc.get(so, 0):.1f}x its share) and "
            f"{100 * share.get(to, 0):.0f} % of the {to} residual energy; the {so} residual "
            f"integrates to a gap of {be.gap_estimate * 1e3:.3g} mm"
        )
        if model is not None and self.present(model):
            gap = float(mk.block_values(model)["linear_backlash"])
            ev["fitted_gap_m"] = gap
            ev["text"] += f" (fitted: {gap * 1e3:.3g} mm)"
        return ev
