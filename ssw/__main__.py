"""``python -m ssw``: the ``ssw`` command line."""

from ssw.cli import main

raise SystemExit(main())
