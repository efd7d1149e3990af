"""gearsim.analysis: model versus measurement.

compare a model with a measurement, see in which operating regimes it fails,
find the missing physical effect from the residual's signature, fit it on the
C simulation and watch the error fall (docs/analysis.md).

    from gearsim.analysis import load_measurement, load_model, compare, diagnose, fit

    model = load_model("model.toml")   # a gearsim.Model plus its [analysis] table
    meas = load_measurement("run.csv", model.block)
    print(compare(model, meas).nrmse)
    d = diagnose(model, meas)
    r = fit(model, meas, d.best.effect)
    r.model.save("model-2.toml")

The command line (``gearsim compare|diagnose|fit|report``) is a thin shell
over these functions (gearsim.cli).
"""

from __future__ import annotations

from .compare import CompareResult, compare
from .diagnose import Candidate, DiagnoseResult, diagnose
from .effects import EFFECT_NAMES, EFFECTS
from .errors import AnalysisError, EffectError, MeasurementError
from .fitting import FitResult
from .measurement import RIG_SPECS, Measurement, load_measurement, write_measurement
from .metrics import OutputMetrics, nrmse, output_metrics
from .modelkit import AnalysisModel, load_model
from .simulate import Inputs, prepare_inputs, simulate

__all__ = [
    "compare",
    "CompareResult",
    "diagnose",
    "DiagnoseResult",
    "Candidate",
    "fit",
    "FitResult",
    "EFFECT_NAMES",
    "EFFECTS",
    "MeasurementError",
    "EffectError",
    "AnalysisError",
    "Measurement",
    "load_measurement",
    "write_measurement",
    "load_model",
    "AnalysisModel",
    "RIG_SPECS",
    "OutputMetrics",
    "nrmse",
    "output_metrics",
    "Inputs",
    "prepare_inputs",
    "simulate",
]


def fit(
    model,
    meas: Measurement,
    effect: str,
    inputs: Inputs | None = None,
    *,
    input_filter="auto",
    max_samples: int | None = None,
    validation: bool = True,
    validation_fraction: float | None = None,
    progress=None,
) -> FitResult:
    """Add `effect` to `model`, fit it (and the parameters that trade off
    against it) on `meas`, and return the FitResult (its .model is the new
    model). validation: estimate on the estimation blocks and report the
    error on the held-out ones (gearsim.analysis.scoring). Raises EffectError
    for an unknown or inapplicable effect."""
    from . import scoring
    from .effects import get_effect
    from .fitting import fit_effect
    from .signatures import build_context

    get_effect(effect, model)
    if inputs is None:
        inputs = prepare_inputs(meas, input_filter)
    base = compare(model, meas, inputs)
    ctx = build_context(model, meas, inputs, base.sim, base.regime_masks)
    fraction = scoring.DEFAULT_FRACTION if validation_fraction is None else validation_fraction
    split = scoring.split_record(meas.n, validation, fraction)
    return fit_effect(ctx, effect, max_samples=max_samples, validation=split, progress=progress)
