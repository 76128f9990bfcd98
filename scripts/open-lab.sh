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
    if [ "$#" -eq 0 ]; then
        # JupyterLab prints its root URL; choose the port and token here so the printed link
        # opens the start-here tutorial itself.
        read -r port token < <("$VENV/bin/python" -c 'import secrets, socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1], secrets.token_hex(24))')
        args+=(--port="$port" --port-retries=0 --IdentityProvider.token="$token")
        echo "== no screen here: open http://localhost:$port/lab/tree/tutorials/00_start_here.ipynb?token=$token"
    else
        echo "== no screen here: open the URL JupyterLab prints below, then tutorials/00_start_here.ipynb"
    fi
fi
cd "$REPO"
exec "$VENV/bin/jupyter" lab "${args[@]}" "$@" tutorials/00_start_here.ipynb
