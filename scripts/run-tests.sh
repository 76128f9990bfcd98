#!/usr/bin/env bash
# Sets everything up from a fresh clone and runs the whole test suite in tiers (tests/tiers.py):
# lint, fast (the science, the widgets without a kernel), fast again on Python 3.10 and 3.13 (their venvs
# .venv-py310 and .venv-py313, by scripts/python-venv.sh), slow, install (the built wheel in each install
# shape), browser (Chromium, installed here from Debian's packages when missing), notebook (every
# notebook under nbval) and hub. Each tier prints its time; the first tier that fails stops the run, so a lint error or a broken core is
# reported in a minute or two. With extra arguments, one pytest run with them instead (a folder, -k, -m ...).
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
source "$REPO/scripts/setup.sh"

cd "$REPO"
# The browser tiers need Debian's Chromium, the hub tier configurable-http-proxy (npm, into .npm/):
# installed when missing, once the cheap tiers passed.
prepare_browser_and_hub() {
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
    # The several-servers test (tests/study_shards, slow tier) runs Debian's nginx as a user, under its own prefix.
    if [ ! -x /usr/sbin/nginx ]; then
        echo "== installing Debian's nginx for the several-servers test"
        if [ "$(id -u)" = 0 ]; then sudo=(); elif sudo -n true 2>/dev/null; then sudo=(sudo -n); else
            echo "The several-servers test needs /usr/sbin/nginx (Debian package 'nginx'); install it and run this again." >&2
            exit 1
        fi
        export DEBIAN_FRONTEND=noninteractive
        "${sudo[@]}" apt-get update -qq
        "${sudo[@]}" apt-get install -y -qq nginx >/dev/null
    fi

    # The class-hub tests need configurable-http-proxy (npm); installed into .npm/ when missing.
    PATH="$("$REPO/scripts/install-hub.sh"):$PATH"
    export PATH
}

# A notebook's shortening under test comes from its cell tagged `parameters`, which the test run
# overrides (conftest.py, NOTEBOOK_PARAMETERS): nothing to set here.
pytest=("$VENV/bin/python" -m pytest --nbval-lax --timeout=600)
if [ "$#" -gt 0 ]; then
    prepare_browser_and_hub
    exec "${pytest[@]}" "$@"
fi

tiers=()
while IFS= read -r line; do tiers+=("$line"); done < <("$VENV/bin/python" tests/tiers.py)
summary=()
started_all=$SECONDS
for line in "${tiers[@]}"; do
    IFS=$'\t' read -r -a fields <<< "$line"   # name, marker expression, the files it is in (if given)
    tier="${fields[0]}"
    expression="${fields[1]}"
    paths=("${fields[@]:2}")
    if [ "$tier" != lint ] && [ "$tier" != fast ] && [[ "$tier" != fast-py* ]] && [ -z "${prepared:-}" ]; then
        prepare_browser_and_hub
        prepared=1
    fi
    echo "== tier $tier: -m \"$expression\""
    started=$SECONDS
    status=0
    run=("${pytest[@]}")
    # The fast tier on another Python (tests/tiers.py, OTHER_PYTHONS): that Python's venv, .venv-py3XX.
    if [[ "$tier" == fast-py* ]]; then
        other="$("$REPO/scripts/python-venv.sh" "${tier#fast-py}")" || status=$?
        run=("$other/bin/python" "${pytest[@]:1}")
    fi
    [ "$status" != 0 ] || "${run[@]}" -m "$expression" ${paths[@]+"${paths[@]}"} </dev/null || status=$?
    elapsed=$((SECONDS - started))
    summary+=("$(printf '%-9s %4d s  %s' "$tier" "$elapsed" "$([ "$status" = 0 ] && echo passed || echo "FAILED ($status)")")")
    echo "== tier $tier: ${elapsed} s"
    if [ "$status" != 0 ]; then
        printf '%s\n' "== the tiers' times:" "${summary[@]}"
        echo "== stopped at the tier '$tier'; the later tiers did not run" >&2
        exit "$status"
    fi
done
printf '%s\n' "== the tiers' times:" "${summary[@]}" "== all tiers passed in $((SECONDS - started_all)) s"
