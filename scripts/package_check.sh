#!/usr/bin/env bash
# Installs the library into a scratch prefix and builds a consumer twice:
# with find_package(gearsim) (CMake package) and with pkg-config.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${PACKAGE_BUILD_DIR:-build/package}
rm -rf "$out"
cmake -S . -B "$out/lib" -DBUILD_TESTING=OFF -DGEARSIM_BUILD_EXAMPLES=OFF -DCMAKE_INSTALL_PREFIX="$PWD/$out/prefix" >/dev/null
cmake --build "$out/lib" -j "$(nproc 2>/dev/null || echo 2)" >/dev/null
cmake --install "$out/lib" >/dev/null
cmake -S tests/package -B "$out/consumer" -DCMAKE_PREFIX_PATH="$PWD/$out/prefix" >/dev/null
cmake --build "$out/consumer" >/dev/null
"$out/consumer/app"
export PKG_CONFIG_PATH="$PWD/$out/prefix/lib/pkgconfig"
# shellcheck disable=SC2046
cc tests/package/main.c $(pkg-config --cflags gearsim) $(pkg-config --libs --static gearsim) -o "$out/app-pkgconfig"
LD_LIBRARY_PATH="$PWD/$out/prefix/lib" "$out/app-pkgconfig"
echo "package_check: find_package(gearsim) and pkg-config consumers ok"
