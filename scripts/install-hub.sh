#!/usr/bin/env bash
# Installs what a JupyterHub for a class needs beyond the Python extras (mt-widgets[course,hub]):
# configurable-http-proxy from npm. It goes into .npm/ of this checkout unless one is already on
# PATH (set NPM_GLOBAL=1 to run `npm install -g configurable-http-proxy` instead). Prints the
# folder to put first on PATH. Sourced by run-tests.sh, so the hub tests find the proxy.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if command -v configurable-http-proxy >/dev/null 2>&1; then
    dirname "$(command -v configurable-http-proxy)"
    exit 0
fi
if [ -x "$REPO/.npm/bin/configurable-http-proxy" ]; then
    echo "$REPO/.npm/bin"
    exit 0
fi
if ! command -v npm >/dev/null 2>&1; then
    echo "configurable-http-proxy needs npm (Debian: apt-get install -y npm)" >&2
    exit 1
fi
if [ "${NPM_GLOBAL:-0}" = 1 ]; then
    npm install -g --no-fund --no-audit configurable-http-proxy >&2
    dirname "$(command -v configurable-http-proxy)"
else
    npm install --prefix "$REPO/.npm" -g --no-fund --no-audit configurable-http-proxy >&2
    echo "$REPO/.npm/bin"
fi
