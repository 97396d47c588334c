"""Open a DXF file: strict reader first, ezdxf's recover mode for damaged files."""

from __future__ import annotations

import logging
from pathlib import Path

import ezdxf
from ezdxf import recover

from mapkit.errors import MapkitError

log = logging.getLogger("mapkit")

#: Errors ezdxf raises on files it cannot parse. It has no common base class
#: for them (a truncated header ends in a bare StopIteration), and the input
#: is a user's file, so any parser failure is a user-fixable problem.
_READ_ERRORS = (Exception,)


def read_dxf(path: Path) -> tuple[object, list[str]]:
    """The ezdxf document of ``path`` and warnings about its condition.

    Raises :class:`MapkitError` when the file is not DXF or nothing usable
    survives recovery.
    """
    warnings: list[str] = []
    _check_looks_like_dxf(path)
    try:
        doc = ezdxf.readfile(path)
    except _READ_ERRORS as strict_error:
        try:
            doc, auditor = recover.readfile(path)
        except _READ_ERRORS as exc:
            raise MapkitError(
                f"{path.name}: the file is damaged or truncated and could not be recovered "
                f"({_short(exc)}); re-export it from the CAD program"
            ) from None
        fixed = len(auditor.fixes)
        errors = len(auditor.errors)
        warnings.append(
            f"{path.name} is damaged ({_short(strict_error)}); recovered what was readable "
            f"({fixed} fixes, {errors} unrecoverable errors): check the preview"
        )
    warnings += _drop_unknown_entities(doc, path)
    if not _has_entities(doc):
        if warnings:
            raise MapkitError(
                f"{path.name}: the file is damaged or truncated and no drawing survived recovery; "
                f"re-export it from the CAD program"
            )
        raise MapkitError(f"{path.name}: the drawing is empty (no entities in model space); check the file")
    return doc, warnings


def model_space(doc):
    """The entities of the drawing's model space (an ezdxf layout to iterate).

    Some files (an AutoCAD 2013 drawing written by other software) name the
    model-space layout something other than "Model" while its block
    ``*Model_Space`` holds the drawing; ezdxf's ``modelspace()`` then raises
    KeyError, in strict and in recover mode alike. The block is the model
    space whatever the layout is called."""
    try:
        return doc.modelspace()
    except KeyError:
        block = doc.blocks.get("*Model_Space")
        if block is None:
            raise MapkitError("the file has no model space (neither a 'Model' layout nor a *Model_Space block); "
                              "re-export it from the CAD program") from None
        return block


def _drop_unknown_entities(doc, path: Path) -> list[str]:
    """Remove model-space entities that have no layer attribute at all: a
    damaged group code makes a value read as an entity type ("9800.0"),
    which ezdxf keeps as raw tags. Returns a warning naming them, or []."""
    msp = model_space(doc)
    try:
        bad = [e for e in msp if not e.dxf.is_supported("layer")]
    except _READ_ERRORS:
        return []
    for e in bad:
        msp.delete_entity(e)
    if not bad:
        return []
    names = ", ".join(sorted({repr(e.dxftype())[:40] for e in bad})[:5])
    return [f"{path.name}: left out {len(bad)} entities of no known type ({names}): the file is damaged; "
            f"check the preview"]


def _check_looks_like_dxf(path: Path) -> None:
    """Reject files that are obviously not DXF before ezdxf tries hard to parse them."""
    with open(path, "rb") as f:
        head = f.read(4096)
    if head.startswith(b"AutoCAD Binary DXF"):
        return
    if not head.strip():
        raise MapkitError(f"{path.name}: the file is empty; give a DXF plan")
    text = head.decode("latin-1")
    lines = [ln.strip() for ln in text.splitlines()[:64]]
    # An ASCII DXF is group-code/value pairs and starts with "0" / "SECTION"
    # (possibly after 999 comments).
    if "SECTION" not in lines and "0" not in lines[:4]:
        raise MapkitError(f"{path.name}: not a DXF file (no DXF SECTION header); give a DXF plan")


def _has_entities(doc) -> bool:
    try:
        return next(iter(model_space(doc)), None) is not None
    except _READ_ERRORS:
        return False


def _short(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text[:120] if text else type(exc).__name__
