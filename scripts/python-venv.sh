#!/usr/bin/env bash
# Prints the path of a venv of Python VERSION (e.g. 3.10) with mt-widgets and what the fast tier collects
# (every extra but bench: the tests of the hub and the course import their libraries),
# creating or updating it first: .venv-py310 in the repository (ignored by git), re-installed only when
# pyproject.toml changed, so a second run takes seconds. The interpreter is python3.X on PATH, else
# pyenv's newest 3.X. Used by run-tests.sh for the tiers of tests/tiers.py's OTHER_PYTHONS.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
version="${1:?usage: python-venv.sh VERSION (e.g. 3.10)}"
if ! [[ "$version" =~ ^3\.[0-9]+$ ]]; then
    echo "python-venv.sh: VERSION: expected 3.X (e.g. 3.10), got '$version'" >&2
    exit 2
fi
VENV="$REPO/.venv-py${version/./}"
find_python() {
    # A pyenv shim of another version is on PATH but fails: the name must also run.
    if command -v "python$version" >/dev/null && "python$version" -c "" 2>/dev/null; then
        command -v "python$version"
        return
    fi
    local root
    root="$(pyenv root 2>/dev/null || echo "$HOME/.pyenv")"
    local found
    found="$(ls -d "$root"/versions/"$version".*/bin/python 2>/dev/null | sort -V | tail -n 1 || true)"
    if [ -z "$found" ]; then
        echo "python-venv.sh: no Python $version (neither python$version on PATH nor pyenv's $root/versions/$version.*)" >&2
        exit 1
    fi
    echo "$found"
}
if [ ! -x "$VENV/bin/python" ]; then
    "$(find_python)" -m venv "$VENV" >&2
fi
stamp="$VENV/.mt-widgets-installed"
wanted="$(sha256sum "$REPO/pyproject.toml" | cut -d' ' -f1)"
if [ "$(cat "$stamp" 2>/dev/null || true)" != "$wanted" ]; then
    echo "== installing mt-widgets[lab,test,course,hub] into $VENV" >&2
    "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check --no-compile -e "$REPO[lab,test,course,hub]" >&2
    echo "$wanted" > "$stamp"
fi
echo "$VENV"
