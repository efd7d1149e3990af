#!/usr/bin/env bash
# The ways a user builds against gearsim, each with tests/package/main.c
# (prints gs_version(), steps a gear rig, checks the torque):
#   1. installed into a scratch prefix, found with find_package(gearsim);
#   2. the same install through pkg-config;
#   3. embedded with add_subdirectory() (tests/package/subproject), configured
#      with cmocka hidden: a parent project needs none of the test tools and
#      gets only the static library;
#   4. at top level with cmocka hidden, configuring fails and says how to fix
#      it (install libcmocka-dev, or BUILD_TESTING=OFF);
#   5. the Python package: an sdist, a wheel built from it (pip, as a user
#      builds one), checked by tests/package/wheel_check.py: the sdist holds
#      the C sources and hil/dbc, the wheel the DBC files as plain package
#      data identical to hil/dbc, and the unpacked wheel runs its bridge.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${PACKAGE_BUILD_DIR:-build/package}
jobs=$(nproc 2>/dev/null || echo 2)
rm -rf "$out"
mkdir -p "$out/no-pkgconfig"
cmake -S . -B "$out/lib" -DBUILD_TESTING=OFF -DGEARSIM_BUILD_EXAMPLES=OFF -DGEARSIM_BUILD_BENCH=OFF \
  -DCMAKE_INSTALL_PREFIX="$PWD/$out/prefix" >/dev/null
cmake --build "$out/lib" -j "$jobs" >/dev/null
cmake --install "$out/lib" >/dev/null
cmake -S tests/package -B "$out/consumer" -DCMAKE_PREFIX_PATH="$PWD/$out/prefix" >/dev/null
cmake --build "$out/consumer" >/dev/null
"$out/consumer/app"
echo "package_check: find_package(gearsim) consumer ok"

pc_path="$PWD/$out/prefix/lib/pkgconfig"
# shellcheck disable=SC2046
cc tests/package/main.c $(PKG_CONFIG_PATH="$pc_path" pkg-config --cflags --libs --static gearsim) \
  -o "$out/app-pkgconfig"
LD_LIBRARY_PATH="$PWD/$out/prefix/lib" "$out/app-pkgconfig"
echo "package_check: pkg-config consumer ok"

# cmocka hidden both ways it could be found: no .pc file visible to
# pkg-config, and the CMake package lookup disabled.
PKG_CONFIG_LIBDIR="$PWD/$out/no-pkgconfig" PKG_CONFIG_PATH="" \
  cmake -S tests/package/subproject -B "$out/subproject" -DCMAKE_DISABLE_FIND_PACKAGE_cmocka=ON \
  >"$out/subproject.log" 2>&1 || { cat "$out/subproject.log"; echo "package_check: subproject configure failed"; exit 1; }
cmake --build "$out/subproject" -j "$jobs" >/dev/null
"$out/subproject/app"
ctest --test-dir "$out/subproject" --output-on-failure >/dev/null
echo "package_check: add_subdirectory() consumer ok (configured without cmocka; static library only)"

if PKG_CONFIG_LIBDIR="$PWD/$out/no-pkgconfig" PKG_CONFIG_PATH="" \
   cmake -S . -B "$out/no-cmocka" -DCMAKE_DISABLE_FIND_PACKAGE_cmocka=ON >"$out/no-cmocka.log" 2>&1; then
  echo "package_check: top-level configure without cmocka succeeded with the tests on"; exit 1
elif ! grep -q "libcmocka-dev" "$out/no-cmocka.log" || ! grep -q "BUILD_TESTING=OFF" "$out/no-cmocka.log"; then
  cat "$out/no-cmocka.log"; echo "package_check: no clear message without cmocka"; exit 1
fi
echo "package_check: top-level configure without cmocka stops, saying to install libcmocka-dev or set BUILD_TESTING=OFF"
python=${PYTHON:-.venv/bin/python}
[ -x "$python" ] || python=python3
mkdir -p "$out/dist"
# python -m build: the sdist as a user builds one, in an isolated environment
# with the build requirements of pyproject.toml (not whatever .venv holds)
"$python" -m build --sdist -o "$out/dist" . >"$out/sdist.log" 2>&1 || { cat "$out/sdist.log"; echo "package_check: sdist failed"; exit 1; }
"$python" -m pip wheel -q --no-deps -w "$out/dist" "$out"/dist/gearsim-*.tar.gz >"$out/wheel.log" 2>&1 \
  || { cat "$out/wheel.log"; echo "package_check: building a wheel from the sdist failed"; exit 1; }
"$python" tests/package/wheel_check.py "$out/dist"
echo "package_check: find_package(gearsim), pkg-config and add_subdirectory() consumers, sdist and wheel ok"
