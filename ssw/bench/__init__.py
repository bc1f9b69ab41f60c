"""Benchmarks behind ``ssw bench``; one module per kind, each with ``register``."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any


def best_time(fn: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    """Fastest wall time (s) of ``repeat`` calls of ``fn`` (at least one) and the last
    result: on a shared machine, noise only adds time.

    Parameters
    ----------
    fn : callable
        The call to time, without arguments.
    repeat : int
        Calls (at least one).

    Returns
    -------
    seconds : float
        The fastest wall time, s.
    result : object
        The last call's result.
    """
    best, out = float("inf"), None
    for _ in range(max(1, int(repeat))):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out
