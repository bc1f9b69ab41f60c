"""Progress bars for long command-line work (sweeps, calibration scans, contact batches,
surveys), over tqdm, on stderr.

Shown only to a person: on when stderr is a terminal, off under ``--json``, when stderr is
redirected (Snakemake logs, pipes, CI, pytest), or when ``SSW_PROGRESS=0``. Library
functions never draw bars themselves: they take an optional callback (``on_progress`` or
an iterable wrapper) and the command passes one of these.

API::

    from ssw.progress import progress, progress_bar, set_enabled

    for scene in progress(scenes, desc="contact", unit="scene"):   # an iterable
        ...
    with progress_bar(total=n_points, desc="TOF sweep", unit="pt") as update:
        run_sweep(..., on_progress=update)                          # a callback: update(k)
    set_enabled(False)   # process-wide off (ssw.cli.main does it under --json)

``enabled=`` on either call overrides the automatic choice (True forces a bar even off a
terminal, e.g. to test it; False hides it).
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Callable, Iterable, Iterator
from typing import Any, TypeVar

T = TypeVar("T")
#: Environment switch: ``SSW_PROGRESS=0`` hides every bar, ``1`` shows them off a terminal.
ENV = "SSW_PROGRESS"
_override: bool | None = None


def set_enabled(on: bool | None) -> None:
    """Turn bars on or off for the whole process (``None``: back to automatic).

    Parameters
    ----------
    on : bool or None
        True: draw bars; False: none; None: automatic.
    """
    global _override
    _override = on


def is_enabled(enabled: bool | None = None) -> bool:
    """Whether a bar is drawn: ``enabled`` if given, else the process-wide setting, else
    ``SSW_PROGRESS``, else whether stderr is a terminal.

    Parameters
    ----------
    enabled : bool or None
        The caller's choice (None: no choice).

    Returns
    -------
    bool
        Whether to draw.
    """
    if enabled is not None:
        return bool(enabled)
    if _override is not None:
        return _override
    env = os.environ.get(ENV)
    if env is not None and env.strip() != "":
        return env.strip().lower() not in ("0", "false", "no", "off")
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):  # closed or replaced stream
        return False


def _bar(total: int | None, desc: str | None, unit: str, enabled: bool | None,
         iterable: Iterable[Any] | None = None) -> Any:
    from tqdm import tqdm

    return tqdm(iterable, total=total, desc=desc, unit=unit, file=sys.stderr, leave=False,
                dynamic_ncols=True, disable=not is_enabled(enabled), mininterval=0.2)


def progress(iterable: Iterable[T], *, total: int | None = None, desc: str | None = None,
             unit: str = "it", enabled: bool | None = None) -> Iterator[T]:
    """Yield the items of ``iterable``, drawing a bar on stderr when enabled.

    ``total`` defaults to ``len(iterable)`` when it has one.

    Parameters
    ----------
    iterable : iterable
        The items.
    total : int or None
        The number of items (None: ``len(iterable)`` when it has one).
    desc : str or None
        The bar's label.
    unit : str
        The unit shown after the count.
    enabled : bool or None
        Draw the bar (None: :func:`is_enabled`).

    Yields
    ------
    object
        The items of ``iterable``, in order.
    """
    if total is None and hasattr(iterable, "__len__"):
        total = len(iterable)  # type: ignore[arg-type]
    if not is_enabled(enabled):
        yield from iterable
        return
    with _bar(total, desc, unit, True, iterable) as bar:
        yield from bar


@contextlib.contextmanager
def progress_bar(total: int | None = None, *, desc: str | None = None, unit: str = "it",
                 enabled: bool | None = None) -> Iterator[Callable[..., None]]:
    """A bar driven by a callback: ``update(n=1, **info)`` advances it by ``n`` and shows
    ``info`` (short key=value pairs) beside it. A no-op callback when disabled.

    Parameters
    ----------
    total : int or None
        The count at completion (None: unknown).
    desc : str or None
        The bar's label.
    unit : str
        The unit shown after the count.
    enabled : bool or None
        Draw the bar (None: :func:`is_enabled`).

    Yields
    ------
    callable
        ``update(n=1, **info)``.
    """
    if not is_enabled(enabled):
        yield lambda n=1, **info: None
        return
    with _bar(total, desc, unit, True) as bar:

        def update(n: int = 1, **info: Any) -> None:
            if info:
                bar.set_postfix(info, refresh=False)
            bar.update(n)

        yield update
