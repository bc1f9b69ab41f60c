"""Matplotlib without a display, and PNG files written atomically (ssw.h5io conventions).

Every figure of the study goes through :func:`pyplot` (the non-interactive Agg backend, so
rules run on cluster nodes without X) and :func:`save_png` (temporary file + rename, so an
interrupted run never leaves a PNG that looks complete).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ssw.h5io import atomic_path


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the Agg backend (imported lazily: matplotlib is slow to load).

    Returns
    -------
    module
        ``matplotlib.pyplot``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_png(fig: Any, path: str | Path, *, dpi: int = 130, **savefig_kw: Any) -> None:
    """Write ``fig`` to ``path`` as PNG atomically, then close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (closed afterwards, also on error).
    path : str or Path
        The PNG file.
    dpi : int
        Dots per inch.
    **savefig_kw : Any
        Further arguments of ``Figure.savefig``.
    """
    import matplotlib.pyplot as plt

    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", dpi=dpi, **savefig_kw)
    finally:
        plt.close(fig)
