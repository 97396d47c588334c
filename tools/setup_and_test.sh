#!/usr/bin/env bash
# From a fresh checkout to a passing test suite:
#   Debian's chromium (for the inspector's browser test), a virtual
#   environment .venv with the project and its test extras, then pytest,
#   in parallel on every core (pytest-xdist's -n auto).
# Extra arguments go to pytest (e.g. -k lmap, or -m "not slow" for the quick lane).
# Each step says what it is doing: the installs take a minute or two.
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '==> %s\n' "$*"; }

if command -v chromium >/dev/null 2>&1; then
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
step "running the tests (pytest -n auto $*) ..."
exec .venv/bin/python -m pytest -n auto "$@"
