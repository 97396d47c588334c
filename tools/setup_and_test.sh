#!/usr/bin/env bash
# From a fresh checkout to a passing test suite:
#   Debian's chromium (for the inspector's browser test), a virtual
#   environment .venv with the project and its test extras, then pytest,
#   in parallel on every core (pytest-xdist's -n auto).
# Extra arguments go to pytest (e.g. -k lmap, or -m "not slow" for the quick lane).
# Each step says what it is doing: the installs take a minute or two.
#
# MAPKIT_NO_BROWSER=1: on a machine where you cannot install system packages,
# neither install chromium nor run the browser tests (pytest -m "not browser",
# joined to your own -m); the run says so. Without it a missing chromium is
# installed, and the browser tests fail if it cannot be.
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '==> %s\n' "$*"; }

args=("$@")
if [ "${MAPKIT_NO_BROWSER:-0}" = "1" ]; then
    step "MAPKIT_NO_BROWSER=1: no chromium install, the browser tests (marker 'browser') are not run"
    # One -m for pytest: the user's expression, if any, and not browser.
    marker="not browser"
    rest=()
    while [ ${#args[@]} -gt 0 ]; do
        if [ "${args[0]}" = "-m" ] && [ ${#args[@]} -gt 1 ]; then
            marker="(${args[1]}) and not browser"; args=("${args[@]:2}")
        else
            rest+=("${args[0]}"); args=("${args[@]:1}")
        fi
    done
    args=(-m "$marker" ${rest[@]+"${rest[@]}"})
elif command -v chromium >/dev/null 2>&1; then
    step "chromium: $(command -v chromium)"
else
    if [ "$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo"; fi
    step "installing chromium (apt-get) for the inspector's browser test ..."
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq chromium >/dev/null
fi

step "creating .venv ..."
python3 -m venv .venv
step "upgrading pip in .venv ..."
.venv/bin/python -m pip install -q --upgrade pip
# pip's own lines show the packages as they come; only its "already satisfied" chatter is dropped
# (a failing pip still fails the script: pipefail, and grep's no-match is not an error).
step "installing the project and its test extras (pip install -e '.[test]') ..."
.venv/bin/python -m pip install --progress-bar off -e '.[test]' | { grep -v '^Requirement already satisfied' || true; }
# Python's own cache of compiled modules, on even where the environment turns
# it off: each pytest worker compiles and rewrites every test module at
# collection, about 10 s of a run on 2 cores; the second run reads them from
# __pycache__ (which git ignores).
unset PYTHONDONTWRITEBYTECODE
step "running the tests (pytest -n auto ${args[*]+${args[*]}}) ..."
exec .venv/bin/python -m pytest -n auto ${args[@]+"${args[@]}"}
