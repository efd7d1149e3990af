"""How candidate effects are judged: the validation split, the score, the
tie rule and the stopping rule (docs/analysis.md, "Judging an effect").

**Validation split.** The record is cut into ``BLOCKS`` equal contiguous
blocks. With a held-out fraction f, block i (0-based) is held out when
``floor((i + 1) f) > floor(i f)``: the held-out blocks are spread evenly and
the first block (the start-up transient) is always used for estimation
(f = 0.3: blocks 3, 6, 9). Parameters are estimated on the other blocks; the
simulation always runs open loop over the whole record, so only which
residual samples count differs (no re-initialisation at block edges).

**Score.** A Bayesian information criterion computed on the held-out
validation blocks (on the whole record with validation off), per output o
with its own noise level:

    score = sum_o n_eff,o ln(mse_o) + k ln(sum_o n_eff,o)

mse_o: mean of ((measured - simulated) / std(measured))^2 over the validation
samples; k: the number of parameters fitted (the effect's and the co-estimated
ones). The validation error rewards what predicts data the fit never saw; the
k ln(n) term still makes an extra parameter pay for itself. Residuals of a rig
are correlated in time, so a sample is not an independent observation:
n_eff,o = n (1 - rho_o) / (1 + rho_o) with rho_o the lag-1 autocorrelation of
the residual (of the best-fitting candidate, the one closest to the noise),
clamped to [0, 0.999]. Lower is better.

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
``HELP_MARGIN`` (relative), its score is lower than the baseline's, and its
fit has no ``negligible`` warning (the effect class judged the fitted size
below what the record can claim, e.g. a delay under 1.5 samples).
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
    """sum_o n_eff,o ln(mse_o) + k ln(sum_o n_eff,o)."""
    data = sum(n * math.log(max(m, 1e-300)) for m, n in zip(mse, n_eff, strict=True))
    return float(data + k * math.log(max(sum(n_eff), 1.0)))


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


def order_candidates(cands: list[Any], relative: float = TIE_RELATIVE) -> list[Any]:
    """Fitted candidates by score, then screening estimates by score. Then,
    repeatedly, a neighbour pair within the noise of each other is swapped
    when the later one has fewer parameters (the simpler one first). Sets
    .tied_with on each fitted candidate (the fitted ones within its noise)."""
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
    for c in fitted:
        c.tied_with = [o.effect for o in fitted if o is not c and within_noise(c, o, relative)]
    for c in screened:
        c.tied_with = []
    return fitted + screened


def helps(candidate: Any, baseline_validation_nrmse: float, baseline_score: float) -> bool:
    """The one stopping rule of diagnose and report (module docstring)."""
    if candidate is None or candidate.method != "fit":
        return False
    if any(w.get("kind") == "negligible" for w in getattr(candidate, "warnings", ())):
        return False  # the effect says the record cannot claim it at the size fitted
    after = candidate.validation_nrmse_after
    if after is None or not np.isfinite(after):
        return False
    lowers = after <= (1.0 - HELP_MARGIN) * baseline_validation_nrmse
    return bool(lowers and candidate.score < baseline_score)
