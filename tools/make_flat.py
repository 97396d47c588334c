#!/usr/bin/env python3
"""Draw the bundled example plan ``maps/flat.dxf`` (a two-bedroom flat, drawn
as an architect's CAD file is: :mod:`mapkit_harness.plans.flat_dxf` says how).

    python tools/make_flat.py [--out maps/flat.dxf]
"""

from __future__ import annotations

import argparse

from mapkit_harness.plans.flat_dxf import DEFAULT_OUT, write


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=str(DEFAULT_OUT),
                        help="output DXF path (default: maps/flat.dxf)")
    args = parser.parse_args(argv)
    path = write(args.out)
    print(f"wrote {path} ({path.stat().st_size // 1024} KB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
