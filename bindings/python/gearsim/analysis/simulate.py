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
log) is fed as it is: its steps are what the rig saw. A model with backlash or
a compliant base shaft gets the measured speed through a wider filter
(:func:`gearsim.analysis.signals.contact_cutoff`): the contact or the shaft
integrates the speed into a spring's deflection instead of differentiating
it, so the impacts and the shaft's ring keep their fast content.

No lag of our own (docs/analysis.md, "Timing"): the rig steps from sample
to sample, its speed ramping linearly over each step, and reports torques as
means over the step and speeds at its end. A record samples every channel at
the same instants. So the rig is fed the (conditioned) speed half a sample
ahead (:func:`half_sample`, cubic interpolation), which centres each step on
a sample instant: its mean torque is the torque at that instant, its load is
the sample's, and the speed-driven rigid rig evaluates its speed terms at the
step's mean speed (rig ``base_speed_ramp``) and its acceleration as the
centred difference; the driven speed, an end-of-step value, is taken back
half a sample. A backlash contact is sub-stepped finely enough for its
backward Euler not to damp the mesh mode (:data:`CONTACT_H_OMEGA`).

Rig time (a CSV of ``gearsim hil to-csv`` whose first line says
``time_base=rig``, :attr:`Measurement.time_base`): the model is stepped as the
rig was, every ``rig_dt`` seconds, ``steps_per_row`` steps per row, and
compared with the outputs after the last step of each row's interval. The
held inputs are fed as the rig applied them (:func:`expand_to_rig_steps`) and
never filtered, whatever ``input_filter`` says: they are exact, a filter
would only make them something the rig did not see. :func:`row_samples`
picks the rows' values out of the rig steps.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..columns import AMBIENT_TEMPERATURE, TEMPERATURE
from . import modelkit as mk
from .measurement import BEFORE_SUFFIX, INPUTS_SINCE, Measurement
from .signals import auto_cutoff, contact_cutoff, is_held, zero_phase_lowpass

__all__ = [
    "Inputs",
    "integrates_drive_speed",
    "CONTACT_LABEL",
    "RigSteps",
    "prepare_inputs",
    "rig_steps_of",
    "expand_to_rig_steps",
    "row_samples",
    "Simulation",
    "simulate",
    "simulate_outputs",
    "delayed",
    "half_sample",
    "CONTACT_H_OMEGA",
    "contact_substeps",
]

#: h*omega_n of a backlash contact's sub-steps in the analysis: backward Euler
#: damps a mode by about (h*omega_n)^2/2 per sub-step, so the rig's own
#: automatic count (h*omega_n <= AUTO_H_OMEGA_N_MAX, stable but over-damped) would damp a
#: mesh mode of a few percent of the sampling rate; the contact model of
#: three external test records came within 1.07x of their noise floor at
#: 0.03 and needed 1.3-1.6x at the automatic count of h*omega_n <= 0.5
#: (docs/analysis.md)
CONTACT_H_OMEGA = 0.03


@dataclass(frozen=True)
class RigSteps:
    """How the rig was stepped over the rows of a rig-time CSV.

    rig_dt: the rig step (s); steps_per_row: rig steps in each row's
    interval; steps_before: per row, how many of those steps (the first
    ones) applied the held inputs' earlier values; before: held input column
    -> its value before the row's ``inputs_since``, per row."""

    rig_dt: float
    steps_per_row: int
    steps_before: np.ndarray
    before: Mapping[str, np.ndarray]

    def slice(self, start: int, stop: int) -> RigSteps:
        return RigSteps(
            self.rig_dt,
            self.steps_per_row,
            self.steps_before[start:stop],
            {name: x[start:stop] for name, x in self.before.items()},
        )


def rig_steps_of(meas: Measurement) -> RigSteps | None:
    """The rig stepping a rig-time measurement records (None for any other).

    In the interval that ends at row j (time t_j), rig step k = 0..n-1 starts
    at t_j - (n - k)*h; it applied the held inputs' ``_before`` values when it
    started before inputs_since[j] (half a step of slack for the rounding of
    the times in the text), the row's own inputs otherwise. Solved for k:
    the first ceil(n - (t_j - inputs_since[j])/h - 1/2) steps, within 0..n."""
    base = meas.time_base
    if base is None or not base.is_rig:
        return None
    h, n = float(base.rig_step), base.steps_per_row
    since = meas[INPUTS_SINCE]
    first_after = np.ceil(n - (meas.time - since) / h - 0.5)
    steps_before = np.clip(first_after, 0, n).astype(np.int64)
    before = {name: meas[name + BEFORE_SUFFIX] for name in base.held}
    return RigSteps(h, n, steps_before, before)


def expand_to_rig_steps(
    values: np.ndarray, steps: RigSteps, before: np.ndarray | None = None
) -> np.ndarray:
    """One value per rig step from one value per row: the row's value for
    each of its steps_per_row steps, except the first steps_before[j] steps
    of row j, which get before[j] (when `before` is given: a held input)."""
    n = steps.steps_per_row
    fine = np.repeat(np.asarray(values, dtype=float), n)
    if before is not None:
        earlier = np.arange(n)[None, :] < steps.steps_before[:, None]
        fine[earlier.ravel()] = np.repeat(np.asarray(before, dtype=float), n)[earlier.ravel()]
    return fine


def row_samples(fine: np.ndarray, steps: RigSteps) -> np.ndarray:
    """The value after the last rig step of each row's interval (the rig
    sent its outputs then)."""
    n = steps.steps_per_row
    return np.asarray(fine, dtype=float)[n - 1 :: n]


#: how input_filter_hz lists the cut-off of contact_speed
CONTACT_LABEL = "backlash contact or compliant shaft"


def integrates_drive_speed(model: Any) -> bool:
    """True when the rig turns the drive speed into a spring's deflection
    (a backlash contact, or a compliant base shaft: compliance_stiffness >
    0) rather than differentiating it for a rigid inertia torque. Such a rig
    filters the speed's fast content itself, through the spring and the
    inertia behind it, so it is driven by the wider contact cut-off, which
    keeps the shaft's ring and the impacts in the input."""
    if mk.block_values(model).get("backlash_enabled"):
        return True
    return float(mk.rig_values(model).get("compliance_stiffness", 0.0)) > 0.0


@dataclass(frozen=True)
class Inputs:
    """Rig inputs derived from a measurement (SI units, one value per sample).

    cutoffs: input column -> cut-off (Hz) applied, or None when unfiltered;
    plus "<speed column> (CONTACT_LABEL)" when contact_speed is set.
    contact_speed: the base speed for a model with backlash or a compliant
    base shaft (integrates_drive_speed), when its conditioning differs from
    base_speed's (None: the same).
    rig_steps: how the rig was stepped over the rows (a rig-time CSV), or
    None: the model is stepped once per row, at dt. held: the input columns
    recorded as zero-order-hold staircases (fed as they are: what a rig
    applied step by step, so the speed is not taken half a sample ahead)."""

    base_speed: np.ndarray
    load: np.ndarray
    measured_temperature: np.ndarray | None
    ambient_temperature: np.ndarray | None
    dt: float
    cutoffs: Mapping[str, float | None] = field(default_factory=dict)
    contact_speed: np.ndarray | None = None
    rig_steps: RigSteps | None = None
    held: frozenset[str] = frozenset()

    def speed_for(self, model: Any) -> np.ndarray:
        """The base speed that drives `model`'s rig: contact_speed for a
        model with backlash or a compliant base shaft (both integrate the
        speed into a spring's deflection instead of differentiating it),
        base_speed otherwise."""
        if self.contact_speed is not None and integrates_drive_speed(model):
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
            None if self.rig_steps is None else self.rig_steps.slice(start, stop),
            self.held,
        )


def prepare_inputs(meas: Measurement, input_filter: float | str | None = "auto") -> Inputs:
    """Rig inputs of a measurement, conditioned by the zero-phase input filter.

    input_filter: "auto" (cut-off per input from its spectrum; held inputs
    unfiltered), a cut-off in Hz for every input, or None (raw samples). The
    held inputs of a rig-time CSV are never filtered (module docstring)."""
    fs = 1.0 / meas.dt
    cutoffs: dict[str, float | None] = {}
    steps = rig_steps_of(meas)
    held_as_applied = set(steps.before) if steps is not None else set()
    held: set[str] = set()

    def cond(name: str) -> np.ndarray:
        x = meas[name]
        if name in held_as_applied:
            cutoffs[name] = None
            held.add(name)
            return x
        if input_filter is None or input_filter == "none":
            cutoffs[name] = None
            return x
        if input_filter == "auto" and is_held(x):
            cutoffs[name] = None
            held.add(name)
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
    speed_cutoff = cutoffs[spec.speed_input]
    if input_filter == "auto" and speed_cutoff is not None:
        fc = contact_cutoff(meas[spec.speed_input], fs)
        if fc is not None and fc > speed_cutoff:
            cutoffs[f"{spec.speed_input} ({CONTACT_LABEL})"] = fc
            contact = zero_phase_lowpass(meas[spec.speed_input], fc, fs)
    load = cond(spec.load_input)
    temp = cond(TEMPERATURE.name) if meas.has_temperature else None
    amb = cond(AMBIENT_TEMPERATURE.name) if meas.has_ambient else None
    return Inputs(speed, load, temp, amb, meas.dt, cutoffs, contact, steps, frozenset(held))


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


def _aligned(meas: Measurement, inputs: Inputs) -> bool:
    """The rig's steps are centred on the samples (module docstring). Not for
    a rig-time record, nor a speed held step by step: those are replayed as
    the rig ran them."""
    return inputs.rig_steps is None and meas.spec.speed_input not in inputs.held


def half_sample(y: np.ndarray, direction: int) -> np.ndarray:
    """y half a sample ahead (direction +1: y(t_k + dt/2)) or behind (-1:
    y(t_k - dt/2)), by the cubic through the four nearest samples,
    (-y[k-1] + 9 y[k] + 9 y[k+1] - y[k+2])/16, the ends extended by
    reflection through the end values (exact for cubics away from the ends,
    for straight lines everywhere)."""
    y = np.asarray(y, dtype=float)
    if y.size < 2:
        return y.copy()
    head = 2.0 * y[0] - y[2:0:-1] if y.size > 2 else 2.0 * y[0] - y[1:2].repeat(2)
    tail = 2.0 * y[-1] - y[-2:-4:-1] if y.size > 2 else 2.0 * y[-1] - y[0:1].repeat(2)
    p = np.concatenate([head, y, tail])  # p[i + 2] = y[i]
    if direction > 0:
        return (-p[1:-3] + 9.0 * p[2:-2] + 9.0 * p[3:-1] - p[4:]) / 16.0
    return (-p[:-4] + 9.0 * p[1:-3] + 9.0 * p[2:-2] - p[3:-1]) / 16.0


def contact_substeps(model: Any, dt: float, h_omega: float = CONTACT_H_OMEGA) -> int | None:
    """The contact sub-steps for a model with backlash whose model leaves
    the count to the rig (contact_substeps 0): the fewest with h*omega_n <=
    h_omega (default CONTACT_H_OMEGA), at most the rig's 64; None otherwise
    (the rig's own)."""
    if not mk.block_values(model).get("backlash_enabled"):
        return None
    if int(mk.rig_values(model).get("contact_substeps", 0) or 0) > 0:
        return None
    info = model.rig(dt=dt).info
    dt_omega = float(info["contact_substeps"]) * float(info["contact_h_omega_n"])
    return int(min(64, max(1, np.ceil(dt_omega / h_omega))))


def _run(
    model: Any, meas: Measurement, inputs: Inputs, substeps: int | None = None
) -> tuple[Any, dict[str, np.ndarray]]:
    """One batch run of the model's rig on the inputs: the RigResult, and the
    two simulated outputs under their canonical names (one value per row).
    substeps: the contact sub-steps of a backlash model (default:
    contact_substeps)."""
    use_temperature = inputs.measured_temperature is not None
    steps = inputs.rig_steps
    aligned = _aligned(meas, inputs)
    dt = inputs.dt if steps is None else steps.rig_dt
    overrides: dict[str, Any] = {"base_speed_ramp": True} if aligned else {}
    if aligned:
        n_sub = substeps if substeps is not None else contact_substeps(model, dt)
        if n_sub:
            overrides["contact_substeps"] = int(n_sub)
    rig = model.rig(dt=dt, temperature_input=use_temperature, **overrides)
    # which rig input each column drives and which rig output each measured
    # output is compared with: gearsim.columns, shared with the HIL recording
    cols = meas.spec.columns
    speed = inputs.speed_for(model)
    given = {
        cols.speed_input: half_sample(speed, +1) if aligned else speed,
        cols.load_input: inputs.load,
        AMBIENT_TEMPERATURE: inputs.ambient_temperature,
        TEMPERATURE: inputs.measured_temperature,
    }
    kw: dict[str, Any] = {}
    for col, x in given.items():
        if x is None:
            continue
        if steps is not None:
            x = expand_to_rig_steps(x, steps, steps.before.get(col.name))
        kw[str(col.rig_input)] = x
    res = rig.run(**kw)
    outputs = {col.name: _per_row(res, str(col.rig_output), steps) for col in cols.outputs}
    if aligned:  # the driven speed is an end-of-step value: half a sample back
        speed_out = meas.spec.speed_output
        outputs[speed_out] = half_sample(outputs[speed_out], -1)
    delay = mk.torque_delay(model)
    if delay:
        torque = meas.spec.torque_output
        outputs[torque] = delayed(outputs[torque], delay / meas.dt)
    return res, outputs


def delayed(y: np.ndarray, samples: float) -> np.ndarray:
    """y delayed by a (fractional) number of samples: y(t - d) by linear
    interpolation on the sample grid, the first value held before the start
    (negative: advanced, the last value held). The [analysis] torque_delay
    is applied this way to the simulated torque: positive means the measured
    torque lags the speed channels, as a logger on a slower device does."""
    y = np.asarray(y, dtype=float)
    grid = np.arange(y.size, dtype=float)
    return np.interp(grid - samples, grid, y)


def _per_row(res: Any, name: str, steps: RigSteps | None) -> np.ndarray:
    """RigResult signal `name`, one value per row of the measurement."""
    values = np.asarray(getattr(res, name), dtype=float)
    return values if steps is None else row_samples(values, steps)


def simulate(
    model: Any, meas: Measurement, inputs: Inputs | None = None, signals: tuple[str, ...] = _SIGNALS
) -> Simulation:
    """Run the model's rig open-loop on the measurement's inputs."""
    if inputs is None:
        inputs = prepare_inputs(meas)
    res, outputs = _run(model, meas, inputs)
    sig = {}
    for name in signals:
        if getattr(res, name, None) is not None:
            sig[name] = _per_row(res, name, inputs.rig_steps)
            if _aligned(meas, inputs) and name in _END_VALUES:
                sig[name] = half_sample(sig[name], -1)
    return Simulation(outputs, sig)


#: the rig outputs that are values at the end of a step (the others are step
#: means): taken back half a sample like the driven speed
_END_VALUES = frozenset(
    ("follower_speed", "base_speed", "temperature", "backlash_position", "follower_position")
)


def simulate_outputs(
    model: Any, meas: Measurement, inputs: Inputs, substeps: int | None = None
) -> dict[str, np.ndarray]:
    """Only the two simulated outputs (the fitting loop's call; substeps:
    a backlash contact's sub-steps held over a fit)."""
    return _run(model, meas, inputs, substeps)[1]
