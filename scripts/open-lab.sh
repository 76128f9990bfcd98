#!/usr/bin/env bash
# Sets everything up from a fresh clone and opens the suite in JupyterLab at the start-here
# tutorial: `mt-widgets lab` on the clone itself (its tutorials/ and notebooks/ are used in place).
# Without a screen, the URL to open is printed. Extra arguments go to JupyterLab.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$REPO/scripts/setup.sh"
exec "$VENV/bin/python" -m mt_widgets.cli lab "$REPO" -- "$@"
