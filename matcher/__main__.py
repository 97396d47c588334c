"""``python -m matcher``: the matcher command line."""

from matcher.cli import main

raise SystemExit(main())
