"""How candidate effects are judged: the validation split, the score, the
tie rule and the stopping rule (docs/analysis.md, "Judging an effect").

**Validation split.** The record is cut into ``BLOCKS`` equal contiguous
blocks. With a held-out fraction f, block i (0-based) is held out when
``floor((i + 1) f) > floor(i f)``: the held-out blocks are spread evenly and
the first block (the start-up transient) is always used for estimation
(f = 0.3: blocks 3, 6, 9). Parameters are estimated on the other blocks; the
simulation always runs open loop over the whole record, so only which
residual samples count differs (no re-initialisation at block edges).

**Score.** A Bayesian information criterion of the contract's error measure
computed on the held-out validation blocks (on the whole record with
validation off):

    score = N ln(e^2) + k ln(N)

e: the overall validation nrmse, the mean over the outputs o of
e_o = sqrt(mse_o), mse_o the mean of ((measured - simulated) / std(measured))^2
over the validation samples; k: the number of parameters fitted (the
effect's and the co-estimated ones); N: the effective number of independent
samples, sum_o w_o n_eff,o with w_o = e_o / sum e_o, each output counted by
its share of the error. The validation error rewards what predicts data the
fit never saw; the k ln(N) term still makes an extra parameter pay for
itself. Residuals of a rig are correlated in time, so a sample is not an
independent observation: n_eff,o = n (1 - rho_o) / (1 + rho_o) with rho_o the
lag-1 autocorrelation of the residual (of the best-fitting candidate, the one
closest to the noise), clamped to [0, 0.999]. Lower is better. (A score that
summed each output's log error would let an output whose error is a
millionth of its spread, a driven speed that is pure kinematics, rank the
candidates by changes no reader of the nrmse could see.)

**Nested candidates.** A candidate that contains another as a special case
(Effect.nests) is ranked above it only when it beats it clearly: a score
lower by more than ``TIE_SCORE`` and a validation error lower by more than
the noise (:func:`beats_nested`). Otherwise the simpler one comes first.

**Tie.** Two candidates are within the noise of each other when their scores
differ by less than ``TIE_SCORE`` or their validation errors by less than
the relative standard error of an rms over the effective validation samples,
``1 / sqrt(2 sum_o n_eff,o)``, and at least ``TIE_RELATIVE`` (3 %: the spread
of the validation error between fits of equivalent structures on records of a
few thousand samples; a 1 % error of the co-estimated inertia moves it that
much). Neighbours in the score order that are within the noise of each other
are swapped until the one with fewer parameters comes first.

**Stopping rule** (:func:`helps`, shared by diagnose and report): an effect
helps when it was fitted, it lowers the validation error by at least
``HELP_MARGIN`` (relative) and the whole record's error, its score is lower
than the baseline's, and its fit has no ``negligible`` or ``inconsistent``
warning (the effect class judged the fitted size below what the record can
claim, or the residual contradicts the effect as fitted).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "BLOCKS",
    "DEFAULT_FRACTION",
    "TIE_SCORE",
    "TIE_RELATIVE",
    "HELP_MARGIN",
    "ValidationSplit",
    "split_record",
    "lag1_autocorrelation",
    "effective_samples",
    "normalized_mse",
    "bic_score",
    "within_noise",
    "tie_relative",
    "order_candidates",
    "helps",
]

BLOCKS = 10
DEFAULT_FRACTION = 0.3
TIE_SCORE = 2.0
TIE_RELATIVE = 0.03
HELP_MARGIN = 0.02
RHO_MAX = 0.999
#: warning kinds that keep a fitted candidate from helping: the effect
#: judged the fitted size below what the record can claim, or the residual
#: contradicts the fitted effect
REFUSED = ("negligible", "inconsistent")


@dataclass(frozen=True)
class ValidationSplit:
    """Which samples estimate and which validate.

    estimation / validation: boolean masks over the record (complementary
    when enabled; with validation off both are all True); blocks: the
    held-out block indices; fraction: the fraction asked for."""

    enabled: bool
    fraction: float
    estimation: np.ndarray
    validation: np.ndarray
    blocks: tuple[int, ...]

    def to_json(self) -> dict[str, Any]:
        return {
            "enabled": self.enabled,
            "fraction": self.fraction if self.enabled else 0.0,
            "blocks": BLOCKS,
            "held_out_blocks": list(self.blocks),
            "validation_samples": int(self.validation.sum()) if self.enabled else 0,
        }


def held_out_blocks(fraction: float, blocks: int = BLOCKS) -> tuple[int, ...]:
    """Indices of the held-out blocks (see the module docstring)."""
    return tuple(
        i for i in range(blocks) if math.floor((i + 1) * fraction) > math.floor(i * fraction)
    )


def split_record(
    n: int, enabled: bool = True, fraction: float = DEFAULT_FRACTION
) -> ValidationSplit:
    """The split of an n-sample record (fraction in (0, 0.5])."""
    if not enabled:
        every = np.ones(n, dtype=bool)
        return ValidationSplit(False, fraction, every, every, ())
    if not (0.0 < fraction <= 0.5):
        raise ValueError(f"validation fraction must be in (0, 0.5], got {fraction}")
    held = held_out_blocks(fraction)
    edges = np.linspace(0, n, BLOCKS + 1).round().astype(int)
    validation = np.zeros(n, dtype=bool)
    for i in held:
        validation[edges[i] : edges[i + 1]] = True
    return ValidationSplit(True, fraction, ~validation, validation, held)


def lag1_autocorrelation(x: np.ndarray) -> float:
    """sum(x_k x_{k+1}) / sum(x_k^2) of the mean-removed x (0 for fewer than 3 samples)."""
    x = np.asarray(x, dtype=float)
    if x.size < 3:
        return 0.0
    x = x - x.mean()
    den = float(np.dot(x, x))
    return float(np.dot(x[:-1], x[1:]) / den) if den > 0 else 0.0


def effective_samples(n: int, rho: float) -> float:
    """n (1 - rho) / (1 + rho), rho clamped to [0, RHO_MAX] (at least 1)."""
    r = min(max(rho, 0.0), RHO_MAX)
    return max(n * (1.0 - r) / (1.0 + r), 1.0)


def normalized_mse(residual: np.ndarray, scale: float, mask: np.ndarray) -> float:
    """mean((residual / scale)^2) over mask."""
    r = np.asarray(residual, dtype=float)[mask]
    s = scale if scale > 0 else 1.0
    return float(np.mean((r / s) ** 2)) if r.size else float("nan")


def bic_score(mse: Sequence[float], n_eff: Sequence[float], k: int) -> float:
    """N ln(e^2) + k ln(N): e the contract's overall error on the judged
    samples, the mean over the outputs of sqrt(mse_o); N the effective
    samples of the outputs weighted by their share of e (module docstring)."""
    e_o = [math.sqrt(max(m, 0.0)) for m in mse]
    e = sum(e_o) / max(len(e_o), 1)
    total = sum(e_o)
    if total > 0:
        n = sum(w * x for w, x in zip(e_o, n_eff, strict=True)) / total
    else:
        n = sum(n_eff) / max(len(n_eff), 1)
    n = max(n, 1.0)
    return float(n * math.log(max(e * e, 1e-300)) + k * math.log(n))


def tie_relative(n_eff_total: float) -> float:
    """The relative validation-error difference that is within the noise:
    the relative standard error of an rms over n_eff independent samples,
    1 / sqrt(2 n_eff), and at least TIE_RELATIVE."""
    return max(TIE_RELATIVE, 1.0 / math.sqrt(2.0 * max(n_eff_total, 1.0)))


def within_noise(a: Any, b: Any, relative: float = TIE_RELATIVE) -> bool:
    """Candidates a and b (with .score, .validation_nrmse_after) are within
    the noise of each other (module docstring)."""
    if abs(a.score - b.score) < TIE_SCORE:
        return True
    va, vb = a.validation_nrmse_after, b.validation_nrmse_after
    if va is None or vb is None or not (np.isfinite(va) and np.isfinite(vb)):
        return False
    return abs(va - vb) <= relative * min(va, vb)


def beats_nested(general: Any, special: Any, relative: float = TIE_RELATIVE) -> bool:
    """A candidate that contains another as a special case (its .nests names
    it) is preferred only when it beats it clearly: a lower score by more
    than TIE_SCORE and a validation error lower by more than the noise."""
    if not general.score < special.score - TIE_SCORE:
        return False
    va, vb = general.validation_nrmse_after, special.validation_nrmse_after
    if va is None or vb is None or not (np.isfinite(va) and np.isfinite(vb)):
        return False
    return bool(va < (1.0 - relative) * vb)


def _nested_first(fitted: list[Any], relative: float) -> bool:
    """Move a nested (simpler) candidate above the first more general one
    that does not beat it clearly; True when something moved."""
    for i, general in enumerate(fitted):
        for j in range(i + 1, len(fitted)):
            special = fitted[j]
            if special.effect in getattr(general, "nests", ()) and not beats_nested(
                general, special, relative
            ):
                fitted.insert(i, fitted.pop(j))
                return True
    return False


def order_candidates(cands: list[Any], relative: float = TIE_RELATIVE) -> list[Any]:
    """Fitted candidates by score, then screening estimates by score. Then,
    repeatedly, a neighbour pair within the noise of each other is swapped
    when the later one has fewer parameters (the simpler one first), and a
    candidate that nests another (a load- or temperature-dependent
    efficiency a constant one, Stribeck friction a Coulomb one) goes below it
    unless it beats it clearly (beats_nested). Sets .tied_with on each
    fitted candidate (the fitted ones within its noise)."""
    fitted = sorted((c for c in cands if c.method == "fit"), key=lambda c: c.score)
    screened = sorted((c for c in cands if c.method != "fit"), key=lambda c: c.score)
    swapped = True
    while swapped:
        swapped = False
        for i in range(len(fitted) - 1):
            a, b = fitted[i], fitted[i + 1]
            if b.n_parameters < a.n_parameters and within_noise(a, b, relative):
                fitted[i], fitted[i + 1] = b, a
                swapped = True
    for _ in range(len(fitted) ** 2):
        if not _nested_first(fitted, relative):
            break
    for c in fitted:
        c.tied_with = [o.effect for o in fitted if o is not c and within_noise(c, o, relative)]
    for c in screened:
        c.tied_with = []
    return fitted + screened


def helps(
    candidate: Any,
    baseline_validation_nrmse: float,
    baseline_score: float,
    baseline_nrmse: float | None = None,
) -> bool:
    """The one stopping rule of diagnose and report (module docstring).
    baseline_nrmse: the whole record's error before; the candidate must
    lower it too (an effect that helps the held-out blocks while the whole
    record gets worse is not accepted)."""
    if candidate is None or candidate.method != "fit":
        return False
    if baseline_nrmse is not None and not candidate.nrmse_after < baseline_nrmse:
        return False
    if any(w.get("kind") in REFUSED for w in getattr(candidate, "warnings", ())):
        return False  # the effect says the record cannot claim it, or contradicts it
    after = candidate.validation_nrmse_after
    if after is None or not np.isfinite(after):
        return False
    lowers = after <= (1.0 - HELP_MARGIN) * baseline_validation_nrmse
    return bool(lowers and candidate.score < baseline_score)
