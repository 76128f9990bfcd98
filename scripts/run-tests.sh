#!/usr/bin/env bash
# Sets everything up from a fresh clone and runs the whole test suite: the science, the
# widgets without a kernel, every notebook under nbval, and the real-browser tests in
# Chromium (installed here from Debian's packages when missing). Extra arguments go to pytest.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$REPO/scripts/setup.sh"

if [ ! -x /usr/bin/chromium ]; then
    echo "== installing Debian's chromium for the browser tests"
    if [ "$(id -u)" = 0 ]; then sudo=(); elif sudo -n true 2>/dev/null; then sudo=(sudo -n); else
        echo "The browser tests need /usr/bin/chromium (Debian package 'chromium') and this user cannot install it." >&2
        echo "Install it (apt-get install chromium) and run this again." >&2
        exit 1
    fi
    export DEBIAN_FRONTEND=noninteractive
    "${sudo[@]}" apt-get update -qq
    "${sudo[@]}" apt-get install -y -qq chromium >/dev/null
fi
/usr/bin/chromium --version

# The class-hub tests need configurable-http-proxy (npm); installed into .npm/ when missing.
PATH="$("$REPO/scripts/install-hub.sh"):$PATH"
export PATH

cd "$REPO"
# The one switch that shortens long notebook work under test (see mt_widgets/core/fast_mode.py).
export MT_WIDGETS_FAST=1
exec "$VENV/bin/python" -m pytest --nbval-lax --timeout=600 "$@"
