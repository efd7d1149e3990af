"""Identifiability warnings: what the record cannot tell apart, and which
excitation would (docs/analysis.md, "Identifiability").

Every warning is a dict with ``kind``, ``text`` (one readable line) and the
names involved (``parameters`` and/or ``effects``) plus ``excitation`` when
one separates them. Kinds:

- ``coestimate_moved``: a co-estimated parameter moved more than
  ``MOVE_LIMIT`` (relative) from its value in the starting model: the new
  effect may be absorbing it, or it absorbing the effect;
- ``not_identifiable``: a combination of fitted parameters the record cannot
  determine (a direction of the scaled Jacobian whose standard deviation
  exceeds its own size, or whose singular value is zero): the parameters are
  named, get no standard deviation, and the excitation that would separate
  them is given; never reported as a correlation of 1.000 with a tiny std;
- ``correlated``: two identifiable parameters correlate with |r| >
  ``CORRELATION_LIMIT`` (from the Jacobian at the solution);
- ``at_bound``: a parameter ended at a bound of its range;
- ``tie``: two effects explain the data equally (scoring.within_noise);
- ``not_converged``, ``no_gain`` (the validation or the whole record's error
  did not fall: not accepted): the fit itself;
- ``negligible``: the effect as fitted is below what the record can claim
  (Effect.negligible; such a candidate does not help).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .effects import FitParam, separating_excitation

__all__ = [
    "MOVE_LIMIT",
    "CORRELATION_LIMIT",
    "correlation_matrix",
    "parameter_warnings",
    "correlated_warnings",
    "unidentifiable_warning",
    "tie_warning",
    "warning",
]

MOVE_LIMIT = 0.25
CORRELATION_LIMIT = 0.95


def warning(kind: str, text: str, **names: Any) -> dict[str, Any]:
    return {"kind": kind, "text": text, **names}


def correlation_matrix(jac: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Correlation matrix and relative standard deviations from a Jacobian:
    cov ~ pinv(J^T J); returns (corr, sqrt(diag(cov)))."""
    cov = np.linalg.pinv(jac.T @ jac)
    d = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(d, d)
    return corr, d


def _moved(p: FitParam, value: float) -> dict[str, Any] | None:
    if p.role != "coestimated" or not p.before:
        return None
    change = (value - p.before) / abs(p.before)
    if abs(change) <= MOVE_LIMIT:
        return None
    return warning(
        "coestimate_moved",
        f"{p.name} moved {100 * change:+.0f} % from {p.before:.4g} to {value:.4g} "
        f"(more than {100 * MOVE_LIMIT:.0f} %): check it against an independent measurement",
        parameters=[p.name],
        effects=[p.owner],
    )


def _at_bound(p: FitParam, value: float, active: int, scale: float) -> dict[str, Any] | None:
    def near(bound: float) -> bool:
        return bool(np.isfinite(bound) and abs(value - bound) <= 1e-3 * max(abs(bound), scale))

    side = None
    if active < 0 or near(p.lower):
        side, bound = "lower", p.lower
    elif active > 0 or near(p.upper):
        side, bound = "upper", p.upper
    if side is None:
        return None
    return warning(
        "at_bound",
        f"{p.name} = {value:.6g} stays at its {side} bound ({bound:.6g}): not identifiable "
        "from this record",
        parameters=[p.name],
        effects=[p.owner],
        bound=side,
    )


def unidentifiable_warning(params: Sequence[FitParam], effect: str) -> dict[str, Any]:
    """The parameters of one direction the record cannot determine, and the
    excitation that would separate them."""
    owners = list(dict.fromkeys(p.owner or effect for p in params))
    if len(owners) >= 2:
        how = separating_excitation(owners[0], owners[1])
    else:
        how = separating_excitation(owners[0], owners[0])
    names = [p.name for p in params]
    if len(names) == 1:
        what = f"{names[0]} changes the error too little to be determined"
    else:
        what = (
            f"{', '.join(names[:-1])} and {names[-1]} can move together without changing the error"
        )
    return warning(
        "not_identifiable",
        f"not identifiable from this record: {what}; the values are where the fit stopped, "
        f"not measurements; to separate them: {how}",
        parameters=names,
        effects=sorted(set(owners)),
        excitation=how,
    )


def correlated_warnings(params: Sequence[FitParam], corr: np.ndarray, effect: str) -> list[dict]:
    """Pairs of identifiable parameters correlated above CORRELATION_LIMIT."""
    return _correlated(params, corr, effect)


def _correlated(params: Sequence[FitParam], corr: np.ndarray, effect: str) -> list[dict]:
    out = []
    for i in range(len(params)):
        for j in range(i + 1, len(params)):
            c = corr[i, j]
            if not (np.isfinite(c) and abs(c) > CORRELATION_LIMIT):
                continue
            a, b = params[i], params[j]
            how = separating_excitation(a.owner or effect, b.owner or effect)
            out.append(
                warning(
                    "correlated",
                    f"{a.name} and {b.name} are strongly correlated (r = {c:+.3f}, above "
                    f"{CORRELATION_LIMIT}): the record cannot tell them apart; to separate "
                    f"them: {how}",
                    parameters=[a.name, b.name],
                    effects=sorted({a.owner or effect, b.owner or effect}),
                    correlation=float(c),
                    excitation=how,
                )
            )
    return out


def parameter_warnings(
    params: Sequence[FitParam],
    x: np.ndarray,
    active: np.ndarray,
    scales: np.ndarray,
    effect: str,
) -> list[dict[str, Any]]:
    """Bound and co-estimate warnings of one fit. For a moved co-estimated
    parameter, the excitation that separates its owner from the new effect
    is added."""
    out: list[dict[str, Any]] = []
    for i, p in enumerate(params):
        w = _at_bound(p, float(x[i]), int(active[i]), float(scales[i]))
        if w:
            out.append(w)
        w = _moved(p, float(x[i]))
        if w:
            how = separating_excitation(p.owner, effect)
            w["text"] += f"; to separate it from {effect}: {how}"
            w["effects"] = sorted({p.owner, effect})
            w["excitation"] = how
            out.append(w)
    return out


def tie_warning(a: Any, b: Any) -> dict[str, Any]:
    """Two candidates (.effect, .score, .validation_nrmse_after) explain the data equally."""
    how = separating_excitation(a.effect, b.effect)
    return warning(
        "tie",
        f"{a.effect} and {b.effect} explain the data equally (scores {a.score:.1f} and "
        f"{b.score:.1f}, validation nrmse {a.validation_nrmse_after:.4g} and "
        f"{b.validation_nrmse_after:.4g}): within the noise, the simpler is listed first; to "
        f"separate them: {how}",
        effects=[a.effect, b.effect],
        excitation=how,
    )
