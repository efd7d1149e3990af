"""Open-loop simulation of a model on a measurement's inputs, through the C rig.

The measured inputs drive the model's rig from the first sample; the outputs
are never fed back (docs/measurement-format.md section 4). One batch call of
``Rig.run`` per simulation: the loop runs in C.

Input conditioning (documented, offline only): the rig is speed-driven and
needs the acceleration of the measured speed for the inertia torque. Raw
measured speeds are noisy and quantized, so by default each input is passed
through a zero-phase low-pass (:func:`gearsim.analysis.signals.zero_phase_lowpass`,
4th-order Butterworth magnitude squared) whose cut-off is chosen from the
input's own spectrum (:func:`gearsim.analysis.signals.auto_cutoff`). Pass
``input_filter=None`` to feed the raw samples, or a number (Hz) to fix the
cut-off for every input. With "auto", an input recorded as a zero-order-hold
staircase (:func:`gearsim.analysis.signals.is_held`, e.g. a command from a HIL
log) is fed as it is: its steps are what the rig saw. A model with backlash
gets the measured speed through a wider filter
(:func:`gearsim.analysis.signals.contact_cutoff`): its contact integrates the
speed instead of differentiating it, so the impacts keep their fast content.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..columns import AMBIENT_TEMPERATURE, TEMPERATURE
from . import modelkit as mk
from .measurement import Measurement
from .signals import auto_cutoff, contact_cutoff, is_held, zero_phase_lowpass

__all__ = ["Inputs", "prepare_inputs", "Simulation", "simulate", "simulate_outputs"]


@dataclass(frozen=True)
class Inputs:
    """Rig inputs derived from a measurement (SI units, one value per sample).

    cutoffs: input column -> cut-off (Hz) applied, or None when unfiltered;
    plus "<speed column> (backlash contact)" when contact_speed is set.
    contact_speed: the base speed for a model with backlash, when its
    conditioning differs from base_speed's (None: the same)."""

    base_speed: np.ndarray
    load: np.ndarray
    measured_temperature: np.ndarray | None
    ambient_temperature: np.ndarray | None
    dt: float
    cutoffs: Mapping[str, float | None] = field(default_factory=dict)
    contact_speed: np.ndarray | None = None

    def speed_for(self, model: Any) -> np.ndarray:
        """The base speed that drives `model`'s rig: contact_speed for a
        model with backlash, base_speed otherwise."""
        if self.contact_speed is not None and mk.block_values(model).get("backlash_enabled"):
            return self.contact_speed
        return self.base_speed

    def slice(self, start: int, stop: int) -> Inputs:
        def s(x):
            return None if x is None else x[start:stop]

        return Inputs(
            self.base_speed[start:stop],
            self.load[start:stop],
            s(self.measured_temperature),
            s(self.ambient_temperature),
            self.dt,
            self.cutoffs,
            s(self.contact_speed),
        )


def prepare_inputs(meas: Measurement, input_filter: float | str | None = "auto") -> Inputs:
    """Rig inputs of a measurement, conditioned by the zero-phase input filter.

    input_filter: "auto" (cut-off per input from its spectrum; held inputs
    unfiltered), a cut-off in Hz for every input, or None (raw samples)."""
    fs = 1.0 / meas.dt
    cutoffs: dict[str, float | None] = {}

    def cond(name: str) -> np.ndarray:
        x = meas[name]
        if input_filter is None or input_filter == "none":
            cutoffs[name] = None
            return x
        if input_filter == "auto" and is_held(x):
            cutoffs[name] = None
            return x
        fc = auto_cutoff(x, fs) if input_filter == "auto" else float(input_filter)
        if fc is None or fc >= 0.5 * fs:
            cutoffs[name] = None
            return x
        cutoffs[name] = fc
        return zero_phase_lowpass(x, fc, fs)

    spec = meas.spec
    speed = cond(spec.speed_input)
    contact = None
    if input_filter == "auto" and cutoffs[spec.speed_input] is not None:
        fc = contact_cutoff(meas[spec.speed_input], fs)
        if fc is not None and fc > cutoffs[spec.speed_input]:
            cutoffs[f"{spec.speed_input} (backlash contact)"] = fc
            contact = zero_phase_lowpass(meas[spec.speed_input], fc, fs)
    load = cond(spec.load_input)
    temp = cond(TEMPERATURE.name) if meas.has_temperature else None
    amb = cond(AMBIENT_TEMPERATURE.name) if meas.has_ambient else None
    return Inputs(speed, load, temp, amb, meas.dt, cutoffs, contact)


@dataclass
class Simulation:
    """Simulated outputs (canonical output names) plus the rig's other signals.

    outputs: {torque output: base torque (N*m), speed output: driven speed}.
    signals: the RigResult arrays by name (follower_speed, follower_port_torque,
    follower_acceleration, temperature, mesh_loss_power, ...)."""

    outputs: dict[str, np.ndarray]
    signals: dict[str, np.ndarray]


_SIGNALS = (
    "base_torque",
    "follower_speed",
    "follower_port_torque",
    "follower_acceleration",
    "temperature",
    "mesh_loss_power",
    "loss_power",
    "base_speed",
    "backlash_position",
    "contact_force",
    "follower_position",
)


def _run(model: Any, meas: Measurement, inputs: Inputs) -> tuple[Any, dict[str, np.ndarray]]:
    """One batch run of the model's rig on the inputs: the RigResult, and the
    two simulated outputs under their canonical names."""
    use_temperature = inputs.measured_temperature is not None
    rig = model.rig(dt=inputs.dt, temperature_input=use_temperature)
    # which rig input each column drives and which rig output each measured
    # output is compared with: gearsim.columns, shared with the HIL recording
    cols = meas.spec.columns
    given = {
        cols.speed_input: inputs.speed_for(model),
        cols.load_input: inputs.load,
        AMBIENT_TEMPERATURE: inputs.ambient_temperature,
        TEMPERATURE: inputs.measured_temperature,
    }
    kw: dict[str, Any] = {str(col.rig_input): x for col, x in given.items() if x is not None}
    res = rig.run(**kw)
    return res, {
        col.name: np.asarray(getattr(res, str(col.rig_output)), dtype=float) for col in cols.outputs
    }


def simulate(
    model: Any, meas: Measurement, inputs: Inputs | None = None, signals: tuple[str, ...] = _SIGNALS
) -> Simulation:
    """Run the model's rig open-loop on the measurement's inputs."""
    if inputs is None:
        inputs = prepare_inputs(meas)
    res, outputs = _run(model, meas, inputs)
    sig = {}
    for name in signals:
        val = getattr(res, name, None)
        if val is not None:
            sig[name] = np.asarray(val, dtype=float)
    return Simulation(outputs, sig)


def simulate_outputs(model: Any, meas: Measurement, inputs: Inputs) -> dict[str, np.ndarray]:
    """Only the two simulated outputs (the fitting loop's call)."""
    return _run(model, meas, inputs)[1]
