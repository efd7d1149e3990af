"""Build glue: the version from include/gearsim/version.h (its one source), the
C libraries gearsim_core from src/ and gearsim_hil from hil/src/ (build_clib,
with the library's warning set) and the cffi extension from
bindings/python/gearsim_build.py, linked against them; the packages, among
them gearsim.hil.dbc from hil/dbc. Everything else is in pyproject.toml."""

import re
import sys
from pathlib import Path

from setuptools import find_packages, setup
from setuptools.command.build_clib import build_clib
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT / "bindings" / "python"))
import gearsim_build  # noqa: E402


def _version() -> str:
    header = ROOT / "include" / "gearsim" / "version.h"
    match = re.search(r'#define\s+GS_VERSION_STRING\s+"([^"]+)"', header.read_text())
    if not match:
        raise RuntimeError(f"GS_VERSION_STRING not found in {header}")
    return match.group(1)


class build_clib_flags(build_clib):
    """build_clib that also recompiles when the compiler or the flags changed
    (e.g. GEARSIM_WERROR, CC) or with --force: setuptools' own compares the
    file times of the sources and obj_deps only."""

    def build_libraries(self, libraries):
        for name, info in libraries:
            stamp = Path(self.build_temp) / f"{name}.flags"
            compiler = getattr(self.compiler, "compiler_so", None) or [type(self.compiler).__name__]
            flags = "\n".join([*compiler, *(info.get("cflags") or [])])
            if self.force or not stamp.is_file() or stamp.read_text() != flags:
                objects = self.compiler.object_filenames(
                    info["sources"], output_dir=self.build_temp
                )
                for obj in objects:
                    Path(obj).unlink(missing_ok=True)
                stamp.parent.mkdir(parents=True, exist_ok=True)
                stamp.write_text(flags)
        super().build_libraries(libraries)


class build_ext_with_core(build_ext):
    """build_ext that builds gearsim_core first (a plain `build` does so too,
    but `build_ext --inplace` and editable installs may run build_ext alone)."""

    def run(self):
        self.run_command("build_clib")
        super().run()


# The package lives in bindings/python; its DBC files live in hil/dbc with
# the C library and are installed from there as the package gearsim.hil.dbc
# (no copy, no link: a wheel and an sdist carry the files, an editable
# install reads them in place).
PACKAGE_DIR = {"": "bindings/python", "gearsim.hil.dbc": "hil/dbc"}
PACKAGES = find_packages("bindings/python", include=["gearsim*"]) + ["gearsim.hil.dbc"]

setup(
    version=_version(),
    packages=PACKAGES,
    package_dir=PACKAGE_DIR,
    libraries=gearsim_build.c_libraries(),
    cmdclass={"build_clib": build_clib_flags, "build_ext": build_ext_with_core},
    cffi_modules=["bindings/python/gearsim_build.py:make_builder"],
)
