"""Fuzz families and the campaign: damaged and hostile inputs for every
entry point, each case run under a time and memory bound.

Each family (:mod:`.families`, one module each) draws a case from a
``random.Random`` (``make_case(family, seed, i)`` from
``random.Random(f"{family}:{seed}:{i}")``, so a run is reproducible and any
case can be drawn again by its number):

- :mod:`.dxf`: ``maps/flat.dxf`` and the real plans of ``tests/data`` with
  group code / value lines deleted, swapped, duplicated, numbers replaced by
  huge, NaN, infinite or garbage values, group codes damaged, the file cut
  short; then ``mapkit build`` (mostly), ``preview`` or ``layers``.
- :mod:`.meshes`: every mesh format (OBJ, OFF, ASCII and binary PLY and STL,
  GLB) with the same kind of damage to its text lines or its bytes (flipped
  bits, overwritten floats, counts, truncation); then ``mapkit build``.
- :mod:`.zind`: a ZInD-shaped floor (three rooms, doors, a window, an
  opening, an island) with values made NaN, huge, tiny or of the wrong
  type, keys and items deleted, lists emptied or repeated, values nested
  thousands deep, the text cut short; or floors of random rooms; then
  ``mapkit build`` (mostly) or ``preview``.
- :mod:`.segments`: segments files, CSV (the example map's segments) with
  cells damaged, removed or added, lines or bytes damaged, and JSON (two
  rooms with an outline and walls) damaged as ZInD's; or random segments;
  then ``mapkit build``.
- :mod:`.lmap_files`: ``maps/flat.lmap`` with flipped bits, overwritten
  bytes, cuts and appended bytes, or its chunks re-encoded with valid
  checksums around a damaged payload; then ``mapkit info``, ``view --html``
  and ``export``, and ``mapkit query``, ``info --json`` or ``matcher
  localize``.
- :mod:`.matcher_inputs`: random values for every input of the matcher:
  lines files and arrays of odd shapes and dtypes, camera files (ours,
  OpenCV's, ROS's), priors, ``dt``, ``dyaw``, budgets, images of odd sizes
  and dtypes, and the JSON Lines frame files of ``matcher track``.

The damage itself is :mod:`.mutations`. A map the build families' ``mapkit
build`` writes is then read by the commands that read maps
(``cases.FOLLOW_UPS``: ``mapkit info``, ``info --json``, ``view --html``,
``export``): damage that passes the importer must not trip them either.

Each case must end in a clean one-line error (exit 2 on the command line, an
``InputError`` through the Python API), a falsy result with its reason (exit
1), or a valid result (:mod:`.classify`). Anything else is a failure: a bug
(an internal error, exit 3; an exception escaping; any other exception
through the API, even a one-line ``ValueError``; a crash; an error message
of more than one line) or a run past the bound. :mod:`.run` runs a case in
this process or in a forked child under a time bound and an address-space
limit; :mod:`.campaign` runs many, a few at once; :mod:`.cases` saves a
failing case as a folder (its input files and ``case.json`` with the
commands) and reads it back. ``tools/fuzz.py`` is the command line;
``tests/test_fuzz_*.py`` draw the same cases through hypothesis.
"""
