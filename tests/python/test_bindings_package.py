"""Installation: version, console script, compiled core."""

import importlib.metadata
import importlib.util

import pytest

import gearsim


def _distribution():
    try:
        return importlib.metadata.distribution("gearsim")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("gearsim is not installed (run `pip install -e .`)")


def test_version_matches_the_c_core():
    assert gearsim.__version__ == _distribution().version == gearsim.C_VERSION


def test_console_script_is_declared():
    scripts = [ep for ep in _distribution().entry_points if ep.group == "console_scripts"]
    assert any(ep.name == "gearsim" and ep.value == "gearsim.cli:main" for ep in scripts)


def test_console_script_target_when_present():
    if importlib.util.find_spec("gearsim.cli") is None:
        pytest.skip("gearsim/cli.py is not written yet")
    from gearsim import cli

    assert callable(cli.main)


def test_the_extension_is_the_compiled_c_core():
    from gearsim._lib import ffi, lib

    assert ffi.sizeof("gs_real") == 8  # the double build
    assert ffi.sizeof("gs_rig_input") == 5 * 8
    assert ffi.sizeof("gs_rig_output") == 15 * 8
    assert ffi.string(lib.gs_status_str(lib.GS_E_NOT_POSITIVE)).decode()
