"""Every validity rule of docs/physics.md section 9 (and of the rigs) raises a
ParameterError (a GearsimError and a ValueError) that names the parameter."""

import math

import pytest

import gearsim

NAN = math.nan
INF = math.inf
CONST = {"friction_model": "constant_efficiency"}
LOAD = {"friction_model": "load_dependent_efficiency"}
TEMP = {"friction_model": "temperature_dependent_efficiency"}
TLOAD = {"friction_model": "temperature_load_dependent_efficiency"}
BACKLASH = {"backlash_enabled": True}
LOCK = {"backlash_enabled": True, "contact_lock_enabled": True}
TOOTH = {"parameterization": "tooth_parameters"}

SIMPLE_GEAR_CASES = [
    ({"teeth_ratio": 0.0}, "teeth_ratio", "GS_E_NOT_POSITIVE"),
    ({"teeth_ratio": -2.0}, "teeth_ratio", "GS_E_NOT_POSITIVE"),
    ({"teeth_ratio": NAN}, "teeth_ratio", "GS_E_NOT_FINITE"),
    ({"teeth_ratio": INF}, "teeth_ratio", "GS_E_NOT_FINITE"),
    ({"teeth_ratio": 1e-310}, "teeth_ratio", "GS_E_MAGNITUDE"),  # 1/g overflows
    ({"output_shaft_rotates": "sideways"}, "output_shaft_rotates", "GS_E_OPTION"),
    ({"friction_model": "magic"}, "friction_model", "GS_E_OPTION"),
    ({"loss_smoothing": "rough"}, "loss_smoothing", "GS_E_OPTION"),
    ({**CONST, "efficiency_const": 0.0}, "efficiency_const", "GS_E_EFFICIENCY_RANGE"),
    ({**CONST, "efficiency_const": 1.01}, "efficiency_const", "GS_E_EFFICIENCY_RANGE"),
    ({**CONST, "power_threshold": 0.0}, "power_threshold", "GS_E_NOT_POSITIVE"),
    ({**LOAD, "idle_torque": -0.1}, "idle_torque", "GS_E_NEGATIVE"),
    ({**LOAD, "nominal_output_torque": 0.0}, "nominal_output_torque", "GS_E_NOT_POSITIVE"),
    ({**LOAD, "efficiency_nominal": 1.0}, "efficiency_nominal", "GS_E_NOMINAL_EFFICIENCY"),
    ({**LOAD, "efficiency_nominal": 0.0}, "efficiency_nominal", "GS_E_NOMINAL_EFFICIENCY"),
    ({**LOAD, "idle_torque": 1.0}, "idle_torque", "GS_E_IDLE_TORQUE_TOO_LARGE"),
    ({**LOAD, "speed_threshold": 0.0}, "speed_threshold", "GS_E_NOT_POSITIVE"),
    (
        {**TEMP, "temperature_vector": [300.0, 280.0, 320.0]},
        "temperature_vector",
        "GS_E_TABLE_NOT_INCREASING",
    ),
    (
        {**TEMP, "temperature_vector": [300.0], "efficiency_vector": [0.9]},
        "temperature_vector",
        "GS_E_TABLE_LENGTH",
    ),
    (
        {**TEMP, "temperature_vector": list(range(300, 311))},
        "temperature_vector",
        "GS_E_TABLE_LENGTH",
    ),
    ({**TEMP, "efficiency_vector": [0.9, 0.8]}, "efficiency_vector", "GS_E_TABLE_SIZE_MISMATCH"),
    ({**TEMP, "efficiency_vector": [0.9, 0.0, 0.8]}, "efficiency_vector", "GS_E_EFFICIENCY_RANGE"),
    ({**TEMP, "power_threshold": -1.0}, "power_threshold", "GS_E_NOT_POSITIVE"),
    ({**TEMP, "thermal_mass": 0.0}, "thermal_mass", "GS_E_NOT_POSITIVE"),
    ({**TLOAD, "load_vector": [-1.0, 50.0, 100.0]}, "load_vector", "GS_E_NEGATIVE"),
    ({**TLOAD, "load_vector": [0.0, 50.0, 50.0]}, "load_vector", "GS_E_TABLE_NOT_INCREASING"),
    (
        {**TLOAD, "efficiency_matrix": [[0.9, 0.9], [0.9, 0.9], [0.9, 0.9]]},
        "efficiency_matrix",
        "GS_E_TABLE_SIZE_MISMATCH",
    ),
    (
        {**TLOAD, "efficiency_matrix": [[0.9] * 3, [0.9] * 3, [0.9, 1.2, 0.9]]},
        "efficiency_matrix",
        "GS_E_EFFICIENCY_RANGE",
    ),
    (
        {**TLOAD, "efficiency_matrix": [[0.9] * 3, [0.9] * 2, [0.9] * 3]},
        "efficiency_matrix",
        "GS_E_TABLE_SIZE_MISMATCH",
    ),
    ({**TLOAD, "speed_threshold": 0.0}, "speed_threshold", "GS_E_NOT_POSITIVE"),
    ({"viscous_coefficients": [-0.1, 0.0]}, "viscous_coefficients", "GS_E_NEGATIVE"),
    ({"viscous_coefficients": [0.0, -0.1]}, "viscous_coefficients", "GS_E_NEGATIVE"),
    ({"viscous_coefficients": [0.0, 0.0, 0.0]}, "viscous_coefficients", "GS_E_TABLE_SIZE_MISMATCH"),
    ({"initial_temperature": 0.0}, "initial_temperature", "GS_E_NOT_POSITIVE"),
    ({**BACKLASH, "hard_stop_model": "soft"}, "hard_stop_model", "GS_E_OPTION"),
    ({**BACKLASH, "linear_backlash": 0.0}, "linear_backlash", "GS_E_NOT_POSITIVE"),
    ({**BACKLASH, "base_radius": 0.0}, "base_radius", "GS_E_NOT_POSITIVE"),
    ({**BACKLASH, "transition_region": 0.0}, "transition_region", "GS_E_TRANSITION_REGION"),
    ({**BACKLASH, "stiffness": 0.0}, "stiffness", "GS_E_NOT_POSITIVE"),
    ({**BACKLASH, "damping": -1.0}, "damping", "GS_E_NEGATIVE"),
    (
        {**BACKLASH, "initial_backlash_position": 0.6e-3},
        "initial_backlash_position",
        "GS_E_BACKLASH_POSITION",
    ),
    ({**LOCK, "contact_speed_threshold": 0.0}, "contact_speed_threshold", "GS_E_NOT_POSITIVE"),
    ({**LOCK, "contact_release_force": -1.0}, "contact_release_force", "GS_E_NEGATIVE"),
]

RACK_PINION_CASES = [
    ({"parameterization": "guess"}, "parameterization", "GS_E_OPTION"),
    ({"pinion_radius": 0.0}, "pinion_radius", "GS_E_NOT_POSITIVE"),
    ({"pinion_radius": NAN}, "pinion_radius", "GS_E_NOT_FINITE"),
    ({**TOOTH, "teeth_count": 0.0}, "teeth_count", "GS_E_NOT_POSITIVE"),
    ({**TOOTH, "spacing": -0.005}, "spacing", "GS_E_NOT_POSITIVE"),
    ({"rack_directionality": "up"}, "rack_directionality", "GS_E_OPTION"),
    ({"friction_model": "load_dependent_efficiency"}, "friction_model", "GS_E_OPTION"),
    ({"loss_smoothing": "rough"}, "loss_smoothing", "GS_E_OPTION"),
    ({**CONST, "efficiency_const": 0.0}, "efficiency_const", "GS_E_EFFICIENCY_RANGE"),
    ({**CONST, "power_threshold": 0.0}, "power_threshold", "GS_E_NOT_POSITIVE"),
    (
        {**TEMP, "temperature_vector": [280.0, 280.0, 320.0]},
        "temperature_vector",
        "GS_E_TABLE_NOT_INCREASING",
    ),
    (
        {**TEMP, "efficiency_vector": [0.9, 0.9, 0.9, 0.9]},
        "efficiency_vector",
        "GS_E_TABLE_SIZE_MISMATCH",
    ),
    ({**TEMP, "efficiency_vector": [0.9, 1.5, 0.9]}, "efficiency_vector", "GS_E_EFFICIENCY_RANGE"),
    ({**TEMP, "thermal_mass": -50.0}, "thermal_mass", "GS_E_NOT_POSITIVE"),
    ({"pinion_viscous_coefficient": -1.0}, "pinion_viscous_coefficient", "GS_E_NEGATIVE"),
    ({"rack_viscous_coefficient": -1.0}, "rack_viscous_coefficient", "GS_E_NEGATIVE"),
    ({"initial_temperature": -1.0}, "initial_temperature", "GS_E_NOT_POSITIVE"),
    ({**BACKLASH, "linear_backlash": -1e-3}, "linear_backlash", "GS_E_NOT_POSITIVE"),
    ({**BACKLASH, "stiffness": 0.0}, "stiffness", "GS_E_NOT_POSITIVE"),
    (
        {**BACKLASH, "initial_backlash_position": -1e-3},
        "initial_backlash_position",
        "GS_E_BACKLASH_POSITION",
    ),
]

RIG_CASES = [
    ("simple_gear", {"follower_inertia": 0.0}, "follower_inertia", "GS_E_NOT_POSITIVE"),
    ("rack_pinion", {"rack_mass": -1.0}, "rack_mass", "GS_E_NOT_POSITIVE"),
    ("simple_gear", {"load_coulomb_friction": -1.0}, "load_coulomb_friction", "GS_E_NEGATIVE"),
    (
        "simple_gear",
        {"load_coulomb_speed_threshold": 0.0},
        "load_coulomb_speed_threshold",
        "GS_E_NOT_POSITIVE",
    ),
    ("rack_pinion", {"load_offset": INF}, "load_offset", "GS_E_NOT_FINITE"),
    ("simple_gear", {"thermal_resistance": 0.0}, "thermal_resistance", "GS_E_NOT_POSITIVE"),
    ("simple_gear", {"base_inertia": -1.0}, "base_inertia", "GS_E_NEGATIVE"),
    ("simple_gear", {"base_drive": "torque"}, "base_inertia", "GS_E_NOT_POSITIVE"),
    (
        "rack_pinion",
        {"base_drive": "torque", "base_inertia": 0.0},
        "base_inertia",
        "GS_E_NOT_POSITIVE",
    ),
    ("simple_gear", {"base_drive": "position"}, "base_drive", "GS_E_OPTION"),
    ("simple_gear", {"initial_base_speed": NAN}, "initial_base_speed", "GS_E_NOT_FINITE"),
    (
        "simple_gear",
        {"accel_filter_time_constant": -1e-3},
        "accel_filter_time_constant",
        "GS_E_NEGATIVE",
    ),
    ("simple_gear", {"contact_substeps": -1}, "contact_substeps", "GS_E_SUBSTEPS"),
    ("rack_pinion", {"contact_substeps": 65}, "contact_substeps", "GS_E_SUBSTEPS"),
    ("simple_gear", {"dt": 0.0}, "dt", "GS_E_STEP_SIZE"),
    ("rack_pinion", {"dt": NAN}, "dt", "GS_E_STEP_SIZE"),
    # positive but subnormal: its reciprocal overflows a double
    ("simple_gear", {"dt": 1e-310}, "dt", "GS_E_MAGNITUDE"),
    ("simple_gear", {"ambient_temperature": 0.0}, "ambient_temperature", None),
]


def _check(exc_info, parameter, status):
    err = exc_info.value
    assert isinstance(err, gearsim.GearsimError)
    assert isinstance(err, ValueError)
    assert err.parameter == parameter
    assert parameter in str(err)
    if status is not None:
        assert err.status == status


@pytest.mark.parametrize(("params", "parameter", "status"), SIMPLE_GEAR_CASES)
def test_simple_gear_rule(params, parameter, status):
    with pytest.raises(gearsim.ParameterError) as exc_info:
        gearsim.SimpleGear(**params)
    _check(exc_info, parameter, status)


@pytest.mark.parametrize(("params", "parameter", "status"), RACK_PINION_CASES)
def test_rack_pinion_rule(params, parameter, status):
    with pytest.raises(gearsim.ParameterError) as exc_info:
        gearsim.RackPinion(**params)
    _check(exc_info, parameter, status)


@pytest.mark.parametrize(("block", "params", "parameter", "status"), RIG_CASES)
def test_rig_rule(block, params, parameter, status):
    cls = gearsim.GearRig if block == "simple_gear" else gearsim.RackRig
    with pytest.raises(gearsim.ParameterError) as exc_info:
        cls(**params)
    _check(exc_info, parameter, status)
    # the same rule through a Model (rig parameters other than dt)
    if parameter != "dt":
        with pytest.raises(gearsim.ParameterError) as exc_info:
            gearsim.Model(block, {}, params)
        _check(exc_info, parameter, status)


@pytest.mark.parametrize(("params", "parameter", "status"), SIMPLE_GEAR_CASES[:12])
def test_model_reports_block_rules(params, parameter, status):
    with pytest.raises(gearsim.ParameterError) as exc_info:
        gearsim.Model("simple_gear", params)
    _check(exc_info, parameter, status)


def test_inactive_parameters_are_not_validated():
    # the C core checks only the parameters of the selected options
    gearsim.SimpleGear(friction_model="none", efficiency_const=5.0, power_threshold=-1.0)
    gearsim.SimpleGear(friction_model="constant_efficiency", efficiency_vector=[0.9, 0.8])
    gearsim.SimpleGear(backlash_enabled=False, linear_backlash=-1.0)
    gearsim.RackPinion(parameterization="pinion_radius", teeth_count=-3.0)
    gearsim.RackPinion(parameterization="tooth_parameters", pinion_radius=0.0)


def test_valid_options_are_accepted():
    for model in (
        "none",
        "constant_efficiency",
        "load_dependent_efficiency",
        "temperature_dependent_efficiency",
        "temperature_load_dependent_efficiency",
    ):
        assert gearsim.SimpleGear(friction_model=model).friction_model == model
    for model in ("none", "constant_efficiency", "temperature_dependent_efficiency"):
        assert gearsim.RackPinion(friction_model=model).friction_model == model
    for hs in ("smooth", "full_undamped", "full_damped"):
        gearsim.SimpleGear(backlash_enabled=True, hard_stop_model=hs)
        gearsim.RackPinion(backlash_enabled=True, hard_stop_model=hs)
    gearsim.SimpleGear(output_shaft_rotates="same", loss_smoothing="simscape")
    gearsim.RackPinion(rack_directionality="negative", parameterization="tooth_parameters")
    gearsim.GearRig(base_drive="torque", base_inertia=0.01)


@pytest.mark.parametrize(
    ("params", "parameter"),
    [
        ({"teeth_ratio": [1.0]}, "teeth_ratio"),
        ({"teeth_ratio": True}, "teeth_ratio"),
        ({"backlash_enabled": 1}, "backlash_enabled"),
        ({"friction_model": 3}, "friction_model"),
        ({"temperature_vector": 300.0}, "temperature_vector"),
        ({"efficiency_matrix": [0.9, 0.9]}, "efficiency_matrix"),
        ({"no_such_parameter": 1.0}, "no_such_parameter"),
        ({"rack_mass": 1.0}, "rack_mass"),  # a rack rig parameter, not a gear one
    ],
)
def test_wrong_type_or_unknown_key(params, parameter):
    with pytest.raises(gearsim.ModelFileError) as exc_info:
        gearsim.GearRig(**params)
    assert exc_info.value.parameter == parameter
    assert parameter in str(exc_info.value)


def test_contact_substeps_must_be_an_integer():
    with pytest.raises(gearsim.ModelFileError, match="contact_substeps"):
        gearsim.GearRig(contact_substeps=2.5)


def test_errors_are_picklable():
    import pickle

    try:
        gearsim.SimpleGear(teeth_ratio=-1.0)
    except gearsim.ParameterError as err:
        again = pickle.loads(pickle.dumps(err))
        assert type(again) is type(err)
        assert again.parameter == "teeth_ratio" and str(again) == str(err)
