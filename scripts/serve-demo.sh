#!/usr/bin/env bash
# Serves the visitors' demo (notebooks/demo.ipynb) with Voila for a kiosk or a class: `mt-widgets demo`,
# with the configuration in deploy/voila/voila.py (--Voila.config_file_paths=deploy/voila): a closed
# page ends its kernel, idle kernels without a page are culled, and a preheated kernel makes the page
# interactive within about 2 s. Open http://localhost:8866/ . Extra arguments go to Voila, e.g.
# --port=8000 or --Voila.ip=0.0.0.0 to serve other machines of the room.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$REPO/scripts/setup.sh"
exec "$VENV/bin/python" -m mt_widgets.cli demo -- "$@"
