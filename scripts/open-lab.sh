#!/usr/bin/env bash
# Sets everything up from a fresh clone and opens the suite in JupyterLab at the start-here
# tutorial. Without a screen, JupyterLab prints the URL to open instead.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$REPO/scripts/setup.sh"
args=(--ServerApp.root_dir="$REPO")
[ "$(id -u)" = 0 ] && args+=(--allow-root)
if [ -z "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ] && [ "$(uname)" = Linux ]; then
    args+=(--no-browser)
    echo "== no screen here: open the URL JupyterLab prints below (tutorials/00_start_here.ipynb)"
fi
cd "$REPO"
exec "$VENV/bin/jupyter" lab "${args[@]}" "$@" tutorials/00_start_here.ipynb
