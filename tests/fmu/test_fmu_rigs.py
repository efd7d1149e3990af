"""FMI 2.0 co-simulation FMUs of the gear and rack rigs (fmu/, docs/fmu.md).

- the FMUs pass fmpy's validation; their parameters, units and start values
  are the C defaults;
- fmpy.simulate_fmu of scripted scenarios equals the same scenario run
  directly through the C rig (libgearsim.so via cffi);
- bad parameter values are refused with fmi2Error and a logged message that
  names the parameter; bad communication steps are refused;
- get/set and serialised FMU state reproduce a continuation bit for bit;
- tunable parameters apply to a running rig; only fmi2* symbols are exported.
"""

from __future__ import annotations

import math
import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy", reason="fmpy is not installed: run scripts/build_fmu.sh")

from fmpy.fmi1 import FMICallException  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402
from fmu_reference import (  # noqa: E402
    INPUT_PREFIX,
    INPUTS,
    OUTPUTS,
    fmi_unit,
    split_name,
)
from fmu_support import FMU_DIR, MAX_DIFFS, REPO, RIGS  # noqa: E402

FMI2_ERROR = 3


def start_value(v):
    """The start value of a model variable as a Python value (fmpy keeps strings)."""
    if v.type == "Boolean":
        return v.start in ("true", "1", True)
    if v.type in ("Integer", "Enumeration"):
        return int(v.start)
    return float(v.start)


# ---------------------------------------------------------------- validation


@pytest.mark.parametrize("rig", RIGS)
def test_validate_fmu_finds_no_problem(fmus, rig):
    assert validate_fmu(str(fmus[rig])) == []


@pytest.mark.parametrize("rig", RIGS)
def test_fmu_layout(fmus, model_descriptions, rig):
    md = model_descriptions[rig]
    ident = f"gearsim_{rig}_rig"
    assert md.fmiVersion == "2.0"
    assert md.coSimulation.modelIdentifier == ident
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
    with zipfile.ZipFile(fmus[rig]) as zf:
        names = set(zf.namelist())
    assert {"modelDescription.xml", f"binaries/linux64/{ident}.so"} <= names
    assert float(md.defaultExperiment.stepSize) == 1e-3


@pytest.mark.parametrize("rig", RIGS)
def test_every_parameter_with_c_default_and_unit(model_descriptions, reference, rig):
    """Every leaf of the C params structs is an FMI parameter, with the C default."""
    md = model_descriptions[rig]
    fields = reference.fields(rig)
    params = [v for v in md.modelVariables if v.causality == "parameter"]
    structs = reference.default_params(rig)
    seen_bases = set()
    for v in params:
        base, _ = split_name(v.name)
        assert base in fields, f"{v.name} has no C field in the test mapping"
        seen_bases.add(base)
        expected = reference.get(rig, structs, v.name)
        if v.type == "Boolean":
            assert start_value(v) == (expected != 0), v.name
        else:
            assert start_value(v) == expected, v.name
        assert v.initial == "exact" and v.variability in ("fixed", "tunable")
    assert seen_bases == set(fields)
    # every C field is reachable from an FMI parameter
    block_type = "gs_simple_gear_params" if rig == "gear" else "gs_rack_pinion_params"
    leaves = {f"block.{p}" for p in reference.leaf_fields(block_type)}
    leaves |= {f"rig.{p}" for p in reference.leaf_fields("gs_rig_params")}
    if rig == "rack":
        leaves.discard("block.backlash.base_radius_m")  # unused by the rack (rack_pinion.h)
    assert leaves == set(fields.values())
    # tables are complete: GS_TABLE_MAX entries (10x10 for the matrix)
    names = {v.name for v in params}
    assert "temperature_vector[10]" in names and "efficiency_vector[10]" in names
    if rig == "gear":
        assert "efficiency_matrix[10,10]" in names and "viscous_coefficients[2]" in names
    # units and variabilities
    by_name = {v.name: v for v in md.modelVariables}
    driven = "follower_inertia" if rig == "gear" else "rack_mass"
    assert by_name[driven].unit == ("kg.m2" if rig == "gear" else "kg")
    assert by_name["inputs.load"].unit == ("N.m" if rig == "gear" else "N")
    assert by_name["follower_acceleration"].unit == ("rad/s2" if rig == "gear" else "m/s2")
    assert by_name["follower_speed"].unit == ("rad/s" if rig == "gear" else "m/s")
    assert by_name["dt"].unit == "s" and by_name["dt"].variability == "fixed"
    assert by_name["efficiency_const"].variability == "tunable"
    assert by_name["temperature_vector[1]"].unit == "K"
    # the rig terms of physics.md 11: driven-side units follow the rig
    assert by_name["load_breakaway_friction"].unit == ("N.m" if rig == "gear" else "N")
    assert by_name["load_stribeck_speed"].unit == ("rad/s" if rig == "gear" else "m/s")
    assert by_name["compliance_stiffness"].unit == "N.m/rad"
    assert by_name["compliance_stiffness"].variability == "fixed"
    assert by_name["compliance_damping"].unit == "N.m.s/rad"
    for family in ("revolution", "mesh"):
        assert by_name[f"ripple_{family}_amplitude[2]"].unit == "N.m"
        assert by_name[f"ripple_{family}_phase[2]"].unit == "rad"
        assert f"ripple_{family}_phase[3]" not in by_name
    assert by_name["ripple_mesh_teeth"].type == "Integer"
    units = {u.name for u in md.unitDefinitions}
    assert all(v.unit in units for v in md.modelVariables if v.unit is not None)


@pytest.mark.parametrize("rig", RIGS)
def test_inputs_and_outputs(model_descriptions, reference, rig):
    md = model_descriptions[rig]
    inputs = [v for v in md.modelVariables if v.causality == "input"]
    outputs = [v for v in md.modelVariables if v.causality == "output"]
    assert [v.name for v in inputs] == list(INPUTS)
    assert [v.name for v in outputs] == list(OUTPUTS)
    # names, units and descriptions are those of the one table (gearsim/fields.h,
    # read here from the library's gs_rig_input_info / gs_rig_output_info)
    for variables, which, prefix in ((inputs, "input", INPUT_PREFIX), (outputs, "output", "")):
        table = reference.field_table(which)
        assert [v.name for v in variables] == [prefix + f["name"] for f in table]
        for v, f in zip(variables, table, strict=True):
            assert v.unit == fmi_unit(f[f"{rig}_unit"]), v.name
            assert v.description == f["doc"], v.name
            assert v.type == "Real" and v.variability == "continuous"
    assert [md.modelVariables.index(u.variable) for u in md.outputs] == [
        i for i, v in enumerate(md.modelVariables) if v.causality == "output"
    ]


@pytest.mark.parametrize("rig", RIGS)
def test_only_fmi2_symbols_exported(unzipped, rig):
    nm = shutil.which("nm")
    if nm is None:
        pytest.skip("nm not available")
    so = Path(unzipped[rig], "binaries", "linux64", f"gearsim_{rig}_rig.so")
    out = subprocess.run(
        [nm, "-D", "--defined-only", str(so)], check=True, capture_output=True, text=True
    ).stdout
    symbols = [line.split()[-1] for line in out.splitlines() if line.strip()]
    assert "fmi2DoStep" in symbols and "fmi2Instantiate" in symbols
    assert [s for s in symbols if not s.startswith("fmi2")] == []


@pytest.mark.parametrize("rig", RIGS)
def test_docs_variable_table_is_current(rig):
    """docs/fmu.md carries the generator's table (regenerate it when this fails)."""
    generator = FMU_DIR / "gs_fmu_modeldescription"
    if not generator.is_file():
        pytest.skip(f"{generator} not built")
    table = subprocess.run(
        [str(generator), "markdown", rig], check=True, capture_output=True, text=True
    ).stdout.strip()
    doc = (REPO / "docs" / "fmu.md").read_text()
    assert table in doc, f"docs/fmu.md: regenerate with {generator} markdown {rig}"


# ------------------------------------------------- FMU vs direct C rig runs


def _scenarios():
    two_pi = 2.0 * math.pi
    return {
        "gear_speed_thermal_table": dict(
            rig="gear",
            dt=1e-3,
            substeps=1,
            n=400,
            start={
                "teeth_ratio": 3.0,
                "friction_model": 4,
                "follower_inertia": 0.02,
                "base_inertia": 1e-3,
                "viscous_coefficients[1]": 0.01,
                "viscous_coefficients[2]": 0.02,
                "load_coulomb_friction": 0.3,
                "load_offset": 0.1,
                "heat_path": True,
                "thermal_resistance": 0.5,
                "thermal_mass": 5.0,
                "accel_filter_time_constant": 0.01,
                "power_threshold": 0.5,
                "efficiency_matrix[2,3]": 0.93,
            },
            inputs=lambda t: {
                "inputs.base_speed": 20.0 * np.sin(two_pi * 2.0 * t) + 5.0 * t,
                "inputs.load": np.where(t < 0.2, 0.0, 2.0),
                "inputs.ambient_temperature": 293.15 + 10.0 * t,
            },
        ),
        "gear_torque_backlash_measured_T": dict(
            rig="gear",
            dt=5e-4,
            substeps=5,
            n=200,
            start={
                "dt": 5e-4,
                "base_drive": 1,
                "base_inertia": 0.01,
                "initial_base_speed": 1.0,
                "backlash_enabled": True,
                "stiffness": 1e5,
                "damping": 50.0,
                "linear_backlash": 2e-3,
                "friction_model": 3,
                "temperature_input": True,
                "output_shaft_rotates": 0,
            },
            inputs=lambda t: {
                "inputs.base_torque": 2.0 * np.sin(two_pi * 3.0 * t),
                "inputs.load": np.full_like(t, -0.5),
                "inputs.measured_temperature": 290.0 + 80.0 * t,
            },
        ),
        "rack_speed_backlash": dict(
            rig="rack",
            dt=1e-3,
            substeps=2,
            n=250,
            start={
                "backlash_enabled": True,
                "hard_stop_model": 2,
                "contact_substeps": 4,
                "friction_model": 1,
                "efficiency_const": 0.85,
                "rack_mass": 2.0,
                "pinion_viscous_coefficient": 0.01,
                "rack_viscous_coefficient": 5.0,
                "load_coulomb_friction": 3.0,
                "stiffness": 2e5,
            },
            inputs=lambda t: {
                "inputs.base_speed": 10.0 * np.sin(two_pi * 1.5 * t),
                "inputs.load": 20.0 * np.cos(two_pi * 4.0 * t),
            },
        ),
        "rack_torque_tooth_table": dict(
            rig="rack",
            dt=1e-3,
            substeps=1,
            n=300,
            start={
                "base_drive": 1,
                "base_inertia": 2e-3,
                "parameterization": 1,
                "teeth_count": 18.0,
                "spacing": 0.01,
                "rack_directionality": 1,
                "friction_model": 3,
                "heat_path": True,
                "thermal_mass": 2.0,
                "temperature_count": 4,
                "temperature_vector[1]": 270.0,
                "temperature_vector[2]": 290.0,
                "temperature_vector[3]": 310.0,
                "temperature_vector[4]": 330.0,
                "efficiency_vector[1]": 0.9,
                "efficiency_vector[2]": 0.85,
                "efficiency_vector[3]": 0.8,
                "efficiency_vector[4]": 0.75,
                "rack_mass": 1.5,
            },
            inputs=lambda t: {
                "inputs.base_torque": np.where(t < 0.1, 1.0, -0.5),
                "inputs.load": np.full_like(t, 4.0),
                "inputs.ambient_temperature": np.full_like(t, 300.0),
            },
        ),
        # the rig terms (physics.md 11): a compliant
        # base shaft with Stribeck friction and both ripple families
        "gear_speed_compliant_stribeck_ripple": dict(
            rig="gear",
            dt=1e-3,
            substeps=2,
            n=250,
            start={
                "friction_model": 1,
                "efficiency_const": 0.9,
                "base_inertia": 2e-3,
                "compliance_stiffness": 400.0,
                "compliance_damping": 0.2,
                "load_coulomb_friction": 0.3,
                "load_breakaway_friction": 0.8,
                "load_stribeck_speed": 0.5,
                "ripple_revolution_amplitude[1]": 0.2,
                "ripple_revolution_phase[1]": 0.3,
                "ripple_revolution_amplitude[2]": 0.05,
                "ripple_mesh_amplitude[1]": 0.04,
                "ripple_mesh_phase[2]": -1.0,
                "ripple_mesh_amplitude[2]": 0.01,
                "ripple_mesh_teeth": 19,
            },
            inputs=lambda t: {
                "inputs.base_speed": 12.0 * np.sin(two_pi * 2.0 * t),
                "inputs.load": np.where(t < 0.2, 0.5, -1.0),
            },
        ),
        "rack_torque_stribeck_ripple": dict(
            rig="rack",
            dt=1e-3,
            substeps=1,
            n=300,
            start={
                "base_drive": 1,
                "base_inertia": 1e-3,
                "rack_mass": 1.0,
                "pinion_radius": 0.02,
                "load_coulomb_friction": 5.0,
                "load_breakaway_friction": 15.0,
                "load_stribeck_speed": 0.013,
                "ripple_mesh_amplitude[1]": 0.02,
                "ripple_mesh_teeth": 12,
            },
            inputs=lambda t: {
                "inputs.base_torque": 0.5 * np.sin(two_pi * 3.0 * t),
                "inputs.load": np.full_like(t, 2.0),
            },
        ),
        # a compliant mesh (no base inertia) with the driven
        # friction creeping behind it, and the step-mean speed of a rigid rack
        "gear_speed_mesh_spring_creep": dict(
            rig="gear",
            dt=1e-3,
            substeps=1,
            n=250,
            start={
                "friction_model": 1,
                "efficiency_const": 0.9,
                "base_inertia": 0.0,
                "compliance_stiffness": 400.0,
                "compliance_damping": 0.2,
                "load_coulomb_friction": 0.3,
                "load_coulomb_speed_threshold": 0.05,
                "load_friction_regularised": True,
            },
            inputs=lambda t: {
                "inputs.base_speed": 12.0 * np.sin(two_pi * 2.0 * t),
                "inputs.load": np.where(t < 0.2, 0.5, -1.0),
            },
        ),
        "rack_speed_ramp_creep": dict(
            rig="rack",
            dt=1e-3,
            substeps=1,
            n=200,
            start={
                "rack_mass": 1.0,
                "pinion_radius": 0.02,
                "load_coulomb_friction": 3.0,
                "base_speed_ramp": True,
                "load_friction_regularised": True,
            },
            inputs=lambda t: {
                "inputs.base_speed": 20.0 * np.sin(two_pi * 4.0 * t),
                "inputs.load": np.full_like(t, 1.0),
            },
        ),
    }


SCENARIOS = _scenarios()


def _signals(inputs: dict[str, np.ndarray], t: np.ndarray) -> np.ndarray:
    signals = np.zeros(len(t), dtype=[("time", np.float64)] + [(k, np.float64) for k in INPUTS])
    signals["time"] = t
    defaults = {"inputs.ambient_temperature": 293.15, "inputs.measured_temperature": 300.0}
    for name in INPUTS:
        signals[name] = inputs.get(name, np.full_like(t, defaults.get(name, 0.0)))
    return signals


@pytest.mark.parametrize("name", list(SCENARIOS))
def test_simulate_fmu_matches_direct_c_run(unzipped, reference, name):
    sc = SCENARIOS[name]
    h = sc["substeps"] * sc["dt"]
    n = sc["n"]
    t = np.arange(n + 1) * h  # the communication points fmpy uses
    inputs = sc["inputs"](t)
    signals = _signals(inputs, t)
    result = fmpy.simulate_fmu(
        unzipped[sc["rig"]],
        start_time=0.0,
        stop_time=n * h,
        output_interval=h,
        input=signals,
        start_values=sc["start"],
        output=list(OUTPUTS),
    )
    assert len(result) == n + 1
    np.testing.assert_array_equal(result["time"], t)
    direct = reference.run(
        sc["rig"], sc["start"], {k: signals[k][:n] for k in INPUTS}, sc["substeps"]
    )
    worst = 0.0
    for out in OUTPUTS:
        fmu_values = result[out][1:]
        ref_values = direct[out]
        assert np.all(np.isfinite(ref_values)), out
        diff = np.abs(fmu_values - ref_values)
        scale = 1.0 + np.max(np.abs(ref_values))
        worst = max(worst, float(np.max(diff)))
        assert np.max(diff) <= 1e-12 * scale, f"{out}: max |FMU - C| = {np.max(diff):.3g}"
    MAX_DIFFS[name] = worst
    # the scenario moves: not a trivially zero run
    assert np.max(np.abs(direct["follower_speed"])) > 0.01
    # outputs at t = 0: initial state
    first = result[0]
    if sc["start"].get("base_drive", 0) == 0:
        assert first["base_speed"] == signals["inputs.base_speed"][0]
    else:
        assert first["base_speed"] == sc["start"].get("initial_base_speed", 0.0)
    if sc["start"].get("temperature_input"):
        assert first["temperature"] == signals["inputs.measured_temperature"][0]
    else:
        assert first["temperature"] == 300.0


# ------------------------------------------------------- refused values


BAD_VALUES = [
    # rig, start values (valid context + one bad value), parameter named in the log
    ("gear", {"friction_model": 1, "efficiency_const": 1.5}, "efficiency_const"),
    ("gear", {"teeth_ratio": -2.0}, "teeth_ratio"),
    ("gear", {"dt": 0.0}, "dt"),
    ("gear", {"follower_inertia": 0.0}, "follower_inertia"),
    ("gear", {"friction_model": 3, "temperature_count": 1}, "temperature_vector"),
    ("gear", {"friction_model": 4, "efficiency_matrix[2,2]": 1.2}, "efficiency_matrix"),
    ("gear", {"output_shaft_rotates": 5}, "output_shaft_rotates"),
    (
        "gear",
        {"backlash_enabled": True, "initial_backlash_position": 0.01},
        "initial_backlash_position",
    ),
    ("gear", {"base_drive": 1, "base_inertia": 0.0}, "base_inertia"),
    ("gear", {"backlash_enabled": True, "contact_substeps": 100}, "contact_substeps"),
    ("gear", {"viscous_coefficients[2]": -1.0}, "viscous_coefficients"),
    ("rack", {"friction_model": 2}, "friction_model"),
    ("rack", {"pinion_radius": 0.0}, "pinion_radius"),
    ("rack", {"rack_mass": -1.0}, "rack_mass"),
    ("rack", {"parameterization": 1, "spacing": 0.0}, "spacing"),
    ("rack", {"heat_path": True, "thermal_resistance": 0.0}, "thermal_resistance"),
    ("rack", {"backlash_enabled": True, "stiffness": float("nan")}, "stiffness"),
    (
        "gear",
        {"load_coulomb_friction": 2.0, "load_breakaway_friction": 1.0},
        "load_breakaway_friction",
    ),
    ("rack", {"load_breakaway_friction": 1.0, "load_stribeck_speed": 0.0}, "load_stribeck_speed"),
    # base_inertia 0 with a compliance puts the spring at the mesh;
    # a negative one is still refused
    ("gear", {"compliance_stiffness": 100.0, "base_inertia": -1e-3}, "base_inertia"),
    (
        "rack",
        {"compliance_stiffness": 100.0, "base_inertia": 1e-3, "base_drive": 1},
        "compliance_stiffness",
    ),
    ("gear", {"compliance_damping": -0.1}, "compliance_damping"),
    ("gear", {"ripple_revolution_amplitude[2]": -0.1}, "ripple_revolution_amplitude"),
    ("rack", {"ripple_mesh_amplitude[1]": 0.1}, "ripple_mesh_teeth"),
    ("gear", {"ripple_mesh_phase[2]": float("inf")}, "ripple_mesh_phase"),
]


@pytest.mark.parametrize(
    "rig,values,parameter", BAD_VALUES, ids=[f"{r}-{p}" for r, _, p in BAD_VALUES]
)
def test_bad_parameter_refused_with_logged_name(
    instance, model_descriptions, rig, values, parameter
):
    inst = instance(rig)
    inst.setup(values)
    with pytest.raises(FMICallException) as info:
        inst.fmu.exitInitializationMode()
    assert info.value.status == FMI2_ERROR
    errors = inst.errors()
    assert len(errors) == 1
    assert f'parameter "{parameter}" rejected' in errors[0]
    # still in initialisation mode: restoring the start values lets the FMU start
    md_vars = {v.name: v for v in model_descriptions[rig].modelVariables}
    inst.set({name: start_value(md_vars[name]) for name in values})
    inst.fmu.exitInitializationMode()
    inst.step(1e-3)
    assert np.all(np.isfinite(inst.get(list(OUTPUTS))))


def test_step_size_not_multiple_of_dt_refused(instance):
    inst = instance("gear")
    inst.start({"dt": 1e-3})
    with pytest.raises(FMICallException) as info:
        inst.fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=1.5e-3)
    assert info.value.status == FMI2_ERROR
    assert any("not a whole multiple of the internal step dt = 0.001" in m for m in inst.errors())
    # the instance is unchanged and a valid step still works
    inst.step(3e-3)
    ok = fmpy.fmi2.fmi2Real()
    inst.fmu.fmi2GetRealStatus(inst.fmu.component, fmpy.fmi2.fmi2LastSuccessfulTime, ok)
    assert ok.value == pytest.approx(3e-3, abs=1e-15)
    with pytest.raises(FMICallException):
        inst.fmu.doStep(currentCommunicationPoint=1.0, communicationStepSize=1e-3)  # wrong time
    assert any("differs from the FMU time" in m for m in inst.errors())


def test_fixed_parameter_refused_in_step_mode(instance):
    inst = instance("gear")
    inst.start()
    with pytest.raises(FMICallException):
        inst.set({"teeth_ratio": 4.0})
    assert any('"teeth_ratio" is a fixed parameter' in m for m in inst.errors())
    with pytest.raises(FMICallException):
        inst.set({"base_speed": 1.0})  # an output
    assert any('"base_speed" is an output' in m for m in inst.errors())


def test_reset_restores_start_values_and_start_time_is_kept(instance):
    def run(inst):
        rows = []
        for k in range(30):
            inst.set({"inputs.base_speed": 3.0 + k, "inputs.load": 0.2})
            inst.step(2e-3)
            rows.append(inst.get(list(OUTPUTS)))
        return np.array(rows)

    values = {"friction_model": 1, "efficiency_const": 0.9, "heat_path": True}
    inst = instance("gear")
    inst.start(values, start_time=10.0)
    first = run(inst)
    inst.fmu.reset()
    assert inst.fmu.getInteger([inst.vars["friction_model"].valueReference]) == [0]
    assert inst.fmu.getBoolean([inst.vars["heat_path"].valueReference]) == [False]
    inst.start(values, start_time=10.0)
    assert run(inst).tobytes() == first.tobytes()


def test_debug_logging_categories(instance):
    inst = instance("rack")
    inst.fmu.setDebugLogging(True, ["logStatusError"])
    inst.start()
    assert [m for _, cat, m in inst.logs if cat == "logInfo"] == []
    inst.fmu.setDebugLogging(True, ["logInfo"])
    inst.set({"efficiency_const": 0.9})
    assert any("tunable parameters applied" in m for _, cat, m in inst.logs if cat == "logInfo")
    with pytest.raises(FMICallException):
        inst.fmu.setDebugLogging(True, ["logNoSuchCategory"])


# ------------------------------------------------------------ FMU state


STATE_SCENARIO = {
    "base_drive": 1,
    "base_inertia": 0.01,
    "initial_base_speed": 2.0,
    "backlash_enabled": True,
    "stiffness": 1e5,
    "damping": 30.0,
    "friction_model": 3,
    "heat_path": True,
    "thermal_mass": 1.0,
    "load_coulomb_friction": 0.2,
}


def _drive(inst: object, steps: int, k0: int, h: float = 2e-3) -> np.ndarray:
    rows = []
    for k in range(k0, k0 + steps):
        t = k * h
        inst.set(
            {
                "inputs.base_torque": 3.0 * math.sin(2 * math.pi * 4.0 * t),
                "inputs.load": -0.3 + 0.1 * math.cos(9.0 * t),
            }
        )
        inst.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        rows.append(inst.get(list(OUTPUTS)))
    return np.array(rows)


@pytest.mark.parametrize("rig", RIGS)
def test_get_set_state_reproduces_continuation_bit_for_bit(instance, rig):
    inst = instance(rig)
    inst.start(STATE_SCENARIO)
    _drive(inst, 60, 0)
    state = inst.fmu.getFMUstate()
    first = _drive(inst, 80, 60)
    inst.fmu.setFMUstate(state)
    again = _drive(inst, 80, 60)
    assert first.tobytes() == again.tobytes()
    assert np.max(np.abs(first[:, list(OUTPUTS).index("contact_force")])) > 0  # backlash engaged

    serialized = inst.fmu.serializeFMUstate(state)
    inst.fmu.freeFMUstate(state)
    # a fresh instance with default parameters continues from the bytes
    other = instance(rig)
    other.start()
    restored = other.fmu.deSerializeFMUstate(serialized)
    other.fmu.setFMUstate(restored)
    other.fmu.freeFMUstate(restored)
    third = _drive(other, 80, 60)
    assert first.tobytes() == third.tobytes()


def test_deserialize_rejects_foreign_bytes(instance):
    gear = instance("gear")
    gear.start()
    state = gear.fmu.getFMUstate()
    blob = gear.fmu.serializeFMUstate(state)
    gear.fmu.freeFMUstate(state)
    rack = instance("rack")
    rack.start()
    with pytest.raises(FMICallException):
        rack.fmu.deSerializeFMUstate(blob)
    with pytest.raises(FMICallException):
        gear.fmu.deSerializeFMUstate(blob[:-1])
    assert any("not a serialized state of this FMU" in m for m in rack.errors())


# ------------------------------------------------------ tunable parameters


def test_tunable_parameter_round_trip_keeps_state_bit_for_bit(instance):
    """Changing a tunable and restoring it between two steps is a no-op."""
    plain = instance("gear")
    plain.start(STATE_SCENARIO)
    expected = _drive(plain, 120, 0)
    tuned = instance("gear")
    tuned.start(STATE_SCENARIO)
    a = _drive(tuned, 50, 0)
    tuned.set({"thermal_mass": 7.0, "load_coulomb_friction": 0.9})
    tuned.set({"thermal_mass": 1.0, "load_coulomb_friction": 0.2})
    # a refused tunable value changes nothing either
    with pytest.raises(FMICallException):
        tuned.set({"load_offset": 0.5, "thermal_resistance": -1.0})
    assert any('parameter "thermal_resistance" rejected' in m for m in tuned.errors())
    assert tuned.fmu.getReal([tuned.vars["load_offset"].valueReference])[0] == 0.0
    b = _drive(tuned, 70, 50)
    assert np.concatenate([a, b]).tobytes() == expected.tobytes()


def test_tunable_load_offset_matches_shifted_load_in_c(instance, reference):
    """load_offset enters the rig as load + load_offset: tuning it at step k equals
    shifting the load input by the same amount from step k in a direct C run."""
    h, n, k, delta = 1e-3, 200, 80, 1.25
    start = {"friction_model": 1, "efficiency_const": 0.9, "follower_inertia": 0.05}
    t = np.arange(n) * h
    speed = 15.0 * np.sin(2 * math.pi * 2.0 * t)
    inst = instance("gear")
    inst.start(start)
    rows = []
    for i in range(n):
        if i == k:
            inst.set({"load_offset": delta})
        inst.set({"inputs.base_speed": speed[i], "inputs.load": 0.5})
        inst.step(h)
        rows.append(inst.get(list(OUTPUTS)))
    fmu_out = np.array(rows)
    load = np.where(np.arange(n) < k, 0.5, 0.5 + delta)
    direct = reference.run("gear", start, {"inputs.base_speed": speed, "inputs.load": load}, 1)
    ref_out = np.column_stack([direct[o] for o in OUTPUTS])
    assert fmu_out.tobytes() == ref_out.tobytes()
    MAX_DIFFS["tunable_load_offset"] = float(np.max(np.abs(fmu_out - ref_out)))


def test_tunable_ripple_adds_its_torque_at_the_mid_angle(instance):
    """A lossless speed-driven gear at a constant 6 rad/s from rest: step i
    (1-based) turns the base from (i-1)*w*h to i*w*h, and the ripple is taken
    at the mid angle (i - 1/2)*w*h (physics.md 11). Switching on A1 = 0.4 N*m
    at phase 0.25 rad from step 31 adds A1*cos((i - 1/2)*w*h + 0.25) to
    base_torque, which is 0 before (no load, no loss, constant speed)."""
    h, n, k, w, amp, phase = 1e-3, 60, 30, 6.0, 0.4, 0.25
    inst = instance("gear")
    inst.start({"friction_model": 0})
    torques = []
    for i in range(n):
        if i == k:
            inst.set({"ripple_revolution_amplitude[1]": amp, "ripple_revolution_phase[1]": phase})
        inst.set({"inputs.base_speed": w, "inputs.load": 0.0})
        inst.step(h)
        torques.append(inst.get(["base_torque"])[0])
    theta_mid = (np.arange(1, n + 1) - 0.5) * w * h
    expected = np.where(np.arange(n) < k, 0.0, amp * np.cos(theta_mid + phase))
    np.testing.assert_allclose(torques, expected, rtol=0, atol=1e-13)
