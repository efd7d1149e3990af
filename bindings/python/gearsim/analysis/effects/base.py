"""The contract of an effect: the abstract :class:`Effect`, its frozen
:class:`Screening`, the fit's :class:`FitParam`, and the helpers every effect
module shares.

An effect class owns everything the analysis knows about one physical
effect, so that diagnose, fitting and report never test an effect's name:

- ``name``, ``blocks`` (rigs it applies to), ``summary``;
- ``unavailable(model)``: why it cannot be added (a combination the block
  cannot express), or None; ``present(model)``: whether the model has it;
- ``signature_text`` and ``columns(ctx)``: its residual signature and the
  screening regressors, with the physical bounds of their coefficients;
- ``screen(ctx)``: a frozen :class:`Screening` (a subclass of it when the
  effect's evidence is more than a regression): the error it predicts after
  fitting, the seeds, and why screening alone rules the effect out, if it
  does;
- ``parameters(ctx, screening)``: the fit's free parameters, bounds and seeds;
- ``coestimated(ctx, screening)`` / ``nuisance_columns(ctx)``: when the model
  already has the effect, the parameters re-estimated with a new effect that
  trades off against it, and their screening columns;
- ``build(ctx, values)``: the block and rig changes for parameter values;
- ``report(model)``: how its fitted parameters are reported;
- ``evidence(ctx, screening, model)``: what the screening saw, with a
  readable text; every number in the text is a field of the evidence (a
  property of the residual), a threshold it names, or a parameter of the
  fitted model (when ``model``, the fitted one, is given), and physically
  possible;
- ``excitation`` / ``separated_from``: the excitation that tells it apart from
  its look-alikes (identifiability warnings name it);
- ``negligible(ctx, model)``: why the fitted size is below what the record
  can claim (the candidate then does not help), or None;
- ``plot(ctx, ax)``: the signature plot of the report, when the general
  residual plots do not show it (None otherwise).

tests/python/analysis/test_check_effect.py checks every registered effect
against this contract the same way (check_effect).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from .. import modelkit as mk

__all__ = [
    "Changes",
    "Column",
    "FitParam",
    "Screening",
    "Effect",
    "DrivenInertia",
    "INERTIA",
    "present_mesh_loss",
]

#: what Effect.build returns: (block, rig) changes, or (block, rig, analysis)
#: for an effect that sets a key of the model file's [analysis] table
Changes = tuple[dict[str, Any], ...]
#: a screening column: (name, values over all samples, (lower, upper) bound
#: of its coefficient)
Column = tuple[str, np.ndarray, tuple[float, float]]


@dataclass
class FitParam:
    """One free parameter of a fit.

    name: the program name it is reported under ("load_coulomb_friction",
    "efficiency_vector[1]", ...); x0: first guess; lower/upper: bounds; unit:
    SI unit for texts; role: "effect" (new) or "coestimated"; owner: the
    effect (or "inertia") it belongs to; before: its value in the starting
    model; grid: multipliers of x0 tried (cost only) before the local fit, for
    costs that are not smooth; starts: absolute first guesses from each of
    which a local fit is run, the best kept (multi-start); optional: left at
    x0 in quick fits; diff_step: relative finite-difference step; log: fitted
    as its logarithm (a positive scale spanning decades: a stiffness, a
    speed threshold), which keeps the problem well scaled."""

    name: str
    x0: float
    lower: float
    upper: float
    unit: str = ""
    role: str = "effect"
    before: float | None = None
    owner: str = ""
    grid: tuple[float, ...] = ()
    starts: tuple[float, ...] = ()
    optional: bool = False
    diff_step: float = 1e-6
    log: bool = False

    def clipped_x0(self) -> float:
        return self.clip(self.x0)

    def clip(self, value: float) -> float:
        """value moved just inside the bounds (the optimiser needs a strictly
        feasible start)."""
        span = self.upper - self.lower
        eps = 1e-6 * (span if np.isfinite(span) else max(abs(value), 1.0))
        lo = self.lower + eps if np.isfinite(self.lower) else -np.inf
        hi = self.upper - eps if np.isfinite(self.upper) else np.inf
        return float(min(max(value, lo), hi))


@dataclass(frozen=True)
class Screening:
    """What screening saw of one effect on one baseline residual. Frozen:
    the fit seeds from it, the evidence and the ranking read it, nothing adds
    to it afterwards.

    predicted_nrmse: the overall nrmse screening predicts after the effect is
    added and fitted; regression: the bounded linear regression of the
    driven-side residual on the effect's and the co-estimated columns
    (gearsim.analysis.signatures.ScreenResult), None for an effect screened
    otherwise; ruled_out: why screening alone rules the effect out (it is
    then not fitted), or None. Effects whose evidence is more than a
    regression subclass it with their own fields."""

    predicted_nrmse: float
    regression: Any = None
    ruled_out: str | None = None

    def seed(self, name: str, default: float = 0.0) -> float:
        """The regression coefficient of column `name` (default when the
        column was not screened)."""
        reg = self.regression
        if reg is None or name not in reg.names:
            return default
        return reg.coefficient(name)


def seed_of(screening: Screening | None, name: str, default: float = 0.0) -> float:
    """screening.seed(name, default), default without a screening."""
    return default if screening is None else screening.seed(name, default)


# ---------------------------------------------------------------- helpers


def robust(x: np.ndarray, q: float = 99.0) -> float:
    return float(np.percentile(np.abs(x), q)) if x.size else 0.0


def force_scale(ctx: Any) -> float:
    """A typical driven-side force: robust max of the transmitted torque."""
    return max(robust(ctx.T), robust(ctx.meas[ctx.torque_output] / ctx.kin), 1e-9)


def speed_scale(ctx: Any) -> float:
    return max(robust(ctx.v), 1e-9)


def force_unit(model: Any) -> str:
    return "N*m" if mk.block_name(model) == "simple_gear" else "N"


def speed_unit(model: Any) -> str:
    return "rad/s" if mk.block_name(model) == "simple_gear" else "m/s"


def fmt(x: float) -> str:
    """A number for an evidence text: 4 significant digits, and never a
    negative zero."""
    x = float(x)
    return f"{x + 0.0:.4g}" if x != 0.0 else "0"


def present_mesh_loss(model: Any) -> float:
    """Present constant meshing loss 1 - eta (0 without an efficiency model)."""
    if mk.friction_model(model) == "constant_efficiency":
        return 1.0 - float(mk.block_values(model)["efficiency_const"])
    return 0.0


def eff_from_loss(loss: float) -> float:
    # the screening coefficient mixes 1-eta (overrunning) and 1/eta-1
    # (driving); their mean is ~ (1-eta)(1+1/eta)/2, close to 1-eta
    return float(min(max(1.0 - loss, 0.3), 1.0))


def as_coestimated(p: FitParam) -> FitParam:
    p.role = "coestimated"
    return p


def rig_has(model: Any, key: str) -> str | None:
    """None when this gearsim's rig has the parameter `key`, else why not."""
    if key in mk.rig_values(model):
        return None
    return f"this gearsim build has no rig parameter {key}"


def cached(ctx: Any, name: str, make: Callable[[], np.ndarray]) -> np.ndarray:
    """A derived per-sample signal, computed once per baseline context."""
    if name not in ctx.columns:
        ctx.columns[name] = make()
    return ctx.columns[name]


def own_regime(ctx: Any, part: np.ndarray) -> tuple[str | None, float]:
    """The regime where an effect's contribution is largest relative to its
    overall rms (regimes under 1 % of the samples, or 10, are skipped)."""
    tot = float(np.sqrt(np.mean(part**2))) if part.size else 0.0
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


# ---------------------------------------------------------------- the contract


class Effect(ABC):
    """One physical effect (see the module docstring). Subclasses set the
    class attributes and implement the abstract methods; the others have
    defaults that suit an effect screened by a linear regression."""

    name: ClassVar[str] = ""
    blocks: ClassVar[tuple[str, ...]] = ("simple_gear", "rack_pinion")
    summary: ClassVar[str] = ""
    signature_text: ClassVar[str] = ""
    #: number of parameters the effect adds (the fit may add optional ones)
    n_params: ClassVar[int] = 1
    #: effects whose model parameters this one replaces when added (they are
    #: then not re-estimated alongside it)
    replaces: ClassVar[tuple[str, ...]] = ()
    #: effects this one contains as a special case (nested): it is ranked
    #: above them only when its score beats theirs by more than the noise
    nests: ClassVar[tuple[str, ...]] = ()
    #: its simulation is costly (contact): the fit includes the driven-speed
    #: output and refines on a subsample of the residual
    costly: ClassVar[bool] = False
    #: the excitation that separates it from everything else, and from named
    #: look-alikes
    excitation: ClassVar[str] = ""
    separated_from: ClassVar[Mapping[str, str]] = {}
    internal_excitation: ClassVar[str] = ""
    #: plot(ctx, ax): draws the effect's signature on a matplotlib axis for
    #: the report (None: the report's general residual plots show it)
    plot: Callable[..., None] | None = None

    # -- applicability
    def unavailable(self, model: Any) -> str | None:
        return None

    @abstractmethod
    def present(self, model: Any) -> bool:
        """Whether the model has the effect."""

    def applies(self, model: Any) -> str | None:
        """Why the effect cannot be a candidate for model, or None."""
        blk = mk.block_name(model)
        if blk not in self.blocks:
            return f"does not apply to the {blk} rig"
        if self.present(model):
            return "already in the model"
        return self.unavailable(model)

    # -- screening
    def columns(self, ctx: Any) -> list[Column]:
        return []

    def regression(self, ctx: Any, own: list[Column] | None = None) -> Any:
        """The bounded linear regression of the driven-side residual on the
        co-estimated columns plus `own` (default: this effect's columns)."""
        from ..signatures import screen
        from .registry import nuisance_columns

        return screen(ctx, nuisance_columns(ctx, self), self.columns(ctx) if own is None else own)

    def screen(self, ctx: Any) -> Screening:
        """The screening of this effect on the baseline residual: the
        regression on the co-estimated columns plus its own."""
        reg = self.regression(ctx)
        return Screening(float(reg.nrmse), reg, None)

    # -- fitting
    @abstractmethod
    def parameters(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        """The fit's free parameters with their bounds and seeds."""

    @abstractmethod
    def build(self, ctx: Any, values: Mapping[str, float]) -> Changes:
        """The block and rig changes (and [analysis] keys) for parameter
        values; ({}, {}) when none of this effect's names is in values."""

    @abstractmethod
    def report(self, model: Any) -> dict[str, Any]:
        """The effect's parameters as the model file holds them."""

    def notes(self, model: Any) -> list[str]:
        """Notes on how the fit reads the effect (identifiability by design)."""
        return []

    def negligible(self, ctx: Any, model: Any) -> str | None:
        """Why the effect as fitted in `model` is too small for the record to
        claim it, although it may lower the error (then it does not help), or
        None."""
        return None

    def inconsistent(self, ctx: Any, model: Any) -> str | None:
        """Why the baseline residual contradicts the effect as fitted in
        `model` (it lowers the error by standing in for another: then it does
        not help), or None."""
        return None

    # -- when the model already has it
    def coestimated(self, ctx: Any, screening: Screening | None) -> list[FitParam]:
        """Its present parameters, re-estimated when another effect is added."""
        return []

    def nuisance_columns(self, ctx: Any) -> list[Column]:
        """Screening columns of the present parameters re-estimated with a new effect."""
        return []

    # -- evidence
    def evidence(self, ctx: Any, screening: Screening, model: Any = None) -> dict[str, Any]:
        """What the screening saw: partial correlation with the residual, the
        coefficients, the regime where the effect's part is largest, and a
        readable text. model: the model with the effect fitted, when it was
        (its parameters may then be quoted)."""
        reg = screening.regression
        nn = reg.nuisance
        own = {n: float(c) for n, c in zip(reg.names[nn:], reg.coef[nn:], strict=True)}
        regime, ratio = own_regime(ctx, reg.explained)
        r = float(reg.partial_r)
        ev: dict[str, Any] = {
            "signature": self.signature_text,
            "correlation": r,
            "explained_share": float(min(max(reg.r2_gain, 0.0), 1.0)),
            "coefficients": own,
            "regime": regime,
            "regime_ratio": ratio,
        }
        ev.update(self.evidence_extra(ctx, screening, own, model))
        seen = abs(r) >= 0.1 and bool(np.any(reg.explained))
        text = self.describe(ctx, ev, model) if seen else None
        if text is None:
            text = (
                f"no sign of it in the residual: {self.signature_text} is not seen "
                f"(partial correlation r = {r:.2f})"
            )
        ev["text"] = text
        return ev

    def describe(self, ctx: Any, ev: dict[str, Any], model: Any = None) -> str | None:
        """The evidence text from the evidence fields `ev` (and the fitted
        model's parameters); None when the fields show no sign of it."""
        return f"{self.signature_text} (r = {ev['correlation']:.2f}); largest in {ev['regime']}"

    def evidence_extra(
        self, ctx: Any, screening: Screening, own: dict[str, float], model: Any = None
    ) -> dict[str, Any]:
        """Fields of the evidence beyond the regression's (own: this effect's
        coefficients)."""
        return {}

    def __repr__(self) -> str:
        return f"<effect {self.name}>"


# ---------------------------------------------------------------- inertia


class DrivenInertia:
    """The driven inertia (follower_inertia / rack_mass), re-estimated with
    every new effect. Not an effect a model can lack; it only takes part in
    the co-estimation and the identifiability texts."""

    name = "inertia"
    excitation = "accelerate and decelerate hard at constant load"
    separated_from = {
        "meshing_efficiency": "hold constant speeds under load (no acceleration) and accelerate "
        "hard with no load",
        "viscous_friction": "hold at two speeds, then accelerate hard between them",
        "coulomb_friction": "accelerate hard within one direction of motion",
        "load_offset": "hold still under load, then accelerate hard",
    }

    def parameter(self, ctx: Any, screening: Screening | None) -> FitParam:
        key = mk.driven_inertia_key(ctx.model)
        j0 = float(mk.rig_values(ctx.model)[key])
        j = j0 + seed_of(screening, "acceleration", 0.0)
        j = j if j > 0 else j0
        unit = "kg*m^2" if key == "follower_inertia" else "kg"
        return FitParam(
            key, j, j0 * 1e-3, j0 * 1e3, unit, role="coestimated", before=j0, owner=self.name
        )

    def column(self, ctx: Any) -> Column:
        j0 = float(mk.rig_values(ctx.model)[mk.driven_inertia_key(ctx.model)])
        return ("acceleration", ctx.columns["acceleration"], (-0.999 * j0, 1e3 * j0))


INERTIA = DrivenInertia()
