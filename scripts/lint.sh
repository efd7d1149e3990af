#!/usr/bin/env bash
# The style checks, the first stage of scripts/test.sh (and what the
# pre-commit hooks run on the files a commit changes):
#   ruff check and ruff format --check over the Python code (pyproject.toml
#   [tool.ruff]), clang-format --dry-run over the C sources (.clang-format),
#   and mypy over the typed package gearsim.analysis (pyproject.toml [tool.mypy]).
# Usage: scripts/lint.sh [--fix]   (--fix applies ruff's fixes and both formatters)
set -euo pipefail
cd "$(dirname "$0")/.."
py=.venv/bin/python
[ -x "$py" ] || { echo "lint: no .venv; run scripts/setup.sh first" >&2; exit 2; }
command -v clang-format >/dev/null || scripts/setup.sh clang-format
fix=0
[ "${1:-}" = "--fix" ] && fix=1

mapfile -t c_files < <(git ls-files '*.c' '*.h')
failures=0
if ((fix)); then
  "$py" -m ruff check --fix . || failures=$((failures + 1))
  "$py" -m ruff format .
  clang-format -i "${c_files[@]}"
else
  "$py" -m ruff check . || failures=$((failures + 1))
  "$py" -m ruff format --check . || failures=$((failures + 1))
  clang-format --dry-run --Werror "${c_files[@]}" || failures=$((failures + 1))
fi
"$py" -m mypy || failures=$((failures + 1))
if ((failures)); then
  echo "lint: $failures check(s) failed; scripts/lint.sh --fix applies the formatters" >&2
  exit 1
fi
echo "lint: ruff, clang-format and mypy clean (${#c_files[@]} C files; $(clang-format --version))"
