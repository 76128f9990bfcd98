#!/usr/bin/env bash
# Sets everything up from a fresh clone and runs the whole test suite in tiers (tests/tiers.py):
# lint, fast (the science, the widgets without a kernel), fast again on Python 3.10 and 3.13, both at once
# (their venvs .venv-py310 and .venv-py313, by scripts/python-venv.sh), slow, install (the built wheel in each install
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

# The fast tier on the other Pythons (tests/tiers.py, OTHER_PYTHONS), all at once: each is one pytest
# process that keeps at most one core busy, so on a 2-core machine the two take about the time of one. Their
# venvs (scripts/python-venv.sh) are made first, one after the other (two pip installs of one source
# tree at once would build it into the same folders); each run's output is printed when all are done.
run_other_pythons() {
    local expression="$1"; shift
    local logs tier venv started elapsed status i=0
    local venvs=()
    logs="$(mktemp -d)"
    for tier in "$@"; do
        started=$SECONDS
        status=0
        venv="$("$REPO/scripts/python-venv.sh" "${tier#fast-py}")" || status=$?
        if [ "$status" != 0 ]; then
            record "$tier" "$((SECONDS - started))" "$status"
            rm -rf "$logs"
            return
        fi
        venvs+=("$venv")
        echo "$((SECONDS - started))" > "$logs/$tier.venv"
    done
    for tier in "$@"; do
        (
            started=$SECONDS
            status=0
            # -p no:cacheprovider: the runs would write .pytest_cache's files at the same time.
            "${venvs[$i]}/bin/python" "${pytest[@]:1}" -p no:cacheprovider -m "$expression" </dev/null || status=$?
            echo "$((SECONDS - started + $(cat "$logs/$tier.venv"))) $status" > "$logs/$tier.result"
        ) > "$logs/$tier.log" 2>&1 &
        i=$((i + 1))
    done
    wait
    for tier in "$@"; do
        echo "== tier $tier (at the same time as the other Pythons' fast tiers): -m \"$expression\""
        cat "$logs/$tier.log"
        read -r elapsed status < "$logs/$tier.result" || { elapsed=0; status=1; }
        echo "== tier $tier: ${elapsed} s (its venv ready after $(cat "$logs/$tier.venv") s)"
        record "$tier" "$elapsed" "$status"
    done
    rm -rf "$logs"
}

# record TIER SECONDS STATUS: the tier's line of the summary; a failed tier stops the run.
record() {
    summary+=("$(printf '%-11s %4d s  %s' "$1" "$2" "$([ "$3" = 0 ] && echo passed || echo "FAILED ($3)")")")
    if [ "$3" != 0 ]; then
        failed="${failed:-$1}"
        failed_status="${failed_status:-$3}"
    fi
}

stop_if_failed() {
    if [ -n "${failed:-}" ]; then
        printf '%s\n' "== the tiers' times:" "${summary[@]}"
        echo "== stopped at the tier '$failed'; the later tiers did not run" >&2
        exit "$failed_status"
    fi
}

tiers=()
while IFS= read -r line; do tiers+=("$line"); done < <("$VENV/bin/python" tests/tiers.py)
others=()
for line in "${tiers[@]}"; do [[ "$line" != fast-py* ]] || others+=("${line%%$'\t'*}"); done
summary=()
started_all=$SECONDS
for line in "${tiers[@]}"; do
    IFS=$'\t' read -r -a fields <<< "$line"   # name, marker expression, the files it is in (if given)
    tier="${fields[0]}"
    expression="${fields[1]}"
    paths=("${fields[@]:2}")
    if [[ "$tier" == fast-py* ]]; then
        # All of them at once, at the first one's line (they follow the fast tier, with its expression).
        [ "$tier" != "${others[0]}" ] || { run_other_pythons "$expression" "${others[@]}"; stop_if_failed; }
        continue
    fi
    if [ "$tier" != lint ] && [ "$tier" != fast ] && [ -z "${prepared:-}" ]; then
        prepare_browser_and_hub
        prepared=1
    fi
    echo "== tier $tier: -m \"$expression\""
    started=$SECONDS
    status=0
    "${pytest[@]}" -m "$expression" ${paths[@]+"${paths[@]}"} </dev/null || status=$?
    elapsed=$((SECONDS - started))
    echo "== tier $tier: ${elapsed} s"
    record "$tier" "$elapsed" "$status"
    stop_if_failed
done
printf '%s\n' "== the tiers' times:" "${summary[@]}" "== all tiers passed in $((SECONDS - started_all)) s"
