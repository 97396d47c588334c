"""A fuzz case and what it ended in: the input files, the command run on
them and the commands that then read what it wrote (``FOLLOW_UPS``); a
failing case saved as a folder (``case.json`` and its files) and read back.

Paths in a case are names of the fresh folder it runs in; ``{ROOT}`` in a
command stands for the checkout, so a saved case runs from any clone.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

#: The checkout (``maps/``, ``tests/data``: the inputs the families damage).
ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data"
#: The example map in a case's command; ``{ROOT}`` is the checkout, so saved cases run from any clone.
FLAT_LMAP = "{ROOT}/maps/flat.lmap"

#: What reads a map a case's command wrote (``out.lmap``), run in turn while each ends valid.
FOLLOW_UPS = (["mapkit", "info", "out.lmap"], ["mapkit", "info", "out.lmap", "--json"],
              ["mapkit", "view", "out.lmap", "--html", "out.html"],
              ["mapkit", "export", "out.lmap", "--geojson", "out.geojson"])


@dataclass
class Case:
    """One input and the commands run on it: ``files`` (name -> bytes) are
    written into a fresh folder; ``call`` is ``["mapkit", *argv]``,
    ``["matcher", *argv]`` or ``["api", function, {arguments}]`` with file
    names of that folder wherever a path belongs; ``then``: commands of the
    same form run after it, in turn, while each ends valid (those that read
    what the one before wrote, or the same input another way);
    ``then_valid``: they read what ``call`` wrote (a map ``mapkit build``
    wrote), so any other end of theirs, even a clean error, is a bug."""

    family: str
    name: str
    files: dict[str, bytes]
    call: list
    note: str = ""
    then: list = field(default_factory=list)
    then_valid: bool = False


@dataclass
class Outcome:
    """What a case ended in: one of the kinds of ``classify``, its detail
    (the error line, the traceback), its wall-clock seconds."""

    kind: str
    detail: str = ""
    seconds: float = 0.0
    case: Case | None = field(default=None, repr=False)


def save_case(case: Case, outcome: Outcome, folder: Path) -> Path:
    """Write a failing case as a folder: its files and case.json."""
    d = folder / case.name
    d.mkdir(parents=True, exist_ok=True)
    for fname, blob in case.files.items():
        (d / fname).write_bytes(blob)
    (d / "case.json").write_text(json.dumps({"family": case.family, "call": case.call, "then": case.then,
                                             "then_valid": case.then_valid, "note": case.note,
                                             "outcome": outcome.kind, "detail": outcome.detail}, indent=1,
                                            default=str))
    return d


def load_case(folder: Path) -> Case:
    meta = json.loads((folder / "case.json").read_text())
    files = {p.name: p.read_bytes() for p in folder.iterdir() if p.name != "case.json" and p.is_file()}
    return Case(meta["family"], folder.name, files, meta["call"], meta.get("note", ""), meta.get("then", []),
                meta.get("then_valid", False))


def follow_ups(argv: list) -> dict:
    """``then`` and ``then_valid`` of a case: the commands that read the map
    ``argv`` writes, if it builds one."""
    return {"then": [list(c) for c in FOLLOW_UPS] if argv[0] == "build" else [], "then_valid": True}


@lru_cache(maxsize=None)
def source_bytes(path: Path) -> bytes:
    """The bytes of a file a family damages, read once a process."""
    return path.read_bytes()
