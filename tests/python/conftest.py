"""Markers shared by every Python test.

``slow``: the modules below take most of the stage's time (each above ~5 s
per test, or a long randomized search). ``scripts/test.sh`` runs them;
``PYTEST_ARGS='-m "not slow"' scripts/test.sh python`` (or ``pytest -m "not
slow"``) leaves them out for a quick round while editing. Listed here, in one
place, by module path relative to tests/python.
"""

from __future__ import annotations

import pathlib

import pytest

SLOW_MODULES = (
    "test_cli_fuzz.py",  # 4,000 hypothesis examples through the CLI (about 3-6 min)
    "test_reference_rig.py",  # the C rig against an independent solve_ivp reference
    "test_bench_alternatives.py",  # the benchmark's alternative implementations
    "analysis/test_acceptance.py",  # every hidden effect fitted on the independent generator
    "analysis/test_acceptance_rig_effects.py",
    "analysis/test_emps.py",  # the real EMPS records (skipped when absent)
    "analysis/test_walkthrough.py",  # the whole walkthrough
)

_HERE = pathlib.Path(__file__).parent


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    slow = {(_HERE / m).resolve() for m in SLOW_MODULES}
    stale = [m for m in SLOW_MODULES if not (_HERE / m).is_file()]
    if stale:  # a renamed module would silently lose its marker
        raise pytest.UsageError(f"tests/python/conftest.py SLOW_MODULES: no such file {stale}")
    for item in items:
        if pathlib.Path(str(item.fspath)).resolve() in slow:
            item.add_marker(pytest.mark.slow)
