"""The one place kvrod chooses matplotlib's backend and saves a figure.

Every module that draws calls :func:`pyplot` instead of importing ``matplotlib.pyplot``
itself: outside an interactive session the backend is Agg (no display, no GUI toolkit,
the fastest raster backend); where pyplot was imported already (a notebook, a user's
script) its backend is left alone, so calling kvrod's plotting functions does not break
``plt.show()`` there. :func:`save` writes a figure atomically and closes it.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any


def pyplot() -> Any:
    """``matplotlib.pyplot``, with the Agg backend unless pyplot was imported before."""
    if "matplotlib.pyplot" not in sys.modules:
        import matplotlib

        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(fig: Any, path: Path, **kwargs: Any) -> Path:
    """Save ``fig`` to ``path`` atomically (``runtime.io.atomic.save_figure``; keyword
    arguments go to ``savefig``) and close it, also when saving fails."""
    from runtime.io.atomic import save_figure

    try:
        return save_figure(fig, Path(path), **kwargs)
    finally:
        pyplot().close(fig)
