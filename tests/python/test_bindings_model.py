"""Model files (docs/measurement-format.md section 2): read, write, round trip,
unit strings, and errors that name the key and the file."""

import math
import tomllib

import pytest

import gearsim

CONTRACT_EXAMPLE = """
[rig]
block = "simple_gear"          # or "rack_pinion"
follower_inertia = 0.05        # kg*m^2
load_coulomb_friction = 0.0    # N*m
load_offset = 0.0              # N*m
thermal_resistance = 2.0       # K/W
ambient_temperature = 293.15   # K

[block]
teeth_ratio = 3.0
output_shaft_rotates = "opposite"
friction_model = "constant_efficiency"
efficiency_const = 0.95
"""


def _write(tmp_path, text, name="model.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_contract_example_loads(tmp_path):
    path = _write(tmp_path, CONTRACT_EXAMPLE)
    model = gearsim.Model.load(path)
    assert model.block == "simple_gear"
    assert model.block_params == {
        "teeth_ratio": 3.0,
        "output_shaft_rotates": "opposite",
        "friction_model": "constant_efficiency",
        "efficiency_const": 0.95,
    }
    assert model.rig_params["thermal_resistance"] == 2.0
    assert model.resolved_block_params["power_threshold"] == pytest.approx(1e-3)  # default
    assert model.file == path
    rig = model.rig(dt=1e-3)
    assert isinstance(rig, gearsim.GearRig)
    out = rig.run(base_speed=[1.0, 2.0, 3.0], load=0.1)
    assert len(out) == 3


def test_round_trip_equal_model(tmp_path):
    model = gearsim.Model.loads(CONTRACT_EXAMPLE)
    path = tmp_path / "out.toml"
    model.save(path)
    again = gearsim.Model.load(path)
    assert again == model
    assert again.block_params == model.block_params
    assert again.rig_params == model.rig_params


def test_fitted_model_round_trip(tmp_path):
    model = gearsim.Model(
        "simple_gear",
        {
            "friction_model": "temperature_load_dependent_efficiency",
            "temperature_vector": [280.0, 300.0, 320.0, 340.0],
            "load_vector": [0.0, 10.0],
            "efficiency_matrix": [[0.9, 0.95], [0.88, 0.93], [0.86, 0.91], [0.84, 0.9]],
            "backlash_enabled": True,
            "hard_stop_model": "full_damped",
            "viscous_coefficients": [1e-4, 2.5e-5],
            "contact_no_pull": False,
        },
        {"follower_inertia": 0.0123456789, "contact_substeps": 8, "base_drive": "speed"},
    )
    fitted = model.replace(
        block_params={"viscous_coefficients": [0.1 / 3.0, 2.0 / 7.0]},
        rig_params={"load_offset": -math.pi / 10, "thermal_resistance": 1.7},
    )
    path = tmp_path / "fitted.toml"
    fitted.save(path)
    again = gearsim.Model.load(path)
    assert again == fitted
    assert again != model
    assert again.block_params["viscous_coefficients"] == [0.1 / 3.0, 2.0 / 7.0]  # bit-exact
    # the written file is plain SI TOML
    data = tomllib.loads(path.read_text())
    assert data["rig"]["block"] == "simple_gear"
    assert data["rig"]["contact_substeps"] == 8
    assert data["block"]["backlash_enabled"] is True
    # removing a parameter (None) returns it to its default
    back = fitted.replace(rig_params={"thermal_resistance": None})
    assert "thermal_resistance" not in back.rig_params


def test_rack_model_round_trip(tmp_path):
    model = gearsim.Model(
        "rack_pinion",
        {
            "parameterization": "tooth_parameters",
            "teeth_count": 18,
            "spacing": "3.14159 mm",
            "friction_model": "temperature_dependent_efficiency",
        },
        {"rack_mass": "2.5 kg", "load_coulomb_friction": "1.5 N"},
    )
    assert model.block_params["spacing"] == pytest.approx(3.14159e-3)
    assert model.rig_params["rack_mass"] == 2.5
    path = tmp_path / "rack.toml"
    model.save(path)
    assert gearsim.Model.load(path) == model


def test_equality_uses_defaults():
    assert gearsim.Model("simple_gear", {}) == gearsim.Model("simple_gear", {"teeth_ratio": 2})
    assert gearsim.Model("simple_gear") != gearsim.Model("rack_pinion")


def test_unit_strings_in_file(tmp_path):
    path = _write(
        tmp_path,
        """
[rig]
block = "rack_pinion"
rack_mass = "500 g"
ambient_temperature = "20 degC"
load_coulomb_friction = "2 lbf"
thermal_resistance = "2 K/W"

[block]
pinion_radius = "100 mm"
power_threshold = "1 mW"
friction_model = "temperature_dependent_efficiency"
temperature_vector = "[7, 27, 47] degC"
initial_temperature = "80 degC"
pinion_viscous_coefficient = "1 mN*m/(rad/s)"
""",
    )
    model = gearsim.Model.load(path)
    b, r = model.block_params, model.rig_params
    assert b["pinion_radius"] == pytest.approx(0.1)
    assert b["power_threshold"] == pytest.approx(1e-3)
    assert b["temperature_vector"] == pytest.approx([280.15, 300.15, 320.15])
    assert b["initial_temperature"] == pytest.approx(353.15)
    assert b["pinion_viscous_coefficient"] == pytest.approx(1e-3)
    assert r["rack_mass"] == pytest.approx(0.5)
    assert r["ambient_temperature"] == pytest.approx(293.15)
    assert r["load_coulomb_friction"] == pytest.approx(8.896443230521)
    # written back as plain SI numbers, loads back equal
    text = model.dumps()
    assert "mm" not in text and "degC" not in text
    assert gearsim.Model.loads(text) == model


def _raises_naming(tmp_path, text, exc, key):
    path = _write(tmp_path, text)
    with pytest.raises(exc) as e:
        gearsim.Model.load(path)
    err = e.value
    assert isinstance(err, gearsim.ModelFileError)  # every problem of a file
    assert isinstance(err, gearsim.GearsimError) and isinstance(err, ValueError)
    assert err.file == str(path)
    assert str(path) in str(err)
    if key is not None:
        assert err.parameter == key
        assert key in str(err)
    return err


def test_unknown_block_key(tmp_path):
    _raises_naming(
        tmp_path,
        '[rig]\nblock = "simple_gear"\n[block]\nteeth_ration = 3.0\n',
        gearsim.ModelFileError,
        "teeth_ration",
    )


def test_unknown_rig_key(tmp_path):
    _raises_naming(
        tmp_path,
        '[rig]\nblock = "simple_gear"\nrack_mass = 1.0\n',
        gearsim.ModelFileError,
        "rack_mass",
    )


def test_unknown_table(tmp_path):
    _raises_naming(
        tmp_path,
        '[rig]\nblock = "simple_gear"\n[gear]\nteeth_ratio = 3.0\n',
        gearsim.ModelFileError,
        "gear",
    )


def test_unknown_block_name(tmp_path):
    _raises_naming(tmp_path, '[rig]\nblock = "worm_gear"\n', gearsim.ModelFileError, "block")


def test_missing_block(tmp_path):
    _raises_naming(tmp_path, "[rig]\nfollower_inertia = 1.0\n", gearsim.ModelFileError, "block")


def test_wrong_type(tmp_path):
    _raises_naming(
        tmp_path,
        '[rig]\nblock = "simple_gear"\n[block]\nbacklash_enabled = "yes"\n',
        gearsim.ModelFileError,
        "backlash_enabled",
    )
    _raises_naming(
        tmp_path,
        '[rig]\nblock = "simple_gear"\n[block]\nteeth_ratio = [3.0]\n',
        gearsim.ModelFileError,
        "teeth_ratio",
    )


def test_invalid_value(tmp_path):
    err = _raises_naming(
        tmp_path,
        '[rig]\nblock = "simple_gear"\n[block]\nteeth_ratio = -3.0\n',
        gearsim.ParameterError,
        "teeth_ratio",
    )
    assert err.status == "GS_E_NOT_POSITIVE"
    err = _raises_naming(
        tmp_path,
        '[rig]\nblock = "rack_pinion"\nrack_mass = 0.0\n',
        gearsim.ParameterError,
        "rack_mass",
    )
    _raises_naming(
        tmp_path,
        '[rig]\nblock = "simple_gear"\n[block]\nfriction_model = "magic"\n',
        gearsim.ParameterError,
        "friction_model",
    )


def test_bad_unit(tmp_path):
    _raises_naming(
        tmp_path,
        '[rig]\nblock = "rack_pinion"\n[block]\npinion_radius = "3 kg"\n',
        gearsim.ParameterError,
        "pinion_radius",
    )


def test_toml_syntax_and_missing_file(tmp_path):
    _raises_naming(tmp_path, '[rig\nblock = "simple_gear"\n', gearsim.ModelFileError, None)
    with pytest.raises(gearsim.ModelFileError) as e:
        gearsim.Model.load(tmp_path / "absent.toml")
    assert "absent.toml" in str(e.value)


def test_model_from_python_without_file():
    with pytest.raises(gearsim.ParameterError) as e:
        gearsim.Model("simple_gear", {"teeth_ratio": 0.0})
    assert e.value.file is None and e.value.parameter == "teeth_ratio"
    assert not isinstance(e.value, gearsim.ModelFileError)


def test_numpy_values_are_accepted_and_written_as_plain_toml():
    np = pytest.importorskip("numpy")
    model = gearsim.Model(
        "simple_gear",
        {
            "teeth_ratio": np.float32(2.5),
            "viscous_coefficients": np.array([1e-3, 2e-3]),
            "friction_model": "temperature_load_dependent_efficiency",
            "efficiency_matrix": np.full((3, 3), 0.9),
            "backlash_enabled": np.bool_(True),
        },
        {"contact_substeps": np.int64(4), "follower_inertia": np.float64(0.1)},
    )
    assert type(model.block_params["teeth_ratio"]) is float
    assert type(model.block_params["backlash_enabled"]) is bool
    assert type(model.rig_params["contact_substeps"]) is int
    assert gearsim.Model.loads(model.dumps()) == model


def test_model_pickles():
    import pickle

    model = gearsim.Model.loads(CONTRACT_EXAMPLE)
    again = pickle.loads(pickle.dumps(model))
    assert again == model
    assert again.rig().run(base_speed=[1.0, 2.0]).base_torque.shape == (2,)


def test_analysis_table_is_kept_through_load_replace_and_save(tmp_path):
    # A model written by `gearsim fit --add sensor_delay --out` has an
    # [analysis] table; every tool that loads models (HIL bridge, examples)
    # must read it and write it back unchanged.
    path = tmp_path / "fitted.toml"
    path.write_text(
        '[rig]\nblock = "simple_gear"\n[block]\nteeth_ratio = 2.0\n'
        '[analysis]\ntorque_delay = "6 ms"\n',
        encoding="utf-8",
    )
    model = gearsim.Model.load(path)
    assert model.analysis == {"torque_delay": "6 ms"}
    changed = model.replace(block_params={"teeth_ratio": 3.0})
    assert changed.analysis == {"torque_delay": "6 ms"}
    again = gearsim.Model.loads(changed.dumps())
    assert again.analysis == {"torque_delay": "6 ms"}
    assert again.block_params["teeth_ratio"] == 3.0


def test_analysis_must_be_a_table():
    with pytest.raises(gearsim.ModelFileError, match="analysis"):
        gearsim.Model.loads('analysis = 3\n[rig]\nblock = "simple_gear"\n')
