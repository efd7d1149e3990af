"""The optional parts of gearsim and the pip extras that bring them.

The core (``import gearsim``: blocks, rigs, model files, units) needs only
numpy, cffi, pint and tomli-w. The analysis, the HIL bridge and the FMU tooling
need more, installed as extras (pyproject.toml ``[project.optional-dependencies]``,
docs/python.md "Installing"). Their modules are imported only where they are
used, so a missing one shows up late and as a bare ``ModuleNotFoundError``;
this table turns it into the extra to install. tests/python/test_extras.py
checks the table against pyproject.toml.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Iterable

__all__ = ["EXTRAS", "MissingExtraError", "extra_of", "find_missing", "require", "missing_extra"]

#: extra -> the top-level modules its distributions install (python-can is ``can``).
EXTRAS: dict[str, tuple[str, ...]] = {
    "analysis": ("scipy", "pandas", "zstandard", "matplotlib", "threadpoolctl"),
    "hil": ("can", "cantools"),
    "fmu": ("fmpy",),
    "fleet": ("dask", "distributed", "pyarrow", "tqdm"),
}


class MissingExtraError(ModuleNotFoundError):
    """A module of an extra is not installed. ``feature`` is what needed it (a
    command, a subpackage), ``extra`` the extra to install, ``module`` the
    module that is missing. Still a ModuleNotFoundError, so code that catches
    that keeps working."""

    def __init__(self, feature: str, extra: str, module: str) -> None:
        self.feature = feature
        self.extra = extra
        self.module = module
        super().__init__(
            f"{feature} needs the {extra} extra: pip install 'gearsim[{extra}]' "
            f"(missing module: {module})",
            name=module,
        )


def extra_of(module: str) -> str | None:
    """The extra that installs ``module`` (any dotted name below it), or None."""
    top = module.partition(".")[0]
    for extra, modules in EXTRAS.items():
        if top in modules:
            return extra
    return None


def find_missing(modules: Iterable[str]) -> str | None:
    """The first of ``modules`` (top-level names) that cannot be imported, or
    None. Looks for them without importing them: the check is cheap, and a
    command that fails on a missing extra fails before it has done any work."""
    for module in modules:
        try:
            if importlib.util.find_spec(module) is None:
                return module
        except ImportError:
            return module
        except ValueError:
            continue  # already imported (a module without a spec): it is there
    return None


def require(feature: str, modules: Iterable[str]) -> None:
    """Raise MissingExtraError when one of ``modules`` (names from EXTRAS) is
    not installed."""
    missing = find_missing(modules)
    if missing is not None:
        raise MissingExtraError(feature, extra_of(missing) or "all", missing)


def missing_extra(exc: BaseException, feature: str) -> MissingExtraError | None:
    """``exc`` as a MissingExtraError of ``feature`` when it is the import of
    a module an extra brings that failed because the module is not installed;
    None for any other error (a bug, a broken installation: not a missing extra)."""
    if not isinstance(exc, ModuleNotFoundError):
        return None
    if isinstance(exc, MissingExtraError):
        return MissingExtraError(feature, exc.extra, exc.module)
    top = (exc.name or "").partition(".")[0]
    extra = extra_of(top)
    if extra is None or find_missing([top]) is None:
        return None  # installed, so a submodule is missing: a broken installation
    return MissingExtraError(feature, extra, top)
