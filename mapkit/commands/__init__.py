"""One module per ``mapkit`` subcommand.

Each module defines ``HELP`` (one line), ``add_arguments(parser)`` and
``run(args) -> int``. Modules import their heavy dependencies inside
``run`` so that ``mapkit --help`` stays instant. The CLI discovers them.
"""
