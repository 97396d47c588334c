"""tools/setup_and_test.sh, the README's test command, run against stub
programs (no install, no network): what it would run, and that
MAPKIT_NO_BROWSER=1 neither installs chromium nor runs the browser tests."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: A stand-in for python3 and for apt-get/sudo: logs its arguments, one call a line;
#: ``python3 -m venv .venv`` makes .venv/bin/python, itself such a stand-in.
STUB = """#!/bin/sh
printf '%s' "$(basename "$0")" >> "$STUB_LOG"
for a in "$@"; do printf ' [%s]' "$a" >> "$STUB_LOG"; done
printf '\\n' >> "$STUB_LOG"
if [ "$1" = "-m" ] && [ "$2" = "venv" ]; then mkdir -p "$3/bin" && cp "$0" "$3/bin/python"; fi
exit 0
"""


def _run(tmp_path: Path, env_extra: dict, *args: str) -> list[str]:
    repo = tmp_path / "repo"
    (repo / "tools").mkdir(parents=True)
    shutil.copy(ROOT / "tools" / "setup_and_test.sh", repo / "tools")
    stubs = tmp_path / "bin"
    stubs.mkdir()
    for name in ("python3", "apt-get", "sudo"):
        (stubs / name).write_text(STUB)
        (stubs / name).chmod(0o755)
    log = tmp_path / "log"
    log.touch()
    # Only the stubs and the basic tools: chromium is not on this PATH.
    path = f"{stubs}:/usr/bin:/bin"
    env = {"PATH": path, "STUB_LOG": str(log), "HOME": str(tmp_path), **env_extra}
    if shutil.which("chromium", path=path):
        env["PATH"] = f"{stubs}:{_basic_tools(tmp_path)}"
    r = subprocess.run([shutil.which("bash"), str(repo / "tools" / "setup_and_test.sh"), *args], env=env, capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    return log.read_text().splitlines()


def _basic_tools(tmp_path: Path) -> str:
    """A folder with links to the few programs the script needs, and no chromium."""
    folder = tmp_path / "basic"
    folder.mkdir()
    for name in ("basename", "bash", "cat", "cp", "dirname", "grep", "id", "mkdir", "printf", "sh"):
        os.symlink(shutil.which(name), folder / name)
    return str(folder)


def test_no_browser_skips_the_install_and_the_browser_tests(tmp_path):
    calls = _run(tmp_path, {"MAPKIT_NO_BROWSER": "1"}, "-m", "not slow", "-q")
    assert not any(c.startswith(("apt-get", "sudo")) for c in calls), calls
    assert calls[-1] == "python [-m] [pytest] [-n] [auto] [-m] [(not slow) and not browser] [-q]"


def test_without_the_option_a_missing_chromium_is_installed(tmp_path):
    calls = _run(tmp_path, {}, "-k", "lmap")
    assert any(c.startswith("apt-get") and "[chromium]" in c for c in calls), calls
    assert calls[-1] == "python [-m] [pytest] [-n] [auto] [-k] [lmap]"
