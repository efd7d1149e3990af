"""The external corpus (../shared/data/truthcases, README inside): nine
records of a rig simulator written by someone who never read gearsim's code,
each missing one or two effects from its starting model.

run_case does what a new user does: diagnose, add the best candidate while
it helps, round by round, then re-fit the effects added together; and checks
the corpus README's criteria on the way:

- rank: while a hidden effect is missing, each round's top candidate is one
  of them, or within 2 % of the best of them (validation error);
- drop: the final nrmse is at most half the start's and at most
  max(1.5 x floor, floor + 0.01), floor being truth.json's
  nrmse.measured_inputs.truth (the true model replayed on the measured
  inputs);
- parameters: efficiency within +-0.01; the viscous coefficient at the input
  shaft within +-20 %; backlash gap and Coulomb friction within +-20 %; idle
  torque within +-30 % and the efficiency at the nominal torque within
  +-0.02; the temperature table within +-0.015 at 300, 320 and 340 K.

true_model builds the simulator's true model in gearsim with the structure
that represents its compliant mesh: the mesh spring-damper as a compliance at
the mesh (stiffness times the base radius squared, no base inertia) or, with
backlash, as the contact's stiffness and damping with the full_damped law;
and its friction regularised at low speed, F tanh(v/v0) being gearsim's
F tanh(4 v/v_th) with v_th = 4 v0 (v0 = 0.02 rad/s on a gear follower, 2 mm/s
on a rack, README)."""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from functools import cache
from typing import Any

import numpy as np
from analysis_helpers import REPO

from gearsim.analysis import load_measurement, load_model, prepare_inputs
from gearsim.analysis.fitting import REFIT
from gearsim.analysis.report import run_rounds

CORPUS = os.path.normpath(os.path.join(REPO, "..", "shared", "data", "truthcases"))
CASES = (
    "pub_gear_backlash",
    "pub_gear_coulomb_viscous",
    "pub_gear_efficiency",
    "pub_gear_idle_loss",
    "pub_gear_temperature",
    "pub_gear_viscous",
    "pub_rack_backlash",
    "pub_rack_coulomb",
    "pub_rack_viscous_backlash",
)
MAX_ROUNDS = 4
RANK_MARGIN = 0.02
#: the regularisation speeds of the simulator's Coulomb friction, tanh(v/v0)
V0 = {"simple_gear": 0.02, "rack_pinion": 0.002}


def corpus_present() -> bool:
    return os.path.isdir(CORPUS) and all(os.path.isdir(os.path.join(CORPUS, c)) for c in CASES)


def truth(case: str) -> dict:
    with open(os.path.join(CORPUS, case, "truth.json"), encoding="utf-8") as f:
        return json.load(f)


def floor(case: str) -> float:
    return float(truth(case)["nrmse"]["measured_inputs"]["truth"]["nrmse"])


@cache
def record(case: str):
    model = load_model(os.path.join(CORPUS, case, "start.toml"))
    meas = load_measurement(os.path.join(CORPUS, case, "data.csv.gz"), model.block)
    return model, meas, prepare_inputs(meas)


def true_model(case: str):
    """The simulator's true model in gearsim (module docstring)."""
    t = truth(case)
    model = load_model(os.path.join(CORPUS, case, "truth.toml"))
    block, rig = dict(model.block_params), dict(model.rig_params)
    mesh = t["mesh_compliance"]
    gear = model.block == "simple_gear"
    r_b = float(mesh["base_radius"]) if gear else float(t["derived"]["pinion_radius_m"])
    rig["load_coulomb_speed_threshold"] = 4.0 * V0[model.block]
    rig["load_friction_regularised"] = True
    if block.get("backlash_enabled"):
        block.update(hard_stop_model="full_damped", contact_no_pull=True)
    else:
        rig.update(
            compliance_stiffness=float(mesh["stiffness"]) * r_b**2,
            compliance_damping=float(mesh["damping"]) * r_b**2,
            base_inertia=0.0,
        )
    return model.replace(block_params=block, rig_params=rig)


# ---------------------------------------------------------------- parameters


def _eff_at(block: dict, load_out: float) -> float:
    """Efficiency of the load-dependent law (eq. 2.4-2.5) at an output torque."""
    g = float(block["teeth_ratio"])
    k = (
        1.0 / block["efficiency_nominal"]
        - 1.0
        - g * block["idle_torque"] / block["nominal_output_torque"]
    )
    t_in = load_out / g
    return t_in / (t_in + block["idle_torque"] + k * t_in)


def parameter_checks(case: str, model: Any) -> dict[str, tuple[Any, Any, bool]]:
    """effect -> (fitted, true, within the README's tolerance)."""
    t = truth(case)
    rig, blk = model.resolved_rig_params, model.resolved_block_params
    gear = t["block"] == "simple_gear"
    out: dict[str, tuple[Any, Any, bool]] = {}
    for eff, p in t["hidden_parameters"].items():
        if eff == "meshing_efficiency":
            got = (
                blk["efficiency_const"] if blk["friction_model"] == "constant_efficiency" else None
            )
            out[eff] = (
                got,
                p["efficiency_const"],
                got is not None and abs(got - p["efficiency_const"]) <= 0.01,
            )
        elif eff == "viscous_friction":
            if gear:
                g = float(t["truth_model"]["block"]["teeth_ratio"])
                got = blk["viscous_coefficients"][0] + blk["viscous_coefficients"][1] / g**2
                want = p["viscous_coefficients"][0] + p["viscous_coefficients"][1] / g**2
            else:
                r = float(t["derived"]["pinion_radius_m"])
                got = blk["pinion_viscous_coefficient"] + blk["rack_viscous_coefficient"] * r * r
                want = p["pinion_viscous_coefficient"] + p["rack_viscous_coefficient"] * r * r
            out[eff] = (got, want, abs(got / want - 1.0) <= 0.2)
        elif eff == "backlash":
            got = blk["linear_backlash"] if blk["backlash_enabled"] else 0.0
            out[eff] = (got, p["linear_backlash"], abs(got / p["linear_backlash"] - 1.0) <= 0.2)
        elif eff == "coulomb_friction":
            got, want = rig["load_coulomb_friction"], p["load_coulomb_friction"]
            out[eff] = (got, want, abs(got / want - 1.0) <= 0.2)
        elif eff == "load_dependent_efficiency":
            if blk["friction_model"] != "load_dependent_efficiency":
                out[eff] = (blk["friction_model"], "load_dependent_efficiency", False)
                continue
            tb = dict(p, teeth_ratio=t["truth_model"]["block"]["teeth_ratio"])
            e_got, e_want = (
                _eff_at(blk, p["nominal_output_torque"]),
                _eff_at(tb, p["nominal_output_torque"]),
            )
            ok = (
                abs(blk["idle_torque"] / p["idle_torque"] - 1.0) <= 0.3
                and abs(e_got - e_want) <= 0.02
            )
            out[eff] = ((blk["idle_torque"], e_got), (p["idle_torque"], e_want), ok)
        elif eff == "temperature_dependent_efficiency":
            if blk["friction_model"] != "temperature_dependent_efficiency":
                out[eff] = (blk["friction_model"], "temperature_dependent_efficiency", False)
                continue
            ts = [300.0, 320.0, 340.0]
            got = np.interp(ts, blk["temperature_vector"], blk["efficiency_vector"])
            want = np.interp(ts, p["temperature_vector"], p["efficiency_vector"])
            out[eff] = (got.tolist(), want.tolist(), bool(np.all(np.abs(got - want) <= 0.015)))
        else:  # pragma: no cover - the README's criteria name no other effect
            out[eff] = (None, p, False)
    return out


# ---------------------------------------------------------------- the user's flow


@dataclass
class Round:
    top: str
    helps: bool
    validation_nrmse: float
    nrmse: float
    rank_ok: bool | None  # None: no hidden effect was missing any more
    note: str = ""


@dataclass
class CaseRun:
    case: str
    hidden: list[str]
    floor: float
    start_nrmse: float
    final_nrmse: float
    rounds: list[Round]
    refit: Any
    final_model: Any
    diagnoses: list[Any] = field(default_factory=list)
    params: dict[str, tuple[Any, Any, bool]] = field(default_factory=dict)
    missing: list[str] = field(default_factory=list)

    @property
    def rank_ok(self) -> bool:
        return not self.missing and all(r.rank_ok is not False for r in self.rounds)

    @property
    def drop_ok(self) -> bool:
        return self.final_nrmse <= 0.5 * self.start_nrmse and self.final_nrmse <= max(
            1.5 * self.floor, self.floor + 0.01
        )

    @property
    def params_ok(self) -> bool:
        return bool(self.params) and all(ok for *_, ok in self.params.values())

    def summary(self) -> str:
        tops = " > ".join(r.top for r in self.rounds if r.helps) or "(nothing)"
        return (
            f"{self.case}: start {self.start_nrmse:.4f}, final {self.final_nrmse:.4f} "
            f"({self.final_nrmse / self.floor:.2f}x the floor {self.floor:.4f}); rounds: {tops}"
            f"{'; refit' if self.refit is not None and self.refit.accepted else ''}; "
            f"parameters {self.params}"
        )


def _rank(d: Any, missing: list[str]) -> bool:
    top = d.candidates[0]
    if top.effect in missing:
        return True
    hidden = [c for c in d.candidates if c.effect in missing and c.method == "fit"]
    if not hidden:
        return False
    return hidden[0].validation_nrmse_after <= (1.0 + RANK_MARGIN) * top.validation_nrmse_after


@cache
def run_case(case: str) -> CaseRun:
    """The rounds of gearsim.analysis.report.run_rounds (what `gearsim
    report` and a user's diagnose -> fit rounds do), at most MAX_ROUNDS, with
    its final joint re-fit; then the README's checks."""
    model, meas, _ = record(case)
    t = truth(case)
    missing = list(t["hidden_effects"])
    out = run_rounds(model, meas, rounds=MAX_ROUNDS)
    rounds: list[Round] = []
    refitted = None
    for r in out:
        if r.effect == REFIT:
            refitted = r.fit
            continue
        d = r.diagnosis
        if d is None or d.best is None:
            continue
        best = d.best
        if not d.best_helps:
            rounds.append(
                Round(best.effect, False, d.validation_baseline_nrmse, d.baseline_nrmse, None)
            )
            continue
        rank = _rank(d, missing) if missing else None
        rounds.append(Round(best.effect, True, best.validation_nrmse_after, best.nrmse_after, rank))
        if best.effect in missing:
            missing.remove(best.effect)
    return CaseRun(
        case,
        list(t["hidden_effects"]),
        floor(case),
        float(out[0].compare.nrmse),
        float(out[-1].compare.nrmse),
        rounds,
        refitted,
        out[-1].model,
        [r.diagnosis for r in out if r.diagnosis is not None],
        parameter_checks(case, out[-1].model),
        missing,
    )


def finite(x: float) -> bool:
    return isinstance(x, float) and math.isfinite(x)
