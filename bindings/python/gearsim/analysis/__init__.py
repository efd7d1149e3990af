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
    r.accepted, r.verdict                # both errors fell? (one line)
    r.model.save("model-2.toml")
    refit(r.model, meas)                 # every effect the model has, together

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
from .threads import single_blas_thread

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
    "refit",
]


@single_blas_thread
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
    model; .accepted and .verdict say whether it lowered both the validation
    error and the whole record's). validation: estimate on the estimation
    blocks and report the error on the held-out ones
    (gearsim.analysis.scoring). max_samples: at most this many residual
    samples per fit, spread evenly over the whole record (the simulation
    always covers all of it). Raises EffectError for an unknown or
    inapplicable effect."""
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
    return fit_effect(ctx, effect, max_points=max_samples, validation=split, progress=progress)


@single_blas_thread
def refit(
    model,
    meas: Measurement,
    inputs: Inputs | None = None,
    *,
    input_filter="auto",
    max_samples: int | None = None,
    validation: bool = True,
    validation_fraction: float | None = None,
    progress=None,
) -> FitResult:
    """Re-fit together every effect `model` has (with the driven inertia), the
    final round after effects were added one by one; FitResult.effect is
    "refit". Raises EffectError when the model has no effect to re-fit."""
    from . import scoring
    from .effects import present_effects
    from .errors import EffectError
    from .fitting import refit_effects
    from .signatures import build_context

    if not present_effects(model):
        raise EffectError("refit: the model has no effect of docs/measurement-format.md section 3")
    if inputs is None:
        inputs = prepare_inputs(meas, input_filter)
    base = compare(model, meas, inputs)
    ctx = build_context(model, meas, inputs, base.sim, base.regime_masks)
    fraction = scoring.DEFAULT_FRACTION if validation_fraction is None else validation_fraction
    split = scoring.split_record(meas.n, validation, fraction)
    return refit_effects(ctx, max_points=max_samples, validation=split, progress=progress)
