"""compare: simulate a model open-loop on a measurement and report its errors,
overall and per operating regime."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .measurement import Measurement
from .metrics import OutputMetrics, output_metrics
from .regimes import FAILING_RATIO, Regime, regime_errors, segment
from .signals import noise_rms
from .simulate import Inputs, Simulation, prepare_inputs, simulate

__all__ = ["CompareResult", "compare"]


@dataclass
class CompareResult:
    """Errors of a model on a measurement.

    outputs: metrics per output column; nrmse: their mean (contract); regimes:
    regime_errors() entries; sim: the simulation; inputs: the conditioned
    inputs it ran on."""

    model: Any
    meas: Measurement
    inputs: Inputs
    sim: Simulation
    outputs: dict[str, OutputMetrics]
    nrmse: float
    regimes: list[dict]
    regime_masks: list[Regime]

    @property
    def residuals(self) -> dict[str, np.ndarray]:
        return {o: self.meas[o] - self.sim.outputs[o] for o in self.meas.spec.outputs}

    @property
    def failing_regimes(self) -> list[dict]:
        return sorted((r for r in self.regimes if r["failing"]), key=lambda r: -r["worst_ratio"])

    def to_json(self) -> dict:
        return {
            "outputs": {
                k: {
                    "nrmse": v.nrmse,
                    "rmse": v.rmse,
                    "max_abs": v.max_abs,
                    "t_max_abs": v.t_max_abs,
                    "fit_percent": v.fit_percent,
                    "bias": v.bias,
                    "std": v.std,
                }
                for k, v in self.outputs.items()
            },
            "nrmse": self.nrmse,
            "fit_percent": 100.0 * (1.0 - self.nrmse),
            "samples": self.meas.n,
            "dt": self.meas.dt,
            "input_filter_hz": dict(self.inputs.cutoffs),
            "regimes": self.regimes,
            "failing_regimes": [r["regime"] for r in self.failing_regimes],
            "failing_ratio": FAILING_RATIO,
        }


def compare(
    model: Any,
    meas: Measurement,
    inputs: Inputs | None = None,
    *,
    input_filter: float | str | None = "auto",
    regimes: bool = True,
) -> CompareResult:
    """Simulate model on meas's inputs and measure the error of each output
    (docs/measurement-format.md section 4), overall and per regime."""
    if inputs is None:
        inputs = prepare_inputs(meas, input_filter)
    sim = simulate(model, meas, inputs)
    outs = {o: output_metrics(meas[o], sim.outputs[o], meas.time) for o in meas.spec.outputs}
    nr = float(np.mean([m.nrmse for m in outs.values()]))
    masks: list[Regime] = []
    reg: list[dict] = []
    if regimes:
        temp = None if meas.has_temperature else sim.signals.get("temperature")
        masks = segment(meas, temperature=temp)
        res = {o: meas[o] - sim.outputs[o] for o in meas.spec.outputs}
        noise = {o: noise_rms(meas[o], 1.0 / meas.dt) for o in meas.spec.outputs}
        reg = regime_errors(masks, res, {o: m.std for o, m in outs.items()}, noise)
    return CompareResult(model, meas, inputs, sim, outs, nr, reg, masks)
