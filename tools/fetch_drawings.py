#!/usr/bin/env python3
"""Download the real-drawings corpus that ``tools/bench_drawings.py`` builds.

    python tools/fetch_drawings.py out/drawings            # every drawing of docs/benchmarks/drawings.tsv
    python tools/fetch_drawings.py out/drawings hal9k      # those whose id holds one of these
    python tools/fetch_drawings.py out/drawings --half tuning   # one half of the manifest's split
    python tools/bench_drawings.py out/drawings --manifest docs/benchmarks/drawings.tsv

Each drawing is a file of a public repository at a fixed commit (the
manifest's ``repo``, ``commit`` and ``path``), saved as ``DIR/<id>.dxf`` and
checked against the manifest's ``sha256_12``. Most carry no licence: they
are for your own benchmark runs, never to be committed here. Files already
present with the right checksum are kept.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import sys
import urllib.parse
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MANIFEST = ROOT / "docs" / "benchmarks" / "drawings.tsv"
#: Where a repository's file at a commit is served as raw bytes.
RAW_BASE = "https://raw.githubusercontent.com"


def corpus(manifest: Path) -> list[dict]:
    """The manifest's rows (``#`` lines are comments), each a dict by column
    name: ``id``, ``repo``, ``commit``, ``path``, ``sha256_12``, ``split``
    (``tuning`` or ``held_out``) and the judged columns that
    ``tools/bench_drawings.py`` reads."""
    lines = [ln for ln in manifest.read_text(encoding="utf-8").splitlines() if ln.strip() and not ln.startswith("#")]
    return list(csv.DictReader(lines, delimiter="\t"))


def raw_url(base: str, row: dict) -> str:
    """The address of one drawing: ``BASE/owner/name/commit/path`` (the path quoted: some hold spaces)."""
    return f"{base.rstrip('/')}/{row['repo']}/{row['commit']}/{urllib.parse.quote(row['path'])}"


def fetch(row: dict, folder: Path, base: str) -> str:
    """Download one drawing unless present with the manifest's checksum; what happened, as a word."""
    target = folder / f"{row['id']}.dxf"
    want = row.get("sha256_12", "")
    if target.exists() and hashlib.sha256(target.read_bytes()).hexdigest()[:12] == want:
        return "kept"
    with urllib.request.urlopen(raw_url(base, row), timeout=120) as resp:
        data = resp.read()
    got = hashlib.sha256(data).hexdigest()[:12]
    if want and got != want:
        raise ValueError(f"SHA-256 {got}..., the manifest says {want}...")
    tmp = target.with_suffix(".part")
    tmp.write_bytes(data)
    tmp.replace(target)
    return "fetched"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", type=Path, help="folder to save the drawings in (created)")
    ap.add_argument("only", nargs="*", help="only drawings whose id holds one of these")
    ap.add_argument("--manifest", type=Path, default=MANIFEST, help="the corpus (default docs/benchmarks/drawings.tsv)")
    ap.add_argument("--half", choices=("tuning", "held_out"), help="only the drawings of this half of the split")
    ap.add_argument("--base-url", default=RAW_BASE, help=f"where raw files are served (default {RAW_BASE})")
    args = ap.parse_intermixed_args(argv)
    args.folder.mkdir(parents=True, exist_ok=True)
    failed = 0
    for row in corpus(args.manifest):
        if args.only and not any(o in row["id"] for o in args.only):
            continue
        if args.half and row.get("split") != args.half:
            continue
        try:
            print(f"{row['id']}: {fetch(row, args.folder, args.base_url)}")
        except (OSError, ValueError) as exc:  # one unreachable file does not stop the others
            print(f"{row['id']}: failed: {exc}", file=sys.stderr)
            failed += 1
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
