#!/usr/bin/env bash
# Installs what a JupyterHub for a class needs beyond the Python extras (mt-widgets[course,hub]):
#
# 1. configurable-http-proxy from npm. It goes into .npm/ of this checkout unless one is already on
#    PATH (set NPM_GLOBAL=1 to run `npm install -g configurable-http-proxy` instead).
# 2. The students' Python, .venv/students/, when students could not run .venv's own: every
#    student's server runs as that student's system user, who must be able to enter every folder
#    down to the interpreter, and a pyenv Python under /root (mode 0700) is out of their reach.
#    .venv/students is a venv of the system's python3 of the same minor version (same ABI), whose
#    site-packages, share/ and etc/ are .venv's own (symlinks): one installation, nothing copied;
#    the hub finds it through MT_HUB_STUDENT_PYTHON (tests/course/hub_support.py sets it). Its bin/
#    holds .venv's commands (nbgrader, jupyter, alembic) run by that Python, for instructors.
#
# Prints the folder to put first on PATH (for the proxy) as its last line. Sourced by
# run-tests.sh, so the hub tests find the proxy.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$REPO/.venv"

students_python() {
    # Can a user who is neither owner nor group enter every folder down to .venv's interpreter?
    local real folder
    real="$(readlink -f "$VENV/bin/python")"
    folder="$(dirname "$real")"
    while [ "$folder" != / ]; do
        if [ "$(( $(stat -c '%a' "$folder" | sed 's/^.*\(.\)$/\1/') & 1 ))" = 0 ]; then
            break
        fi
        folder="$(dirname "$folder")"
    done
    if [ "$folder" = / ]; then
        return 0  # .venv's interpreter is reachable: students use it as it is
    fi
    local version system
    version="$("$VENV/bin/python" -c 'import sys; print("%d.%d" % sys.version_info[:2])')"
    system="/usr/bin/python$version"
    if [ ! -x "$system" ]; then
        echo "students cannot enter $folder (so not run $real), and there is no $system to give them" >&2
        echo "(Debian: apt-get install python$version, or chmod o+x $folder)" >&2
        return 1
    fi
    local students="$VENV/students"
    local site="lib/python$version/site-packages"
    # Made again when its site-packages is not .venv's own: a .venv reached through a symlink (a
    # git worktree's) made links to a folder that may since have gone.
    if [ ! -x "$students/bin/python" ] || [ "$(readlink -f "$students/$site")" != "$(readlink -f "$VENV/$site")" ]; then
        rm -rf "${students:?}"
        "$system" -m venv --without-pip "$students" >&2
        rm -rf "${students:?}/$site"
        ln -s "$VENV/$site" "$students/$site"
        for shared in share etc; do
            [ -e "$VENV/$shared" ] && ln -sfn "$VENV/$shared" "$students/$shared"
        done
    fi
    # .venv's commands (nbgrader, alembic, jupyter, ...) for everyone on the hub, instructors
    # included: the same scripts with the students' Python as interpreter (an instructor grades
    # with nbgrader as their own user, and nbgrader runs alembic by name).
    local script first
    for script in "$VENV"/bin/*; do
        [ -f "$script" ] && [ ! -L "$script" ] || continue
        first="$(head -c 200 "$script" | tr -d '\000' | head -n 1)"
        if [ "$first" = "#!$VENV/bin/python" ] || [ "$first" = "#!$VENV/bin/python3" ]; then
            { echo "#!$students/bin/python"; tail -n +2 "$script"; } > "$students/bin/.$(basename "$script").new"
            chmod 755 "$students/bin/.$(basename "$script").new"
            mv -f "$students/bin/.$(basename "$script").new" "$students/bin/$(basename "$script")"
        fi
    done
    echo "students' Python: $students/bin/python ($("$students/bin/python" --version 2>&1))" >&2
}

proxy() {
    if command -v configurable-http-proxy >/dev/null 2>&1; then
        dirname "$(command -v configurable-http-proxy)"
        return 0
    fi
    if [ -x "$REPO/.npm/bin/configurable-http-proxy" ]; then
        echo "$REPO/.npm/bin"
        return 0
    fi
    if ! command -v npm >/dev/null 2>&1; then
        echo "configurable-http-proxy needs npm (Debian: apt-get install -y npm)" >&2
        return 1
    fi
    if [ "${NPM_GLOBAL:-0}" = 1 ]; then
        npm install -g --no-fund --no-audit configurable-http-proxy >&2
        dirname "$(command -v configurable-http-proxy)"
    else
        npm install --prefix "$REPO/.npm" -g --no-fund --no-audit configurable-http-proxy >&2
        echo "$REPO/.npm/bin"
    fi
}

if [ -x "$VENV/bin/python" ]; then
    students_python
fi
proxy
