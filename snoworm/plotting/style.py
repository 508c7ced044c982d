"""The figures' style and plumbing: colour-blind-safe colours, line styles and markers, axis
labels in words with units, figures without pyplot, atomic saving.

The library never touches the matplotlib backend or pyplot's global state: figures are
:class:`matplotlib.figure.Figure` objects created directly (or the user's own, through ``ax=``
or ``fig=``) and saved through a canvas chosen by the file format.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..infra.folders import atomic_path

__all__ = ["COLOURS", "LINESTYLES", "MARKERS", "PLOT_FORMATS", "DPI", "series_style", "new_figure", "save",
           "quantity_label", "force_text", "legend_outside"]

#: Okabe & Ito (2008) colour-blind-safe palette (yellow last: it is faint on white).
COLOURS = ("#0072B2", "#E69F00", "#009E73", "#D55E00", "#CC79A7", "#56B4E9", "#000000", "#F0E442")
#: Line styles and markers cycled with the colours, so traces that coincide stay distinguishable
#: (and the figure reads in black and white).
LINESTYLES = ("-", "--", "-.", ":", (0, (5, 1, 1, 1, 1, 1)), (0, (1, 2)))
MARKERS = ("o", "s", "^", "v", "D", "P", "X", "*")
#: File formats of the saved figures (``--plot-format``).
PLOT_FORMATS = ("png", "pdf", "svg")
#: Resolution of raster (PNG) figures [dots per inch].
DPI = 200


def series_style(k: int, n_points: int = 0) -> dict:
    """Line keyword arguments of the ``k``-th series: colour, line style, a sparse marker.

    Markers are placed at ``n_points // 12``-sample intervals, shifted per series so that the
    markers of coinciding traces do not hide one another.
    """
    every = max(n_points // 12, 1)
    return {"color": COLOURS[k % len(COLOURS)], "ls": LINESTYLES[k % len(LINESTYLES)],
            "marker": MARKERS[k % len(MARKERS)], "ms": 4,
            "markevery": (int((k * every) // 7) % every, every) if n_points else None}


def new_figure(ax=None, fig=None, nrows=1, ncols=1, figsize=(8, 5), **subplot_kw):
    """(figure, 2-D array of axes) to draw on.

    ``ax``: the user's axes (one, or a sequence of ``nrows * ncols``); ``fig``: the user's figure,
    in which the axes are created; neither: a new :class:`~matplotlib.figure.Figure` (constrained
    layout, no pyplot).
    """
    if ax is not None:
        axes = np.atleast_1d(np.asarray(ax, dtype=object)).reshape(-1)
        if axes.size != nrows * ncols:
            raise ValueError(f"this plot draws {nrows * ncols} panel(s): pass as many axes (got {axes.size}), "
                             "or pass fig= instead")
        return axes[0].get_figure(), axes.reshape(nrows, ncols)
    if fig is None:
        fig = Figure(figsize=figsize, layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False, **subplot_kw)
    return fig, axes


def save(fig, path, fmt: str | None = None, dpi: int = DPI) -> Path:
    """Save ``fig`` atomically to ``path`` (format from ``fmt`` or the suffix; PNG at ``dpi``).

    Returns the path written.  The figure stays usable (nothing is closed: there is no pyplot
    state to release).
    """
    path = Path(path)
    fmt = (fmt or path.suffix.lstrip(".") or "png").lower()
    if fmt not in PLOT_FORMATS:
        raise ValueError(f"plot format {fmt!r}: expected one of {', '.join(PLOT_FORMATS)}")
    if path.suffix.lstrip(".").lower() != fmt:
        path = path.with_suffix("." + fmt)
    with atomic_path(path) as tmp:
        # svg: no hash salt, so the same figure gives the same file
        meta = {"Date": None} if fmt in ("pdf", "svg") else None
        fig.savefig(tmp, dpi=dpi, format=fmt, metadata=meta)
    return path


#: Words and units of the scenario keys and quantities the figures show.
_LABELS = {
    "terrain.xt": "terrain coefficient X_t", "xt": "terrain coefficient X_t",
    "tow.force_N": "tow force [N]", "tow_N": "tow force [N]",
    "vehicle.segments": "number of segments",
    "mean_speed_mps": "mean speed [m/s]", "mean_slip": "mean slip (2nd half)", "max_slip": "max slip",
    "max_link_force_N": "max |link force| [N]", "energy_per_m_J": "energy per metre [J/m]",
    "late_speed_mps": "late speed [m/s]", "distance_m": "distance [m]",
}
_UNITS = {"N": "N", "Nm": "N m", "mps": "m/s", "m": "m", "s": "s", "kg": "kg", "W": "W", "J": "J",
          "Ns_per_m": "N s/m", "N_per_m": "N/m", "rad": "rad", "deg": "deg", "Hz": "Hz"}


def quantity_label(key: str) -> str:
    """A scenario key or column name in words with its unit: ``"tow.force_N"`` -> ``"tow force [N]"``.

    Known keys have hand-written labels; others are read as ``section.name_unit`` (the unit
    suffix of the project's naming convention) and become ``"section name [unit]"``.
    """
    if key in _LABELS:
        return _LABELS[key]
    *sections, name = str(key).split(".")
    unit = None
    for suffix in sorted(_UNITS, key=len, reverse=True):
        if name.endswith("_" + suffix):
            name, unit = name[: -len(suffix) - 1], _UNITS[suffix]
            break
    words = " ".join(re.sub(r"[_\-]+", " ", p) for p in [*sections[-1:], name] if p)
    return f"{words} [{unit}]" if unit else words


def force_text(force_N: float, digits: int = 1) -> str:
    """A signed force as text, ``"+12.3 N"``; a value that rounds to zero is ``"0.0 N"`` (never ``"-0.0 N"``)."""
    v = round(float(force_N), digits)
    if v == 0:
        return f"{0.0:.{digits}f} N"
    return f"{v:+.{digits}f} N"


def legend_outside(ax, **kw):
    """A legend to the right of ``ax``, outside the data (constrained layout makes room for it)."""
    return ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize=8, **kw)
