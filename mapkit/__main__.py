from mapkit.cli import main

raise SystemExit(main())
