"""The README's and the docs' examples run as written from a fresh clone and leave it clean.

Every line of README.md and of docs/*.md (:data:`DOCUMENTS`) inside an
indented block that starts with ``$ `` is a runnable example; the indented
lines under it, up to the next ``$ `` line or the end of the block, are the
output it shows. Command lines without ``$ `` (the test command, a server,
data one downloads, a build of minutes, a file not in the repository) are
shown, not run. The benchmark pages (docs/benchmarks/) are records of a run
at a commit, not examples.

The examples run in the README's order, as a newcomer would type them, in a
copy of the repository's tracked files (a fresh clone: a git repository of
its own, so ``git status`` can be asked). Examples that share no file under
``out/`` do not depend on one another, so they run as separate chains
(:func:`example_chains`), each in its own clone with ``out/`` made (the
README's first command makes it), and the chains run in parallel. ``.venv/bin/X`` stands for the
environment running this test (in CI that *is* ``.venv``); in the first
command, the steps that make the environment (``python3 -m venv .venv``,
``.venv/bin/pip install ...``) are left out, since CI's set-up has made it.
The docs' pages assume the environment is active (``mapkit``, ``matcher``,
``python``): its bin directory comes first on PATH.

Each example must exit 0 and print what the README shows: the shown lines in
order, ``...`` standing for lines left out, with the figures that depend on
the machine's speed (stage seconds, ``time ms``) masked. After all of them,
``git status`` must show nothing: everything written went under ``out/``,
which git ignores.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
#: The pages whose ``$ `` examples run: the README, then the docs' pages.
DOCUMENTS = [README, *sorted((ROOT / "docs").glob("*.md"))]
PROMPT = "$ "
INDENT = "    "
SKIPPED_OUTPUT = "..."
# Steps of the first command that make the environment this test already runs in.
ENVIRONMENT_STEPS = (re.compile(r"^python3 -m venv \.venv$"), re.compile(r"^\.venv/bin/pip install "))


@dataclass
class Example:
    command: str
    shown: list[str] = field(default_factory=list)
    page: Path = README


def readme_examples(text: str, page: Path = README) -> list[Example]:
    """The ``$ `` lines of the README's indented blocks, each with the output shown under it."""
    examples: list[Example] = []
    current = None
    for line in text.splitlines():
        if not line.startswith(INDENT):
            current = None  # a blank or unindented line ends the block
            continue
        body = line[len(INDENT):]
        if body.startswith(PROMPT):
            current = Example(body[len(PROMPT):].strip(), page=page)
            examples.append(current)
        elif current is not None:
            current.shown.append(body.rstrip())
    return examples


def out_files(command: str) -> set[str]:
    """What ``command`` names under ``out/``: the first name after ``out/``
    (``out/frame/lines.json`` -> ``frame``)."""
    return set(re.findall(r"(?<![\w/.])out/([\w.-]+)", command))


def example_chains(examples: list[Example]) -> list[list[Example]]:
    """The examples grouped into chains that share files under ``out/``
    (one writes what another reads), each in the README's order; the chains
    in the order of their first example."""
    owner: dict[str, int] = {}  # out/ name -> chain index
    chains: list[list[Example]] = []
    for example in examples:
        joined = sorted({owner[f] for f in out_files(example.command) if f in owner})
        if not joined:
            chains.append([])
            joined = [len(chains) - 1]
        keep = joined[0]
        for other in reversed(joined[1:]):  # a command that reads two chains' files joins them
            chains[keep] += chains[other]
            chains[other] = []
        chains[keep].append(example)
        for f in out_files(example.command):
            owner[f] = keep
        for f, c in owner.items():
            if c in joined:
                owner[f] = keep
    order = {id(e): i for i, e in enumerate(examples)}
    return [sorted(c, key=lambda e: order[id(e)]) for c in chains if c]


def without_environment_steps(command: str) -> str:
    steps = [s.strip() for s in command.split(" && ")]
    kept = [s for s in steps if not any(p.search(s) for p in ENVIRONMENT_STEPS)]
    return " && ".join(kept)


def as_typed_anywhere(command: str) -> str:
    """The command as the docs' pages type it: ``.venv/bin/mapkit`` and
    ``mapkit`` (the environment active) are the same program."""
    return re.sub(r"(?<![\w/.])\.venv/bin/", "", command)


def with_this_environment(command: str) -> str:
    """``.venv/bin/X`` -> the bin directory of the interpreter running the tests."""
    bin_dir = Path(sys.executable).parent
    return re.sub(r"(?<![\w/.])\.venv/bin/", f"{bin_dir}/", command)


def masked(line: str) -> str:
    """A printed line with the figures that follow the machine's speed masked."""
    line = re.sub(r"\b\d+\.\d+s\b", "#s", line)  # stage seconds: (import 0.34s edges 0.01s ...)
    line = re.sub(r"(time ms: )[^(]*", r"\1# ", line)  # time ms: select 2.3, ..., total 80.1
    return line.rstrip()


def shown_in(shown: list[str], printed: list[str]) -> str | None:
    """None if ``printed`` is what ``shown`` shows, else what differs.

    ``shown`` is cut at its ``...`` lines into runs of lines; each run must
    appear in ``printed`` as consecutive lines, in order; without a leading
    (trailing) ``...`` the first (last) run must start (end) the output.
    """
    printed = [masked(p) for p in printed]
    runs: list[list[str]] = [[]]
    for line in shown:
        if line.strip() == SKIPPED_OUTPUT:
            runs.append([])
        else:
            runs[-1].append(masked(line))
    anchored_start = bool(runs[0])
    anchored_end = bool(runs[-1])
    runs = [r for r in runs if r]
    if not runs:  # nothing shown: nothing printed; only "...": anything
        return None if shown or not printed else f"printed {printed[:3]!r} where the README shows nothing"
    at = 0
    for i, run in enumerate(runs):
        starts = [at] if (i == 0 and anchored_start) else range(at, len(printed) - len(run) + 1)
        found = next((s for s in starts if printed[s:s + len(run)] == run), None)
        if found is None:
            near = printed[at:at + len(run) + 2]
            return f"expected {run!r}\n  from line {at} of the output, got {near!r}"
        at = found + len(run)
    if anchored_end and at != len(printed):
        return f"output goes on after the README's last line: {printed[at:at + 3]!r}"
    return None


def test_readme_marks_its_examples():
    """The README has its runnable examples, the two set-up commands among them as they should be."""
    commands = [e.command for e in readme_examples(README.read_text())]
    assert len(commands) >= 10
    assert commands[0].startswith("python3 -m venv .venv && .venv/bin/pip install -e '.[build]' && ")
    assert "mapkit build maps/flat.dxf -o out/flat.lmap" in commands[0]
    assert "bash tools/setup_and_test.sh" in README.read_text()
    for c in commands:
        # Every program the README runs comes from the venv: nothing relies on an activated shell.
        for step in re.split(r"&&|\|", c):
            program = step.split()[0]
            assert program in ("python3", "mkdir") or program.startswith(".venv/bin/"), c


def test_the_readme_is_an_overview():
    """The README stays an overview (under 350 lines); detail goes in docs/."""
    assert len(README.read_text().splitlines()) < 350


def test_shown_in_reads_the_readme_conventions():
    assert shown_in(["a", "...", "c"], ["a", "b", "c"]) is None
    assert shown_in(["a", "c"], ["a", "b", "c"]) is not None
    assert shown_in(["...", "b"], ["a", "b"]) is None
    assert shown_in(["b", "..."], ["a", "b"]) is not None
    assert shown_in(["x (import 0.34s)"], ["x (import 2.35s)"]) is None
    assert shown_in([], []) is None
    assert shown_in([], ["noise"]) is not None


def fresh_clone(dest: Path) -> Path:
    """The repository's tracked files (as they are in the working tree) in a git repository of their own."""
    names = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True).stdout
    for name in names.decode().split("\0"):
        if name and (ROOT / name).is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, dest / name)
    git = ["git", "-c", "user.name=readme test", "-c", "user.email=readme@test", "-c", "commit.gpgsign=false"]
    subprocess.run(git + ["init", "-q"], cwd=dest, check=True)
    subprocess.run(git + ["add", "-A"], cwd=dest, check=True)
    subprocess.run(git + ["commit", "-q", "-m", "fresh clone"], cwd=dest, check=True)
    return dest


def chain_name(chain: list[Example]) -> str:
    """A test id for a chain: the program and subcommand of its first
    example's first step past the set-up ("mapkit-build", "simulate.py")."""
    steps = [s.split() for s in without_environment_steps(chain[0].command).split(" && ")]
    words = next(w for w in steps if w[0] != "mkdir")
    program = Path(words[0] if Path(words[0]).name != "python" else words[1]).name
    return program if program.endswith(".py") else f"{program}-{words[1]}"


#: Every page's examples in chains, in the pages' order. A page's example
#: that writes under ``out/`` what another page's writes joins that chain:
#: docs/cli.md shows again the README's build and simulated frame, and a
#: command typed the same way on two pages runs once (see the test).
CHAINS = example_chains([e for doc in DOCUMENTS for e in readme_examples(doc.read_text(), doc)])


def chain_id(chain: list[Example]) -> str:
    """``README:mapkit-build``, ``docs/cli:simulate.py``: the first
    example's page and program; a second chain of the same name gets ``-2``."""
    return f"{chain[0].page.relative_to(ROOT).with_suffix('')}:{chain_name(chain)}"


def _unique(ids: list[str]) -> list[str]:
    seen: dict[str, int] = {}
    out = []
    for i in ids:
        seen[i] = seen.get(i, 0) + 1
        out.append(i if seen[i] == 1 else f"{i}-{seen[i]}")
    return out


def test_the_docs_have_runnable_examples():
    """docs/cli.md's examples run (the batch build, an error's exit status,
    a simulated frame localised) and docs/inputs.md's (a plan, a mesh)."""
    pages = {doc.name: sum(e.page == doc for c in CHAINS for e in c) for doc in DOCUMENTS}
    assert pages["cli.md"] >= 8 and pages["inputs.md"] >= 2
    assert any("tests/data/dxf/truncated.dxf" in e.command for c in CHAINS for e in c if e.page.name == "cli.md")


def test_example_chains_follow_the_files_under_out():
    a, b, c, d = (Example(x) for x in ("mkdir -p out && build -o out/m.lmap", "query out/m.lmap",
                                       "sim --out out/frame", "loc --lines out/frame/l.json --map out/m.lmap"))
    e = Example("layers maps/flat.dxf")
    assert example_chains([a, b, c, e]) == [[a, b], [c], [e]]
    assert example_chains([a, c, d, b]) == [[a, c, d, b]]


@pytest.fixture(scope="session")  # not module: the chains must stay free to run on different workers
def clean_clone(tmp_path_factory):
    """A fresh clone, made once per process: each chain runs in a copy of it."""
    return fresh_clone(tmp_path_factory.mktemp("readme-clone"))


@pytest.mark.slow  # the examples, one chain each: builds maps, simulates frames, tracks a run
@pytest.mark.parametrize("chain", CHAINS, ids=_unique([chain_id(c) for c in CHAINS]))
def test_examples_run_as_written(chain, clean_clone, tmp_path):
    """Each example of the chain runs in order in one clone. A command
    already run in this chain (typed the same on another page) is not run
    again: its output is compared with what this page shows. The examples
    are deterministic, so a second run would write the same files."""
    repo = shutil.copytree(clean_clone, tmp_path / "clone", symlinks=True)
    (repo / "out").mkdir()
    bin_dir = str(Path(sys.executable).parent)  # the docs' bare mapkit, matcher, python
    env = dict(os.environ, PYTHONUNBUFFERED="1", PYTHONPATH=str(repo), MPLBACKEND="Agg",
               PATH=os.pathsep.join([bin_dir, os.environ.get("PATH", "")]))
    env.pop("PYTHONSTARTUP", None)
    already: dict[str, list[str]] = {}  # command as typed anywhere -> what it printed
    for example in chain:
        page = example.page.relative_to(ROOT)
        typed = as_typed_anywhere(without_environment_steps(example.command))
        if typed not in already:
            command = with_this_environment(without_environment_steps(example.command))
            done = subprocess.run(["bash", "-c", command], cwd=repo, env=env, capture_output=True, text=True,
                                  timeout=600)
            assert done.returncode == 0, f"{page}: $ {example.command}\nexit {done.returncode}\n{done.stdout}{done.stderr}"
            # stderr first: the CLIs' warnings come before their summary line (stdout is unbuffered).
            already[typed] = (done.stderr + done.stdout).splitlines()
        printed = already[typed]
        differs = shown_in(example.shown, printed)
        assert differs is None, f"{page}: $ {example.command}\n{differs}"
    status = subprocess.run(["git", "status", "--porcelain", "--untracked-files=all"], cwd=repo,
                            capture_output=True, text=True, check=True).stdout
    assert status == "", f"the examples of {chain_id(chain)} left files outside out/:\n{status}"
    if (repo / "out" / "flat.lmap").exists():
        assert (repo / "out" / "flat.lmap").read_bytes() == (repo / "maps" / "flat.lmap").read_bytes()
