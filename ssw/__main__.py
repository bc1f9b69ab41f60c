"""``python -m ssw``: the ``ssw`` command line, run in a fork of the workflow's warm process
when one serves it (:mod:`ssw.warmstart`), else here."""

import os

if os.environ.get("SSW_WARM_SOCKET"):  # ssw.warmstart.SOCKET_ENV, read before importing it
    from ssw.warmstart import request

    _status = request()
    if _status is not None:
        raise SystemExit(_status)

from ssw.cli import main

raise SystemExit(main())
