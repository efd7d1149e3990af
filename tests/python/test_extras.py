"""The core package needs numpy, cffi, pint and tomli-w only; the analysis, HIL
and FMU dependencies are extras, and the command line names a missing one.

A second virtual environment is not needed to prove it: each test runs this
venv's Python in a subprocess whose import system acts as if the extras were
not installed (a ``sys.meta_path`` finder that refuses their modules), and
checks that none of them was even looked for where the core is concerned.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

from gearsim import _extras, cli
from gearsim._extras import EXTRAS, MissingExtraError, find_missing, missing_extra, require

ROOT = Path(__file__).resolve().parents[2]
DEMO_CSV = ROOT / "examples" / "data" / "demo_gear.csv"
DEMO_MODEL = ROOT / "examples" / "data" / "demo_gear_start.toml"

#: Every module an extra brings (python-can is ``can``).
OPTIONAL_MODULES = tuple(m for modules in EXTRAS.values() for m in modules)

# Run before anything else in the child: the blocked modules behave as if they
# were not installed, and every attempt to import one is recorded with the file
# that asked. GEARSIM_ATTEMPTS() are those made by gearsim's own code: other
# libraries may probe too (pint tries scipy, and does without it).
_BLOCKER = """
import os
import sys

_BLOCKED = set({blocked!r})
ATTEMPTS = []


def _importer():
    frame = sys._getframe(2)
    while frame is not None and frame.f_code.co_filename.startswith("<frozen"):
        frame = frame.f_back
    return frame.f_code.co_filename if frame is not None else "?"


class _NotInstalled:
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in _BLOCKED:
            ATTEMPTS.append((name, _importer()))
            raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
        return None


def GEARSIM_ATTEMPTS():
    import gearsim

    home = os.path.dirname(os.path.abspath(gearsim.__file__)) + os.sep
    return [name for name, where in ATTEMPTS if os.path.abspath(where).startswith(home)]


sys.meta_path.insert(0, _NotInstalled())

# a probe with importlib.util.find_spec (pint looks for dask that way) gets
# what it gets for a module that is not installed: None
import importlib.util as _util

_real_find_spec = _util.find_spec


def _find_spec(name, package=None):
    if name.partition(".")[0] in _BLOCKED:
        frame = sys._getframe(1)
        ATTEMPTS.append((name, frame.f_code.co_filename))
        return None
    return _real_find_spec(name, package)


_util.find_spec = _find_spec
"""


def _run_blocked(
    code: str, blocked: tuple[str, ...] = OPTIONAL_MODULES, cwd: Path = ROOT
) -> subprocess.CompletedProcess[str]:
    script = _BLOCKER.format(blocked=sorted(blocked)) + textwrap.dedent(code)
    return subprocess.run(
        [sys.executable, "-c", script],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=600,
    )


def _cli_blocked(
    argv: list[str], blocked: tuple[str, ...] = OPTIONAL_MODULES, module: str = "gearsim.cli"
) -> subprocess.CompletedProcess[str]:
    return _run_blocked(
        f"""
        from {module} import main
        sys.exit(main({argv!r}))
        """,
        blocked,
    )


# ------------------------------------------------------------------ the core


def test_core_runs_without_any_extra(tmp_path):
    out = _run_blocked(
        f"""
        import json
        import numpy as np
        import gearsim

        w = np.full(200, 10.0)
        res = gearsim.GearRig(dt=1e-3, teeth_ratio=2.0).run(base_speed=w, load=np.zeros(200))
        rack = gearsim.RackRig(dt=1e-3).run(base_speed=w, load=np.zeros(200))

        # a model file with units (pint), saved again (tomli-w)
        model = gearsim.Model.loads('''
        [rig]
        block = "rack_pinion"
        rack_mass = "2000 g"
        ambient_temperature = "25 degC"

        [block]
        pinion_radius = "20 mm"
        ''')
        model.save({str(tmp_path / "saved.toml")!r})
        again = gearsim.Model.load({str(tmp_path / "saved.toml")!r})
        loaded = gearsim.Model.load({str(DEMO_MODEL)!r}).rig(dt=1e-3).run(base_speed=w, load=0 * w)
        units = gearsim.param_units("simple_gear")

        # modules of the core that use no extra
        import gearsim.columns, gearsim.model, gearsim.params, gearsim.units, gearsim.errors

        print(json.dumps({{
            "follower": float(res.follower_speed[-1]),
            "rack": float(rack.follower_speed[-1]),
            "loaded": float(loaded.base_torque[-1]),
            "mass": again.resolved_rig_params["rack_mass"],
            "ambient": again.resolved_rig_params["ambient_temperature"],
            "unit": units["follower_inertia"],
            "attempts": GEARSIM_ATTEMPTS(),
            "imported": sorted(m for m in sys.modules if m.partition(".")[0] in _BLOCKED),
        }}))
        """
    )
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout)
    assert got["attempts"] == [], "the core imported a module of an extra"
    assert got["imported"] == []
    assert got["follower"] == pytest.approx(-5.0)  # teeth_ratio 2, opposite rotation
    assert got["mass"] == pytest.approx(2.0)
    assert got["ambient"] == pytest.approx(298.15)
    assert got["unit"] == "kg*m**2"


def test_subpackages_and_help_import_without_extras():
    """The analysis and HIL packages import their extras only where used: the
    ``gearsim`` command (which registers both) and their packages load, and
    ``gearsim --help`` works."""
    out = _run_blocked(
        """
        import contextlib, io
        import gearsim.analysis, gearsim.analysis.cli, gearsim.hil, gearsim.hil.cli
        from gearsim.cli import main

        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            status = main(["--help"])
        print(status, "hil" in buf.getvalue(), "diagnose" in buf.getvalue())
        print(sorted(m for m in sys.modules if m.partition(".")[0] in _BLOCKED))
        print(GEARSIM_ATTEMPTS())
        """
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines() == ["0 True True", "[]", "[]"]


def test_hil_package_names_its_extra():
    out = _run_blocked(
        """
        try:
            from gearsim.hil import Bridge
        except ModuleNotFoundError as exc:
            print(type(exc).__name__, exc.name, exc)
        """
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == (
        "MissingExtraError can gearsim.hil needs the hil extra: "
        "pip install 'gearsim[hil]' (missing module: can)"
    )


# ------------------------------------------------------------------ the CLI


def _expect_one_line(out: subprocess.CompletedProcess[str], command: str, extra: str, module: str):
    assert out.returncode == 2, out.stderr
    assert out.stdout == ""
    assert out.stderr.splitlines() == [
        f"gearsim: '{command}' needs the {extra} extra: pip install 'gearsim[{extra}]' "
        f"(missing module: {module})"
    ]


@pytest.mark.parametrize(
    "argv, command, module, blocked",
    [
        (
            ["diagnose", str(DEMO_CSV), "--model", str(DEMO_MODEL)],
            "gearsim diagnose",
            "scipy",
            None,
        ),
        (
            ["fit", str(DEMO_CSV), "--model", str(DEMO_MODEL), "--add", "viscous_friction"],
            "gearsim fit",
            "scipy",
            None,
        ),
        (["report", str(DEMO_CSV), "--model", str(DEMO_MODEL)], "gearsim report", "scipy", None),
        # scipy there, matplotlib not: the plots are what is missing
        (
            ["report", str(DEMO_CSV), "--model", str(DEMO_MODEL)],
            "gearsim report",
            "matplotlib",
            ("matplotlib",),
        ),
    ],
)
def test_analysis_command_names_the_extra(tmp_path, argv, command, module, blocked):
    out_arg = ["--out", str(tmp_path / ("out" if argv[0] == "report" else "fitted.toml"))]
    argv = argv + (out_arg if argv[0] in ("fit", "report") else [])
    out = _cli_blocked(argv, blocked or OPTIONAL_MODULES)
    _expect_one_line(out, command, "analysis", module)
    assert list(tmp_path.iterdir()) == []  # refused before any work


def test_compare_needs_no_extra():
    """compare simulates and scores with numpy alone (CSV through the csv
    module when pandas is missing)."""
    out = _cli_blocked(["compare", str(DEMO_CSV), "--model", str(DEMO_MODEL), "--json"])
    assert out.returncode == 0, out.stderr
    assert "nrmse" in json.loads(out.stdout)


@pytest.mark.parametrize(
    "argv, command",
    [
        (["hil", "to-csv", "LOG", "--rig", "gear", "-o", "OUT"], "gearsim hil to-csv"),
        (["hil", "replay", "LOG", "--model", str(DEMO_MODEL), "-o", "OUT"], "gearsim hil replay"),
        (["hil", "dbc", "gear"], "gearsim hil dbc"),
    ],
)
@pytest.mark.parametrize("module", ["gearsim.cli", "gearsim.hil.cli"])
def test_hil_command_names_the_extra(tmp_path, argv, command, module):
    log = tmp_path / "bench.asc"
    log.write_text("date Mon Jan 1 00:00:00 2024\n")
    out_path = tmp_path / "out.csv"
    argv = [str(log) if a == "LOG" else str(out_path) if a == "OUT" else a for a in argv]
    if module == "gearsim.hil.cli":  # python -m gearsim.hil: the same command, standalone
        argv = argv[1:]
    _expect_one_line(_cli_blocked(argv, module=module), command, "hil", "can")
    assert not out_path.exists()


def test_cantools_alone_missing_is_named():
    out = _cli_blocked(["hil", "dbc", "rack"], blocked=("cantools",))
    _expect_one_line(out, "gearsim hil dbc", "hil", "cantools")


def test_a_late_import_of_an_extra_is_named(monkeypatch, capsys):
    """A module of an extra that a command imports while it runs, beyond what
    it declared, still ends in the one line and status 2, not an internal error."""
    from gearsim.analysis.cli import compare as command

    monkeypatch.setitem(EXTRAS, "analysis", (*EXTRAS["analysis"], "gearsim_no_such_module"))

    def compare(args):
        import gearsim_no_such_module  # noqa: F401

        return 0

    monkeypatch.setattr(command, "execute", compare)
    status = cli.main(["compare", str(DEMO_CSV), "--model", str(DEMO_MODEL)])
    err = capsys.readouterr().err
    assert status == cli.EXIT_BAD_INPUT
    assert err.splitlines() == [
        "gearsim: 'gearsim compare' needs the analysis extra: pip install "
        "'gearsim[analysis]' (missing module: gearsim_no_such_module)"
    ]


def test_a_missing_module_of_no_extra_stays_an_internal_error(monkeypatch, capsys):
    from gearsim.analysis.cli import compare as command

    def compare(args):
        import gearsim_no_such_module  # noqa: F401

        return 0

    monkeypatch.setattr(command, "execute", compare)
    status = cli.main(["compare", str(DEMO_CSV), "--model", str(DEMO_MODEL)])
    assert status == cli.EXIT_INTERNAL
    assert "internal error: ModuleNotFoundError" in capsys.readouterr().err


# ------------------------------------------------------------------ the table


def test_helpers():
    assert _extras.extra_of("scipy.optimize") == "analysis"
    assert _extras.extra_of("can.io") == "hil"
    assert _extras.extra_of("numpy") is None
    assert find_missing(["numpy", "gearsim_no_such_module"]) == "gearsim_no_such_module"
    assert find_missing(["numpy", "json"]) is None
    with pytest.raises(MissingExtraError) as info:
        require("'x'", ["gearsim_no_such_module"])
    assert isinstance(info.value, ModuleNotFoundError)
    # installed, but a submodule is missing: a broken installation, not an extra
    assert missing_extra(ModuleNotFoundError("x", name="numpy.nothing_here"), "'x'") is None
    assert missing_extra(ValueError("x"), "'x'") is None


def _distribution(requirement: str) -> str:
    name = requirement
    for stop in "<>=!~;[ ":
        name = name.split(stop)[0]
    return name.strip().lower()


#: Distribution name -> the top-level module it installs, where they differ.
_MODULE_OF = {"python-can": "can"}
#: A requirement with an extra -> the top-level modules it installs.
_REQUIREMENT_MODULES = {"dask[distributed]": ("dask", "distributed")}


def test_table_matches_pyproject():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    core = {_distribution(r) for r in project["dependencies"]}
    assert core == {"numpy", "cffi", "pint", "tomli-w"}
    extras = project["optional-dependencies"]
    for extra, modules in EXTRAS.items():
        # an extra may name another of gearsim's own ("gearsim[analysis]"), and a
        # requirement with an extra brings that extra's modules too
        reqs = [r for r in extras[extra] if not r.startswith("gearsim[")]
        got = tuple(
            m
            for r in reqs
            for m in _REQUIREMENT_MODULES.get(
                r.split(">")[0], (_MODULE_OF.get(_distribution(r), _distribution(r)),)
            )
        )
        assert got == modules, extra
    assert "gearsim[analysis]" in extras["fleet"]
    # all: every extra but the test tooling, with the same pins
    union = {
        r
        for name, reqs in extras.items()
        if name not in ("all", "test")
        for r in reqs
        if not r.startswith("gearsim[")
    }
    assert set(extras["all"]) == union
    # the test tooling: pytest, hypothesis, build for the sdist of scripts/package_check.sh,
    # xmlschema for the JUnit verdicts of the HIL scenarios (tests/python/hil/junit.xsd),
    # ruff and mypy for the style checks of scripts/lint.sh
    test_tools = {"pytest", "hypothesis", "build", "xmlschema", "ruff", "mypy"}
    assert {_distribution(r) for r in extras["test"]} == test_tools
    # docs/python.md's table of extras names every tool of the test extra
    doc = (ROOT / "docs" / "python.md").read_text()
    rows = [line for line in doc.splitlines() if line.startswith("| `test` |")]
    assert len(rows) == 1
    assert {t.strip() for t in rows[0].split("|")[2].split(",")} == test_tools
    assert set(extras["bench"]) <= set(extras["analysis"])


def test_hil_exports_resolve():
    """With the extra installed, every name gearsim.hil exports loads, and
    ``replay`` stays the function even when its submodule loaded first."""
    out = subprocess.run(
        [
            sys.executable,
            "-c",
            "import gearsim.hil.replay, gearsim.hil as h\n"
            "from gearsim.hil import replay\n"
            "print(callable(replay) and replay.__module__ == 'gearsim.hil.replay', "
            "all(getattr(h, n) is not None for n in h.__all__))",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "True True"


@pytest.mark.parametrize(
    "blocked, extra, module",
    [
        (("dask",), "fleet", "dask"),
        (("pyarrow",), "fleet", "pyarrow"),
        (OPTIONAL_MODULES, "analysis", "scipy"),
    ],
)
def test_fleet_command_names_the_extra(tmp_path, blocked, extra, module):
    argv = [
        "fleet",
        str(DEMO_CSV.parent),
        "--model",
        str(DEMO_MODEL),
        "--out",
        str(tmp_path / "out"),
        "--add",
        "coulomb_friction",
    ]
    _expect_one_line(_cli_blocked(argv, blocked), "gearsim fleet", extra, module)
    assert list(tmp_path.iterdir()) == []
