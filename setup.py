"""Build glue: version from include/gearsim/types.h, cffi extension from
bindings/python/gearsim_build.py. Everything else is in pyproject.toml."""

import re
from pathlib import Path

from setuptools import setup


def _version() -> str:
    header = Path(__file__).resolve().parent / "include" / "gearsim" / "types.h"
    match = re.search(r'#define\s+GS_VERSION_STRING\s+"([^"]+)"', header.read_text())
    if not match:
        raise RuntimeError(f"GS_VERSION_STRING not found in {header}")
    return match.group(1)


setup(
    version=_version(),
    cffi_modules=["bindings/python/gearsim_build.py:ffibuilder"],
)
