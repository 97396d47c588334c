"""The package layout docs/architecture.md describes, held by tests: who may
import whom, one documented place for the matcher's thresholds, and
functions short enough to read."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
AUTHORING = ("mapkit", "ezdxf", "trimesh", "shapely", "viser", "ifcopenshell")

#: Module-level numeric constants in matcher/ and linemap/ that are not
#: thresholds, with the reason. Anything else numeric at module level
#: belongs in matcher/tolerances.py.
NOT_THRESHOLDS = {
    ("linemap/lmap.py", "FORMAT_MAJOR"): "the .lmap format's version",
    ("linemap/lmap.py", "FORMAT_MINOR"): "the .lmap format's version",
    ("linemap/lmap.py", "_RAW"): "a chunk codec id of the format",
    ("linemap/lmap.py", "COORD_QUANTUM_M"): "the format's storage unit for outline vertices",
    ("linemap/lmap.py", "MAX_INFLATION"): "the loader's resource bounds on hostile files",
    ("linemap/lmap.py", "RAW_FLOOR_BYTES"): "the loader's resource bounds on hostile files",
    ("linemap/lmap.py", "MAX_LIST_ENTRIES_PER_BYTE"): "the loader's resource bounds on hostile files",
    ("linemap/lmap.py", "MAX_META_BYTES"): "the loader's resource bounds on hostile files",
    ("linemap/lmap.py", "MAX_META_DEPTH"): "the loader's resource bounds on hostile files",
    ("linemap/lmap.py", "MAX_EXTENT_M"): "the loader's resource bounds on hostile files",
    ("linemap/building.py", "MANIFEST_VERSION"): "the building manifest's format version",
    ("linemap/camera_files.py", "_MAX_CALIBRATION_CHARS"): "input size limits of a file parser",
    ("linemap/camera_files.py", "_MAX_CALIBRATION_DEPTH"): "input size limits of a file parser",
    ("linemap/safe_yaml.py", "MAX_CHARS"): "input size limits of a file parser",
    ("linemap/safe_yaml.py", "MAX_DEPTH"): "input size limits of a file parser",
    ("linemap/rig_files.py", "RIGID_TOLERANCE"): "a rig file's check of its input (is a transform rigid)",
    ("linemap/rig_files.py", "MAX_PITCH_DEG"): "a rig file's check of its input (the camera files' pitch bound)",
    ("linemap/rig_files.py", "_KALIBR_DISTORTIONS"): "the coefficient counts of a file format",
    ("linemap/atomic.py", "STALE_TEMP_S"): "file housekeeping (a killed write's leftovers), not a tolerance of the method",
    ("matcher/panorama.py", "_KEPT_VIEW_MAPS"): "a cache's size (memory), not a tolerance of the method",
    ("matcher/cli.py", "EXIT_OK"): "exit codes",
    ("linemap/errors.py", "EXIT_BUG"): "exit codes",
    ("matcher/tracking/route_plot.py", "_WALL"): "colours of a picture",
    ("matcher/tracking/route_plot.py", "_LOST"): "colours of a picture",
    ("matcher/tracking/route_plot.py", "_JUMP_M"): "where a picture breaks its line",
    ("matcher/search/tree/constraints.py", "_NOISE_CASES"): "the signs of the noise model's extreme cases",
    ("matcher/search/tree/constraints.py", "_PAIR_BLOCK"): "a work size bounding temporaries, not a tolerance",
    ("matcher/search/tree/tree.py", "_BIT_LEVELS"): "the bits of an int64, sign spared",
}


def _modules_loaded_by(statement: str) -> set[str]:
    """Top-level package names in sys.modules after ``statement`` in a
    fresh interpreter."""
    code = f"import sys; {statement}; print(' '.join(sorted({{m.split('.')[0] for m in sys.modules}})))"
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    return set(out.stdout.split())


def _python_files(package: str):
    return sorted((ROOT / package).rglob("*.py"))


def _imported_packages(path: Path) -> set[str]:
    """Top-level names of every module ``path`` imports, anywhere in it."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module.split(".")[0])
    return names


def test_import_matcher_loads_no_authoring_stack():
    loaded = _modules_loaded_by("import matcher, matcher.cli")
    assert "linemap" in loaded
    assert not loaded & set(AUTHORING), sorted(loaded & set(AUTHORING))
    assert not loaded & {"dask", "distributed"}  # the batch builder's, never the runtime's
    assert "yaml" not in loaded  # PyYAML is loaded when a YAML rig file is read, not before


def test_import_linemap_loads_neither_half():
    loaded = _modules_loaded_by("import linemap, linemap.geometry, linemap.regions, linemap.rig_files")
    assert not loaded & {"mapkit", "matcher", "scipy", "cv2", "yaml", *AUTHORING}


def test_pyyaml_is_imported_by_the_yaml_reader_alone():
    """The runtime's one dependency beyond numpy, scipy and OpenCV: PyYAML,
    for the YAML rig files (Kalibr's), in linemap/safe_yaml.py only, which
    linemap/rig_files.py imports when it reads one."""
    users = sorted(str(p.relative_to(ROOT)) for package in ("linemap", "matcher")
                   for p in _python_files(package) if "yaml" in _imported_packages(p))
    assert users == ["linemap/safe_yaml.py"]


#: The test and benchmark harness: the shipped packages never import it.
HARNESS = "mapkit_harness"


@pytest.mark.parametrize("package,forbidden", [
    # (linemap.camera imports cv2 inside the one method that undistorts: loading stays numpy-only.)
    ("linemap", {"mapkit", "matcher", "scipy", "ezdxf", "trimesh", "shapely", "viser", HARNESS}),
    ("matcher", {*AUTHORING, HARNESS, "dask", "distributed"}),
    ("mapkit", {"matcher", HARNESS}),
])
def test_packages_import_only_what_they_may(package, forbidden):
    bad = {str(p.relative_to(ROOT)): sorted(_imported_packages(p) & forbidden) for p in _python_files(package)}
    assert not {k: v for k, v in bad.items() if v}


def test_mapkit_loads_no_matcher():
    loaded = _modules_loaded_by("import mapkit, mapkit.cli, mapkit.pipeline, mapkit.view")
    assert "matcher" not in loaded


def test_tests_and_tools_edit_no_import_path():
    """Tests and tools import the harness by name (it is installed with the
    project); tools/bench_ab.py runs a revision in a worker process whose
    folder and PYTHONPATH put that revision first. Code written into a
    string for another process counts too: ``sys.path`` is looked for in
    the text, not only in the syntax tree."""
    edits = []
    for folder in ("tests", "tools"):
        for p in _python_files(folder):
            for lineno, line in enumerate(p.read_text().splitlines(), 1):
                if "sys.path" in line.split("#")[0] and p.name != "test_layout.py":
                    edits.append(f"{p.relative_to(ROOT)}:{lineno}")
    assert not edits


def test_no_tool_imports_a_test():
    tests = {p.stem for p in _python_files("tests")}
    bad = {str(p.relative_to(ROOT)): sorted(_imported_packages(p) & tests) for p in _python_files("tools")}
    assert not {k: v for k, v in bad.items() if v}


def test_old_import_paths_still_work():
    from linemap.camera import Camera
    from linemap.lmap import load_map
    from mapkit.lmap import load_map as old_load_map
    from matcher.camera import Camera as OldCamera
    from matcher.pipeline import localize, localize_global

    import matcher

    assert old_load_map is load_map and OldCamera is Camera
    assert localize is matcher.localize and localize_global is matcher.localize_global


#: The longest function and the longest parameter list the code base may have.
MAX_FUNCTION_LINES = 80
MAX_PARAMETERS = 8

SHAPED_PACKAGES = ("linemap", "mapkit", "matcher")


def _functions(package: str):
    """(path relative to the root, function node) of every function and
    method of ``package``, nested ones included."""
    for p in _python_files(package):
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                yield str(p.relative_to(ROOT)), node


def _lines(node) -> int:
    return node.end_lineno - node.lineno + 1


def _parameters(node) -> int:
    """Positional and keyword-only parameters, ``self`` and ``cls`` and
    ``*args``/``**kwargs`` not counted."""
    a = node.args
    return sum(x.arg not in ("self", "cls") for x in a.posonlyargs + a.args + a.kwonlyargs)


@pytest.mark.parametrize("package", SHAPED_PACKAGES)
def test_no_function_over_80_lines(package):
    long = [f"{rel}:{node.lineno} {node.name} ({_lines(node)} lines)" for rel, node in _functions(package)
            if _lines(node) > MAX_FUNCTION_LINES]
    assert not long


@pytest.mark.parametrize("package", SHAPED_PACKAGES)
def test_no_function_over_8_parameters(package):
    wide = [f"{rel}:{node.lineno} {node.name} ({_parameters(node)} parameters)" for rel, node in _functions(package)
            if _parameters(node) > MAX_PARAMETERS]
    assert not wide


def _numeric(node: ast.AST) -> bool:
    return any(isinstance(n, ast.Constant) and isinstance(n.value, (int, float)) and not isinstance(n.value, bool)
               for n in ast.walk(node))


@pytest.mark.parametrize("package", ["matcher", "linemap"])
def test_no_module_level_threshold_outside_tolerances(package):
    """Every numeric constant at module level lives in matcher/tolerances.py
    (as a field of Tolerances or of one of its constants classes), or is
    named in NOT_THRESHOLDS."""
    found = []
    for p in _python_files(package):
        rel = str(p.relative_to(ROOT))
        if rel == "matcher/tolerances.py":
            continue
        for node in ast.parse(p.read_text()).body:
            if isinstance(node, (ast.Assign, ast.AnnAssign)) and node.value is not None and _numeric(node.value):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                names = [n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)]
                if not any((rel, name) in NOT_THRESHOLDS for name in names):
                    found.append(f"{rel}:{node.lineno} {names}")
    assert not found


def test_builder_geometric_zeros_live_in_tolerances():
    """No float literal of magnitude under 1e-5 in mapkit/ outside
    mapkit/tolerances.py: float-noise zeros are fields of its
    ``GeometricZeros`` (``ZERO``), one per meaning."""
    found = []
    for p in _python_files("mapkit"):
        rel = str(p.relative_to(ROOT))
        if rel == "mapkit/tolerances.py":
            continue
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.Constant) and isinstance(node.value, float) and 0 < abs(node.value) < 1e-5:
                found.append(f"{rel}:{node.lineno} {node.value!r}")
    assert not found


def test_tolerances_document_every_field():
    """Each field of every class in matcher/tolerances.py (Tolerances, each
    consumer's constants class, LineDetection, Tracking) has a ``#:`` comment."""
    src = (ROOT / "matcher" / "tolerances.py").read_text().splitlines()
    tree = ast.parse("\n".join(src))
    missing = []
    for cls in (n for n in tree.body if isinstance(n, ast.ClassDef)):
        for i, node in enumerate(cls.body):
            if isinstance(node, ast.AnnAssign):
                above = src[node.lineno - 2].strip()
                # A field may share the comment of the one above it (a pair such as min and max).
                prev = cls.body[i - 1] if i else None
                shares = isinstance(prev, ast.AnnAssign) and prev.end_lineno == node.lineno - 1
                if not (above.startswith("#:") or shares):
                    missing.append(f"{cls.name}.{node.target.id}")
    assert not missing


def test_every_constants_class_is_held_by_tolerances_and_names_are_unique():
    """Each ``*Constants`` class of matcher/tolerances.py is a field of
    Tolerances (so a user reaches it, and the type check covers it), and no
    two share a field name (each constant has one home: constants_owner)."""
    from dataclasses import fields

    import matcher.tolerances as t

    tree = ast.parse((ROOT / "matcher" / "tolerances.py").read_text())
    defined = {n.name for n in tree.body if isinstance(n, ast.ClassDef) and n.name.endswith("Constants")
               and not n.name.startswith("_")}
    held = {f.name: f.type for f in fields(t.Tolerances) if f.name in t.CONSTANTS}
    assert {c.__name__ for c in t.CONSTANTS.values()} == defined == set(held.values())
    names = [f.name for c in t.CONSTANTS.values() for f in fields(c)]
    assert len(names) == len(set(names))
    assert all(hasattr(getattr(t.DEFAULT, t.constants_owner(n)), n) for n in names)
