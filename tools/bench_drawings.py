#!/usr/bin/env python3
"""Build every drawing of a folder with defaults, as a new user would, and
judge what came out.

    python tools/bench_drawings.py DIR                      # every plan in DIR
    python tools/bench_drawings.py DIR hal9k daoshi_f1      # drawings whose name holds one of these
    python tools/bench_drawings.py DIR --previews out/previews --report out/drawings.md
    python tools/bench_drawings.py DIR --manifest docs/benchmarks/drawings.tsv --half tuning   # one half only

Each drawing is built by ``mapkit build DRAWING -o OUT.lmap`` with no option
at all, in a child process of its own (its seconds and peak memory, the
child's ``ru_maxrss``, are the build's alone). A second child asks the
importer what it understood (``mapkit.importers.load_scene``): the doors and
windows found, the free space's area and how many separate parts it has.

A manifest beside the drawings (``DIR/manifest.tsv`` or ``--manifest``) may
say what a person sees in each drawing; a column left empty is not judged:

    id  repo  split  expect  doors_drawn  rooms  outline_m2  sha256_12
    (tab-separated; '#' lines are comments; the drawing is DIR/<id>.dxf, or a "file" column)

The outcome of a drawing:

- **right**: built, and each judged fact holds: at most 10 % of the doors
  drawn are missing; the rooms connect (the free space is one part, or no
  more parts than the manifest's ``rooms`` when its doors are not drawn);
  the free space lies inside the building (no more than ``outline_m2``)
  and fills a fair share of it (at least 40 %: rooms are not lost);
  no fallback to the walls' convex hull. Also right: a drawing that cannot
  honestly be right with defaults (unknown scale, traced in pixels, a
  framing plan), declared in the manifest's ``expect`` column as
  ``refuse:--OPTION``, refused with a message that names that option.
- **built wrong**: built, and a judged fact fails (named in the notes), or
  built though the manifest expects a refusal.
- **built**: built, nothing to judge it by.
- **refused**: the one-line error (exit 2); it should name what fixes it.
- **bug**: anything else: a traceback, an internal error (exit 3), a crash
  or the time limit.

The manifest's ``split`` column puts each drawing in the ``tuning`` or the
``held_out`` half by a fixed rule (``split_of``: the parity of a hash of
its repository's name, so that drawings of one repository, or of its
forks, stay in one half); rules are chosen on the tuning half and both
halves are reported. The summary counts each outcome per half and in all.
A manifest's ``sha256_12`` column (the first 12 hex digits of a file's
SHA-256) warns when a drawing is another version than the one measured.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from mapkit_harness.tables import add_report_option, markdown_table, reported

#: Plan files the benchmark builds (mapkit build's suffixes for drawings).
PLAN_SUFFIXES = (".dxf",)
#: Share of the doors drawn that may be missing in a right build.
MISSING_DOORS_SHARE = 0.10
#: The free space may exceed the building's outline by this share (the
#: outline in a manifest is a person's estimate).
OUTLINE_SLACK = 0.05
#: A right build's free space fills at least this share of the outline:
#: walls take 10 to 20 % of a floor and the robot's clearance from them
#: (0.2 m each side) a further 15 to 30 % of rooms 3 to 4 m wide, and
#: furniture drawn as walls some more; below 40 % whole rooms are lost.
MIN_FREE_SHARE = 0.40
#: The halves of the corpus (the manifest's ``split`` column).
HALVES = ("tuning", "held_out")


@dataclass
class Expected:
    """What a person sees in a drawing (None: not given, not judged)."""

    doors_drawn: int | None = None
    rooms: int | None = None
    outline_m2: float | None = None
    #: ``refuse:--OPTION`` (or ``refuse:--A|--B``): the drawing cannot
    #: honestly be right with defaults; a refusal naming the option (one
    #: of them) is its right outcome. A bare ``refuse``: no option makes it
    #: a floor plan (a framing plan), any one-line refusal is right.
    expect: str | None = None
    #: ``tuning`` or ``held_out`` (None: not in the corpus's split).
    split: str | None = None

    def refusal_options(self) -> list[str] | None:
        """The options one of which a right refusal names (``["--scale"]``;
        ``[]``: any refusal), or None when a refusal is not expected."""
        if not self.expect or not self.expect.startswith("refuse"):
            return None
        return [o.strip() for o in self.expect.removeprefix("refuse").lstrip(":").split("|") if o.strip()]


def split_of(repo: str) -> str:
    """The half a drawing of ``repo`` ("owner/name") belongs to: the parity
    of the first byte of the SHA-256 of the repository's name (lower case,
    without its owner, so a fork falls in the same half as its source).
    Fixed before any drawing was judged: it cannot be chosen per drawing."""
    name = repo.strip().split("/")[-1].lower()
    return HALVES[hashlib.sha256(name.encode()).digest()[0] % 2]


@dataclass
class Outcome:
    """One drawing's build: outcome, figures and notes."""

    name: str
    outcome: str = ""
    seconds: float = float("nan")
    peak_mb: float = float("nan")
    segments: int | None = None
    regions: int | None = None
    doors: int | None = None
    windows: int | None = None
    free_m2: float | None = None
    free_parts: int | None = None
    warnings: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


# -- children ---------------------------------------------------------------

def child_build(plan: str, out: str) -> dict:
    """``mapkit build PLAN -o OUT`` in this process, as the command line runs
    it: exit status, stderr lines, seconds, peak memory."""
    import contextlib
    import io
    import resource
    import traceback

    from mapkit.cli import main

    err = io.StringIO()
    t0 = time.perf_counter()
    with contextlib.redirect_stderr(err):
        try:
            rc = main(["build", plan, "-o", out, "-q"])
        except SystemExit as exc:  # argparse
            rc = exc.code if isinstance(exc.code, int) else 2
        except BaseException:  # a traceback is what the benchmark looks for
            traceback.print_exc(file=err)
            rc = -1
    seconds = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return {"rc": rc, "stderr": err.getvalue().splitlines(), "seconds": seconds, "peak_mb": peak}


def child_scene(plan: str) -> dict:
    """What the importer understood of ``plan`` with default options."""
    import logging

    logging.disable(logging.WARNING)
    from mapkit.importers import load_scene
    from mapkit.shapes import polygon_parts

    scene = load_scene(plan)
    kinds = [o.kind for o in scene.openings]
    parts = polygon_parts(scene.free_space)
    return {"doors": kinds.count("door"), "windows": kinds.count("window"),
            "free_m2": float(scene.free_space.area), "free_parts": len(parts),
            "warnings": [str(w) for w in scene.info.get("warnings", [])]}


def run_child(args: list[str], timeout: float) -> dict:
    """One child of this script; its JSON answer, or {"crash": why}."""
    try:
        done = subprocess.run([sys.executable, __file__, *args], capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"crash": f"over the time limit of {timeout:g} s"}
    lines = done.stdout.strip().splitlines()
    if done.returncode or not lines:
        tail = (done.stderr or done.stdout).strip().splitlines()
        return {"crash": tail[-1] if tail else f"exit status {done.returncode}"}
    return json.loads(lines[-1])


# -- judging ----------------------------------------------------------------

def judge(o: Outcome, exp: Expected) -> None:
    """Set ``o.outcome`` for a built drawing from the facts a person gave."""
    wrong = []
    if exp.refusal_options() is not None:
        wrong.append(f"built, though it cannot be right with defaults (the manifest expects {exp.expect})")
    if exp.doors_drawn:
        missing = exp.doors_drawn - (o.doors or 0)
        if missing > MISSING_DOORS_SHARE * exp.doors_drawn:
            wrong.append(f"{o.doors} of {exp.doors_drawn} doors found")
    if o.free_parts is not None and o.free_parts > 1:
        # Rooms whose doors are not drawn cannot connect: then as many parts as rooms is right.
        allowed = exp.rooms if (exp.rooms and exp.doors_drawn == 0) else 1
        if o.free_parts > allowed:
            wrong.append(f"free space in {o.free_parts} parts: rooms not connected")
    if exp.outline_m2 and o.free_m2 is not None and o.free_m2 > exp.outline_m2 * (1 + OUTLINE_SLACK):
        wrong.append(f"free space {o.free_m2:.0f} m2 beyond the outline's {exp.outline_m2:.0f} m2")
    if exp.outline_m2 and o.free_m2 is not None and o.free_m2 < exp.outline_m2 * MIN_FREE_SHARE:
        wrong.append(f"free space {o.free_m2:.0f} m2, under {100 * MIN_FREE_SHARE:.0f} % of the outline's "
                     f"{exp.outline_m2:.0f} m2: rooms lost")
    if any("convex hull" in w for w in o.warnings):
        wrong.append("free space from the walls' convex hull")
    judged = any(v is not None for v in (exp.doors_drawn, exp.rooms, exp.outline_m2))
    o.notes += wrong
    o.outcome = "built wrong" if wrong else ("right" if judged else "built")


def judge_refusal(o: Outcome, exp: Expected, message: str) -> None:
    """A refusal is right when the manifest expects one and the message
    names the option it expects; otherwise it is "refused"."""
    options = exp.refusal_options()
    named = [opt for opt in options or () if opt in message]
    if options is not None and (named or not options):
        why = f"naming {named[0]}" if named else "(no option makes it a floor plan)"
        o.outcome, o.notes = "right", [f"refused {why}, as the manifest expects: {message}"]
    else:
        o.outcome, o.notes = "refused", [message]


def bench_one(plan: Path, exp: Expected, timeout: float, previews: Path | None) -> Outcome:
    """Build ``plan`` with defaults and judge it."""
    o = Outcome(plan.stem)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / f"{plan.stem}.lmap"
        b = run_child(["--child-build", str(plan), str(out)], timeout)
        if "crash" in b:
            o.outcome, o.notes = "bug", [b["crash"]]
            return o
        o.seconds, o.peak_mb = b["seconds"], b["peak_mb"]
        err = b["stderr"]
        o.warnings = [ln.split("warning:", 1)[1].strip() for ln in err if ln.startswith("mapkit: warning:")]
        errors = [ln for ln in err if ln.startswith("mapkit: error:")]
        traceback = any(ln.startswith("Traceback") for ln in err)
        if b["rc"] == 2 and errors and not traceback:
            judge_refusal(o, exp, errors[-1].removeprefix("mapkit: error: "))
            return o
        if b["rc"] != 0 or traceback or not out.exists():
            o.outcome, o.notes = "bug", [f"exit {b['rc']}: {err[-1] if err else 'no message'}"]
            return o
        from linemap.lmap import load_map

        counts = load_map(out).meta.get("stats", {}).get("counts", {})
        o.segments, o.regions = counts.get("segments"), counts.get("regions")
    s = run_child(["--child-scene", str(plan)], timeout)
    if "crash" in s:
        o.outcome, o.notes = "bug", [f"the import alone: {s['crash']}"]
        return o
    o.doors, o.windows, o.free_m2, o.free_parts = s["doors"], s["windows"], s["free_m2"], s["free_parts"]
    judge(o, exp)
    if previews is not None:
        previews.mkdir(parents=True, exist_ok=True)
        subprocess.run([sys.executable, "-m", "mapkit", "preview", str(plan), "-o", str(previews / f"{plan.stem}.png")],
                       capture_output=True, timeout=timeout)
    return o


# -- manifest and table -----------------------------------------------------

def read_manifest(path: Path) -> tuple[dict[str, Expected], dict[str, str]]:
    """What a person sees in each drawing, by name (file stem), and the
    SHA-256 prefixes (``sha256_12``) of the versions measured, from a TSV
    (``#`` lines are comments) or JSON (a list of objects) manifest."""
    if path.suffix == ".json":
        rows = json.loads(path.read_text())
    else:
        lines = [ln for ln in path.read_text(encoding="utf-8").splitlines() if ln.strip() and not ln.startswith("#")]
        rows = list(csv.DictReader(lines, delimiter="\t"))

    def num(row, key, kind):
        v = row.get(key)
        return None if v in (None, "", "-") else kind(v)

    exps, sums = {}, {}
    for row in rows:
        name = Path(row.get("file") or row.get("id") or "").stem
        if name:
            exps[name] = Expected(num(row, "doors_drawn", int), num(row, "rooms", int), num(row, "outline_m2", float),
                                  row.get("expect") or None, row.get("split") or None)
            check_split(name, row)
            if row.get("sha256_12"):
                sums[name] = row["sha256_12"]
    return exps, sums


def check_split(name: str, row: dict) -> None:
    """A row's ``split`` must be the one its repository's rule gives (a
    drawing is not moved between halves by hand)."""
    split, repo = row.get("split"), row.get("repo")
    if split and split not in HALVES:
        raise ValueError(f"{name}: split {split!r} is neither of {', '.join(HALVES)}")
    if split and repo and split != split_of(repo):
        raise ValueError(f"{name}: split {split!r}, but the rule (split_of) puts {repo} in {split_of(repo)!r}")


def sha256_12(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()[:12]


COLUMNS = ("drawing", "half", "outcome", "s", "peak MB", "segments", "regions", "doors found / drawn", "windows",
           "free m2 (parts) / outline m2", "warnings", "notes")
OUTCOMES = ("right", "built", "built wrong", "refused", "bug")


def table(rows: list[Outcome], exps: dict[str, Expected]) -> str:
    """The markdown table of the outcomes and the summary line."""
    def f(v, fmt):
        return "-" if v is None or v != v else format(v, fmt)

    cells = []
    for o in rows:
        e = exps.get(o.name, Expected())
        cells.append((o.name, e.split or "-", o.outcome, f(o.seconds, ".1f"), f(o.peak_mb, ".0f"), f(o.segments, "d"),
                      f(o.regions, "d"), f"{f(o.doors, 'd')} / {f(e.doors_drawn, 'd')}", f(o.windows, "d"),
                      f"{f(o.free_m2, '.0f')} ({f(o.free_parts, 'd')}) / {f(e.outline_m2, '.0f')}",
                      len(o.warnings), "; ".join(n.replace("|", "/") for n in o.notes)))
    seconds = [o.seconds for o in rows if o.seconds == o.seconds]
    peaks = [o.peak_mb for o in rows if o.peak_mb == o.peak_mb]
    summary = (summary_line(rows) + f"; slowest {max(seconds, default=0):.1f} s, largest {max(peaks, default=0):.0f} MB")
    halves = [summary_line([o for o in rows if exps.get(o.name, Expected()).split == h], h) for h in HALVES]
    halves = [ln for ln in halves if not ln.startswith("0 ")]
    return markdown_table(COLUMNS, cells) + "\n\n" + "\n\n".join([*halves, summary])


def summary_line(rows: list[Outcome], half: str | None = None) -> str:
    """``N drawings (half): a right (p %), b built, ...``: each outcome counted."""
    counts = {k: sum(o.outcome == k for o in rows) for k in OUTCOMES}
    share = f" ({100 * counts['right'] / len(rows):.0f} %)" if rows else ""
    where = f" ({half})" if half else " (all)"
    return (f"{len(rows)} drawings{where}: " + ", ".join(
        f"{counts[k]} {k}" + (share if k == "right" else "") for k in OUTCOMES))


def check_files(plans: list[Path], sums: dict[str, str]) -> None:
    """Warn about drawings whose SHA-256 differs from the manifest's
    ``sha256_12`` (another version of the file than the one measured)."""
    for plan in plans:
        want = sums.get(plan.stem)
        if want and sha256_12(plan) != want:
            print(f"warning: {plan.name}: SHA-256 {sha256_12(plan)}..., the manifest says {want}...: "
                  f"another version of the drawing", file=sys.stderr)


def run(args) -> int:
    manifest = args.manifest or args.folder / "manifest.tsv"
    try:
        exps, sums = read_manifest(manifest) if manifest.exists() else ({}, {})
    except ValueError as exc:
        print(f"bench_drawings: error: {manifest}: {exc}", file=sys.stderr)
        return 2
    plans = sorted(p for p in args.folder.iterdir() if p.suffix.lower() in PLAN_SUFFIXES)
    plans = [p for p in plans if not args.only or any(o in p.stem for o in args.only)]
    if args.half:
        plans = [p for p in plans if exps.get(p.stem, Expected()).split == args.half]
    check_files(plans, sums)
    rows = []
    for i, plan in enumerate(plans, 1):
        print(f"[{i}/{len(plans)}] building {plan.name} ...", file=sys.stderr, flush=True)
        rows.append(bench_one(plan, exps.get(plan.stem, Expected()), args.timeout, args.previews))
    print(table(rows, exps))
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", nargs="?", type=Path, help="folder of drawings")
    ap.add_argument("only", nargs="*", help="only drawings whose name holds one of these")
    ap.add_argument("--manifest", type=Path, help="what a person sees in each drawing (default DIR/manifest.tsv)")
    ap.add_argument("--previews", type=Path, metavar="DIR", help="write a preview PNG per drawing here")
    ap.add_argument("--half", choices=HALVES, help="only the drawings of this half of the manifest's split")
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds a drawing may take (default 600)")
    add_report_option(ap)
    ap.add_argument("--child-build", nargs=2, help=argparse.SUPPRESS)
    ap.add_argument("--child-scene", help=argparse.SUPPRESS)
    args = ap.parse_intermixed_args(argv)
    if args.child_build:
        print(json.dumps(child_build(*args.child_build)))
        return 0
    if args.child_scene:
        print(json.dumps(child_scene(args.child_scene)))
        return 0
    if args.folder is None or not args.folder.is_dir():
        ap.error("give the folder of drawings")
    return reported(args.report, lambda: run(args), __file__, argv)


if __name__ == "__main__":
    raise SystemExit(main())
