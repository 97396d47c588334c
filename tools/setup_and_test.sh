#!/usr/bin/env bash
# From a fresh checkout to a passing test suite:
#   Debian's chromium (for the inspector's browser test), a virtual
#   environment .venv with the project and its test extras, then pytest.
# Extra arguments go to pytest (e.g. -k lmap).
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v chromium >/dev/null 2>&1; then
    if [ "$(id -u)" -eq 0 ]; then SUDO=""; else SUDO="sudo"; fi
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq chromium >/dev/null
fi

python3 -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -e '.[test]'
.venv/bin/python -m pytest -q "$@"
