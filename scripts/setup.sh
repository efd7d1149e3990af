#!/usr/bin/env bash
# Installs what gearsim needs on a fresh Debian machine: the C toolchain,
# cmocka and clang-format (the C style check of scripts/lint.sh) from apt (when
# missing), and a Python virtual environment in .venv
# with the package installed in editable mode, with every extra the scripts
# and tests use (all: analysis, hil, fmu, bench) and the test tools. Safe to
# run again.
# Usage: scripts/setup.sh [apt-package ...]   (extra Debian packages to ensure)
set -euo pipefail
cd "$(dirname "$0")/.."

need_apt=()
for pkg in cmake gcc make pkg-config libcmocka-dev clang-format "$@"; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need_apt+=("$pkg")
done
if ((${#need_apt[@]})); then
  echo "setup: installing Debian packages: ${need_apt[*]}" >&2
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq "${need_apt[@]}" >/dev/null
fi

if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv" >&2
  python3 -m venv .venv
fi
stamp=.venv/.gearsim-installed
if [ ! -f "$stamp" ] || [ pyproject.toml -nt "$stamp" ] || [ setup.py -nt "$stamp" ] || [ -n "$(find src include bindings hil/src hil/include hil/dbc -newer "$stamp" -print -quit 2>/dev/null)" ]; then
  echo "setup: installing the gearsim Python package into .venv (compiles the C core)" >&2
  .venv/bin/python -m pip install -q --upgrade pip >/dev/null
  .venv/bin/python -m pip install -q -e ".[all,test]"
  touch "$stamp"
fi
