"""Test records with known truth: the rigs, the hidden effects, the record.

``generate(block, effects)`` integrates the true mechanism (plant.py) on an
excitation (excitation.py), measures it with imperfect sensors (sensors.py)
and returns the gearsim Measurement, the noise-free outputs and the noise
floor. ``gearsim_model(block, effects)`` writes the same truth as a gearsim
model file would (the loss-law thresholds mapped onto gearsim's tanh(4*u/u_th)
form), for comparing gearsim's rig with the true system; it is the only place
that touches gearsim, and only to build Model objects and Measurements.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from functools import cache

import numpy as np

from . import excitation, sensors
from .plant import Losses, Mechanism, TrueRun, simulate_true

DT = 1e-3  # s, sample period of every record

# the rigs: geometry, inertias, a compliant mesh (about 90 Hz with the drive
# open) and a drive loop of 15 Hz; excitation peaks (rad/s at the base, load)
RIGS = {
    "simple_gear": Mechanism(
        block="simple_gear",
        ratio_sign_s=-1.0,
        base_radius_m=0.05,
        driven_radius_m=0.15,
        teeth_ratio=3.0,
        base_inertia=0.002,
        driven_inertia=0.05,
        mesh_stiffness_N_m=2e5,
        mesh_damping_Ns_m=300.0,
        coulomb_speed=0.01,
        mesh_power_W=0.3,
        idle_speed=0.02,
    ),
    "rack_pinion": Mechanism(
        block="rack_pinion",
        ratio_sign_s=1.0,
        base_radius_m=0.05,
        driven_radius_m=1.0,
        teeth_ratio=1.0,
        base_inertia=0.002,
        driven_inertia=5.0,
        mesh_stiffness_N_m=2e5,
        mesh_damping_Ns_m=300.0,
        coulomb_speed=0.005,
        mesh_power_W=0.3,
    ),
}
PEAKS = {"simple_gear": (30.0, 3.0), "rack_pinion": (20.0, 50.0)}

#: the rack's linear encoder: 1 um increments
RACK_SENSORS = sensors.Sensors(driven_quantum=1e-6)
GEAR_SENSORS = sensors.Sensors()

BACKLASH_M = 1e-3
TEMPERATURES_K = (290.0, 310.0, 330.0)
#: hidden effect -> true value(s), per rig
TRUTHS = {
    "simple_gear": {
        "meshing_efficiency": {"efficiency": 0.8},
        # eq. 2.5 with tau_nom = 3 N*m, eta_nom = 0.7: k = 1/0.7 - 1 - 3*0.3/3
        "load_dependent_efficiency": {"idle_torque_Nm": 0.3, "load_slope": 1 / 0.7 - 1 - 0.3},
        "temperature_dependent_efficiency": {
            "efficiency_table": (TEMPERATURES_K, (0.95, 0.8, 0.6))
        },
        "viscous_friction": {"viscous": 0.15},
        "coulomb_friction": {"coulomb": 1.5},
        "load_offset": {"load_offset": 1.5},
        "backlash": {},
    },
    "rack_pinion": {
        "meshing_efficiency": {"efficiency": 0.8},
        "temperature_dependent_efficiency": {
            "efficiency_table": (TEMPERATURES_K, (0.95, 0.8, 0.6))
        },
        "viscous_friction": {"viscous": 40.0},
        "coulomb_friction": {"coulomb": 30.0},
        "load_offset": {"load_offset": 30.0},
        "backlash": {},
    },
}
#: a mesh 10x stiffer than the rigs' (5000 N*m/rad at a 50 mm base radius).
#: The compliance records use it so that the shaft is the compliance under
#: test; the Stribeck records because the friction at rest, higher than the
#: Coulomb level, winds the usual mesh up at every reversal for several ms,
#: a lag a rigid model cannot follow: gearsim's rig with the true parameters
#: reaches 1.34x (gear) and 1.65x (rack) the noise floor on the default mesh,
#: 1.26x and 1.21x on this one.
STIFF_MESH_N_M = 2e6
#: the motor of the ripple records (kg*m^2, 100x the rigs'). The ripple acts
#: between the torque sensor and the mesh; at tooth frequencies, beyond the
#: drive's 15 Hz loop, the motor (J_M) and the driven side reflected to the
#: base (J_r) share it, and the sensor reads only J_M/(J_M + J_r) of it: 26 %
#: on the gear's usual 0.002 kg*m^2 motor. The speed-driven rig assumes a
#: drive that holds the speed; this motor does, to 97 % (gear) and 94 %
#: (rack).
RIPPLE_MOTOR_KG_M2 = 0.2
#: the effects real rigs show on top of the blocks' losses (physics.md 11, "Effects
#: of real rigs"), kept apart from TRUTHS so that the acceptance of
#: the contract's first effects iterates over those alone. Each value sets
#: fields of Losses, of Mechanism or of the Sensors, whichever has the name.
RIG_EFFECT_TRUTHS = {
    "simple_gear": {
        # the torque logged by another device than the speeds, 6.4 ms late
        # (the rig: 6 ms; a fraction of a sample on purpose)
        "sensor_delay": {"torque_delay_s": 6.4e-3},
        # on top of coulomb_friction (1.5 N*m): 2.5 N*m at rest, back to 1.5
        # over 0.3 rad/s of follower speed (30x the tanh band, 0.9 rad/s at
        # the base). The mesh is 10x stiffer than usual (STIFF_MESH_N_M)
        "stribeck_friction": {
            "breakaway": 2.5,
            "stribeck_speed": 0.3,
            "mesh_stiffness_N_m": STIFF_MESH_N_M,
        },
        # a 600 N*m/rad shaft between a 0.01 kg*m^2 motor and a 0.001 kg*m^2
        # base gear: 48.1 Hz with the motor held and the mesh rigid, damping
        # ratio 0.050 (physics.md 11.4; J_eff = 0.001 + 0.05/9). The mesh is
        # then 10x stiffer than usual (5000 N*m/rad at the base shaft), so
        # that the shaft is the compliance under test
        "compliance": {
            "shaft_stiffness_Nm_rad": 600.0,
            "shaft_damping_Nms_rad": 0.2,
            "gear_inertia": 0.001,
            "base_inertia": 0.01,
            "mesh_stiffness_N_m": STIFF_MESH_N_M,
        },
        # eccentricity (per revolution) and transmission error (per tooth of
        # a 16-tooth base gear), N*m and rad, on a heavy motor (RIPPLE_MOTOR)
        "torque_ripple": {
            "base_inertia": RIPPLE_MOTOR_KG_M2,
            "ripple_revolution": ((0.08, 0.6), (0.03, -1.1)),
            "ripple_mesh": ((0.05, 0.3), (0.02, 2.0)),
            "teeth": 16,
        },
    },
    "rack_pinion": {
        "sensor_delay": {"torque_delay_s": 6.4e-3},
        # on top of coulomb_friction (30 N): 60 N at rest, back to 30 N over
        # 50 mm/s (10x the tanh band, 1 rad/s at the pinion)
        "stribeck_friction": {
            "breakaway": 60.0,
            "stribeck_speed": 0.05,
            "mesh_stiffness_N_m": STIFF_MESH_N_M,
        },
        # 1200 N*m/rad: 47.5 Hz with the motor held and the mesh rigid,
        # damping ratio 0.050 (J_eff = 0.001 + 0.05^2*5)
        "compliance": {
            "shaft_stiffness_Nm_rad": 1200.0,
            "shaft_damping_Nms_rad": 0.4,
            "gear_inertia": 0.001,
            "base_inertia": 0.01,
            "mesh_stiffness_N_m": STIFF_MESH_N_M,
        },
        # a 20-tooth pinion
        "torque_ripple": {
            "base_inertia": RIPPLE_MOTOR_KG_M2,
            "ripple_revolution": ((0.1, -0.4), (0.04, 1.3)),
            "ripple_mesh": ((0.06, 0.9), (0.02, -2.2)),
            "teeth": 20,
        },
    },
}
STROKE_RECORD_START_S = 0.5
LOAD_DEPENDENT_NOMINAL = (3.0, 0.7)  # tau_nom (N*m), eta_nom: how gearsim states k


_LOSS_FIELDS = {f.name for f in dataclasses.fields(Losses)}
_SENSOR_FIELDS = {f.name for f in dataclasses.fields(sensors.Sensors)}


def _truth_values(block: str, effects: tuple[str, ...]) -> tuple[dict, dict, dict]:
    """The truth of `effects` split into Losses, Mechanism and Sensors fields."""
    losses, mech, sens = {}, {}, {}
    for effect in effects:
        truth = TRUTHS[block].get(effect)
        if truth is None:
            truth = RIG_EFFECT_TRUTHS[block][effect]
        for name, value in truth.items():
            if name in _LOSS_FIELDS:
                losses[name] = value
            elif name in _SENSOR_FIELDS:
                sens[name] = value
            else:
                mech[name] = value
    return losses, mech, sens


def mechanism(block: str, effects: tuple[str, ...]) -> Mechanism:
    """The rig of `block` with the hidden `effects` switched on."""
    losses, fields, _ = _truth_values(block, effects)
    backlash = BACKLASH_M if "backlash" in effects else 0.0
    return dataclasses.replace(RIGS[block], losses=Losses(**losses), backlash_m=backlash, **fields)


@dataclass(frozen=True)
class Record:
    """A generated record: the Measurement gearsim reads, the noise-free
    outputs at the same instants, and the truth that made it."""

    block: str
    effects: tuple[str, ...]
    mechanism: Mechanism
    measurement: object  # gearsim.analysis.Measurement
    true_run: TrueRun
    true_outputs: dict[str, np.ndarray]
    measured_outputs: dict[str, np.ndarray]

    def noise_floor(self, start: int = 0, stop: int | None = None) -> dict[str, float]:
        """nrmse of the true outputs against the measured ones over samples
        [start, stop): per output and 'overall' (their mean)."""
        per = {
            name: sensors.nrmse(self.measured_outputs[name][start:stop], true[start:stop])
            for name, true in self.true_outputs.items()
        }
        per["overall"] = float(np.mean(list(per.values())))
        return per


_COLUMNS = {
    "simple_gear": ("base_speed", "load_torque", "base_torque", "follower_speed"),
    "rack_pinion": ("pinion_speed", "load_force", "pinion_torque", "rack_velocity"),
}


def _torque_reading(run: TrueRun, sens: sensors.Sensors) -> np.ndarray:
    """The noise-free torque as the torque sensor delivers it: on time, or
    late by sens.torque_delay_s."""
    if sens.torque_delay_s == 0.0:
        return run.base_torque
    return sensors.delayed_reading(
        run.fine_torque, run.fine_dt, run.time.size, DT, sens.torque_delay_s
    )


def _measure(block: str, run: TrueRun, sens: sensors.Sensors, seed: int):
    """The four columns and the temperature as the sensors record them."""
    rng = np.random.default_rng(seed)
    speed_in, load_in, torque_out, speed_out = _COLUMNS[block]
    base_quantum = 2 * math.pi / sens.base_counts_per_rev
    torque_range = sensors.robust_range(run.base_torque)
    load_range = sensors.robust_range(run.load)
    n = run.time.size
    columns = {
        speed_in: sensors.encoder_speed(run.base_angle, base_quantum, DT),
        load_in: run.load + sens.load_noise * load_range * rng.standard_normal(n),
        torque_out: _torque_reading(run, sens)
        + torque_range * (sens.torque_offset + sens.torque_noise * rng.standard_normal(n)),
        speed_out: sensors.encoder_speed(run.driven_position, sens.driven_quantum, DT),
        "temperature": run.temperature + sens.temperature_noise_K * rng.standard_normal(n),
    }
    return {name: sensors.delayed(x, sens.delay_samples) for name, x in columns.items()}


@cache
def generate(
    block: str,
    effects: tuple[str, ...],
    *,
    profile: str = "rich",
    duration_s: float = 12.0,
    seed: int = 11,
    sens: sensors.Sensors | None = None,
    substeps: int = 4,
) -> Record:
    """A record of the `block` rig with the hidden `effects` (cached: the same
    arguments give the same object).

    profile: "rich", "stroke", "steps" (moves at constant acceleration, load
    steps) or "creep" (slow holds near the truth's Stribeck speed, seen at
    the base); substeps: integration steps per sample."""
    from gearsim.analysis.measurement import Measurement

    mech = mechanism(block, effects)
    max_speed, max_load = PEAKS[block]
    if profile == "rich":
        prof = excitation.rich(duration_s, DT, max_speed, max_load, seed)
    elif profile == "stroke":
        prof = excitation.stroke(duration_s, DT, max_speed, -0.6 * max_load)
    elif profile == "steps":
        prof = excitation.steps(duration_s, DT, max_speed, max_load, seed)
    elif profile == "creep":
        low = mech.losses.stribeck_speed / abs(mech.kinematic_ratio)
        prof = excitation.creep(duration_s, DT, max_speed, max_load, low, seed)
    else:
        raise ValueError(f"unknown profile {profile!r}")
    run = simulate_true(
        mech, prof.time, prof.speed_command, prof.load, prof.temperature, substeps=substeps
    )
    if sens is None:
        sens = RACK_SENSORS if block == "rack_pinion" else GEAR_SENSORS
    sens = dataclasses.replace(sens, **_truth_values(block, effects)[2])
    columns = _measure(block, run, sens, seed + 1)
    true_torque = _torque_reading(run, sens)
    if profile == "stroke":
        # the record starts in motion, after the start from rest: nothing but
        # the stroke itself is seen
        keep = prof.time >= STROKE_RECORD_START_S
        n = run.time.size
        run = dataclasses.replace(
            run,
            **{
                f.name: getattr(run, f.name)[keep]
                for f in dataclasses.fields(run)
                if isinstance(getattr(run, f.name), np.ndarray) and getattr(run, f.name).size == n
            },
        )
        true_torque = true_torque[keep]
        first = int(np.argmax(keep)) * int(round(DT / run.fine_dt))
        run = dataclasses.replace(run, fine_torque=run.fine_torque[first:])
        columns = {name: x[keep] for name, x in columns.items()}
        prof = dataclasses.replace(prof, time=prof.time[keep] - prof.time[keep][0])
    _, _, torque_out, speed_out = _COLUMNS[block]
    meas = Measurement.from_arrays(
        block, prof.time, path=f"<independent {block}:{'+'.join(effects) or 'none'}>", **columns
    )
    return Record(
        block,
        effects,
        mech,
        meas,
        run,
        {torque_out: true_torque, speed_out: run.driven_speed},
        {torque_out: columns[torque_out], speed_out: columns[speed_out]},
    )


def _gearsim_parameters(block: str, effects: tuple[str, ...]) -> tuple[dict, dict]:
    """Block and rig parameters of the truth in gearsim's names."""
    mech = mechanism(block, effects)
    loss = mech.losses
    if block == "simple_gear":
        bp = {
            "teeth_ratio": mech.teeth_ratio,
            "output_shaft_rotates": "opposite" if mech.ratio_sign_s < 0 else "same",
            "base_radius": mech.base_radius_m,
        }
        rp = {"follower_inertia": mech.driven_inertia}
    else:
        bp = {
            "pinion_radius": mech.base_radius_m,
            "rack_directionality": "positive" if mech.ratio_sign_s > 0 else "negative",
        }
        rp = {"rack_mass": mech.driven_inertia}
    # the torque sensor sits between the motor's inertia and the mesh; with a
    # compliant shaft the base gear's inertia is behind it, whether the model
    # has the shaft's compliance or not
    rp["base_inertia"] = mech.gear_inertia
    # the smoothing of every law as the truth has it, also in a start model
    # that lacks the law (a user states the rig's thresholds once): gearsim
    # blends with tanh(4*u/u_th), the truth with tanh(u/u_s), so u_th = 4*u_s
    rp["load_coulomb_speed_threshold"] = 4 * mech.coulomb_speed
    bp["power_threshold"] = 4 * mech.mesh_power_W
    if block == "simple_gear":
        bp["speed_threshold"] = 4 * mech.idle_speed
    if "coulomb_friction" in effects:
        rp["load_coulomb_friction"] = loss.coulomb
    if "load_offset" in effects:
        rp["load_offset"] = loss.load_offset
    if "viscous_friction" in effects:
        if block == "simple_gear":
            bp["viscous_coefficients"] = [0.0, loss.viscous]
        else:
            bp["rack_viscous_coefficient"] = loss.viscous
    if "meshing_efficiency" in effects:
        bp.update(friction_model="constant_efficiency", efficiency_const=loss.efficiency)
    if "temperature_dependent_efficiency" in effects:
        temps, etas = loss.efficiency_table
        bp.update(
            friction_model="temperature_dependent_efficiency",
            temperature_vector=list(temps),
            efficiency_vector=list(etas),
        )
    if "load_dependent_efficiency" in effects:
        tau_nom, eta_nom = LOAD_DEPENDENT_NOMINAL
        bp.update(
            friction_model="load_dependent_efficiency",
            idle_torque=loss.idle_torque_Nm,
            nominal_output_torque=tau_nom,
            efficiency_nominal=eta_nom,
        )
    if "backlash" in effects:
        bp.update(
            backlash_enabled=True,
            linear_backlash=mech.backlash_m,
            stiffness=mech.mesh_stiffness_N_m,
            damping=mech.mesh_damping_Ns_m,
            transition_region=mech.backlash_m / 20,
        )
        if block == "simple_gear":
            bp["base_radius"] = mech.base_radius_m
    if "stribeck_friction" in effects:
        rp["load_breakaway_friction"] = loss.breakaway
        rp["load_stribeck_speed"] = loss.stribeck_speed
    if "compliance" in effects:
        # the torque sensor sits in the shaft: the base gear is behind it
        rp.update(
            compliance_stiffness=mech.shaft_stiffness_Nm_rad,
            compliance_damping=mech.shaft_damping_Nms_rad,
        )
    if "torque_ripple" in effects:
        rp.update(
            ripple_revolution_amplitude=[a for a, _ in mech.ripple_revolution],
            ripple_revolution_phase=[p for _, p in mech.ripple_revolution],
            ripple_mesh_amplitude=[a for a, _ in mech.ripple_mesh],
            ripple_mesh_phase=[p for _, p in mech.ripple_mesh],
            ripple_mesh_teeth=mech.teeth,
        )
    return bp, rp


def gearsim_model(block: str, effects: tuple[str, ...] = ()):
    """The truth with `effects` as a gearsim Model (no effects: the start model
    of a diagnosis, which has the right geometry and inertia only). A torque
    delay is not a rig parameter: with sensor_delay the model is the
    analysis' AnalysisModel with its torque_delay."""
    import gearsim

    bp, rp = _gearsim_parameters(block, effects)
    if "sensor_delay" not in effects:
        return gearsim.Model(block, bp, rp)
    from gearsim.analysis.modelkit import AnalysisModel

    delay = _truth_values(block, effects)[2]["torque_delay_s"]
    return AnalysisModel(block, bp, rp, analysis={"torque_delay": delay})
