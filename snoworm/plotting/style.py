"""The figures' style and plumbing: colour-blind-safe colours, line styles and markers, axis
labels in words with units, print sizes, figures for notebooks and for files, atomic saving.

The library never selects the matplotlib backend nor changes the user's ``rcParams``:

* A figure drawn on the user's axes (``ax=``) or figure (``fig=``) is the user's.
* A figure drawn without either is created through pyplot's figure manager
  (``pyplot.figure``, as python-control does), so it shows inline in Jupyter and with
  ``plt.show()`` in a script, with whatever backend the user has (pyplot's own choice).
* Figures drawn only to be written to files (:func:`headless`, used by :func:`write_figure`,
  the CLI, sweeps and the paper report) are bare :class:`matplotlib.figure.Figure` objects:
  pyplot is not imported, no window opens, nothing is left for pyplot to release.

Every plotting function draws inside snoworm's own style (:func:`figure_style`): font sizes for
print, TrueType fonts in PDF (``pdf.fonttype`` 42, no Type 3 fonts) and text kept as ``<text>`` in
SVG (``svg.fonttype`` ``none``); :func:`save` applies the same font settings while writing.  Both
set and restore only their own rcParams (:func:`own_rc`), never pyplot's global state: a first
``pyplot`` import inside them (IPython's inline backend turns interactive mode on then) stays.
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
import io
import re
import textwrap
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib._pylab_helpers import Gcf
from matplotlib.figure import Figure

from ..config.schema import quote, split_unit
from ..infra.folders import atomic_path

__all__ = [
    "COLOURS",
    "LINESTYLES",
    "MARKERS",
    "PLOT_FORMATS",
    "DPI",
    "FIGURE_SIZES",
    "series_style",
    "new_figure",
    "save",
    "quantity_label",
    "force_text",
    "legend_outside",
    "figure_style",
    "own_rc",
    "headless",
    "figure_function",
    "parse_size",
    "write_figure",
    "NotebookFigure",
    "blank_figure",
    "small_pt",
    "wrap_title",
    "target_width",
]

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
#: Named print widths [in]: a journal's single column and full page width (IEEE: 3.5 and 7.16 in).
FIGURE_SIZES = {"column": 3.5, "page": 7.16}
#: Font settings applied while drawing and saving (TrueType in PDF/PS, text as text in SVG).
FONT_RC = {"pdf.fonttype": 42, "ps.fonttype": 42, "svg.fonttype": "none"}
#: Font sizes [pt] at print size: (text, small text) for column-width and wider figures; the
#: smallest text of every figure is ``small`` (>= 7 pt, the usual journal minimum).
_FONT_PT = {"column": (8.0, 7.0), "wide": (9.0, 8.0)}

_HEADLESS = contextvars.ContextVar("snoworm_headless", default=False)
_SIZE = contextvars.ContextVar("snoworm_size", default=None)


def parse_size(size):
    """``None``, ``"column"``, ``"page"``, ``"WxH"`` (inches, e.g. ``"3.5x2.6"``) or a (W, H) pair
    -> ``None``, a width [in] or a (width, height) pair [in].

    Raises ``ValueError`` naming the rule for anything else.
    """
    if size is None:
        return None
    if isinstance(size, str):
        key = size.strip().lower()
        if key in FIGURE_SIZES:
            return FIGURE_SIZES[key]
        m = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*[x×]\s*([0-9]*\.?[0-9]+)\s*", key)
        if not m:
            raise ValueError(f"figure size {quote(size, 60)}: expected column, page or WxH in inches (e.g. 3.5x2.5)")
        size = (float(m.group(1)), float(m.group(2)))
    try:
        if isinstance(size, (bool, bytes, dict)) or any(isinstance(v, (bool, str, bytes)) for v in size):
            raise TypeError("not a pair of numbers")
        w, h = (float(v) for v in size)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(
            f"figure size {quote(size, 60)}: expected column, page, 'WxH' in inches (e.g. '3.5x2.5') or a "
            "(width, height) pair of numbers in inches"
        ) from None
    if not (1.0 <= w <= 40.0 and 1.0 <= h <= 40.0):
        raise ValueError(f"figure size {w:g}x{h:g} in: width and height must lie in 1..40 inches")
    return (w, h)


def _width(size) -> float:
    s = parse_size(size)
    if s is None:
        return FIGURE_SIZES["page"]
    return s if isinstance(s, float) else s[0]


def target_width() -> float:
    """The width [in] of a new figure at the current ``size=`` (page width by default)."""
    return _width(_SIZE.get())


def style_rc(size=None) -> dict:
    """The rcParams of snoworm's figures at ``size`` (see :func:`parse_size`)."""
    big, small = _FONT_PT["column" if _width(size) < 5.0 else "wide"]
    return {
        **FONT_RC,
        "font.size": big,
        "axes.titlesize": big,
        "axes.labelsize": big,
        "figure.titlesize": big + 1,
        "xtick.labelsize": small,
        "ytick.labelsize": small,
        "legend.fontsize": small,
        "legend.title_fontsize": small,
        "lines.linewidth": 1.2 if big < 9 else 1.4,
        "lines.markersize": 3.5,
        "axes.linewidth": 0.6,
        "grid.linewidth": 0.5,
        "xtick.major.width": 0.6,
        "ytick.major.width": 0.6,
        "figure.constrained_layout.h_pad": 0.03,
        "figure.constrained_layout.w_pad": 0.03,
        "legend.borderaxespad": 0.3,
        "legend.handlelength": 1.8,
        "legend.columnspacing": 1.0,
    }


@contextlib.contextmanager
def own_rc(rc: dict):
    """Set the rcParams ``rc`` for the block and, on exit, give exactly those keys back their
    earlier values; nothing else is touched.

    Unlike :func:`matplotlib.rc_context`, which restores *every* rcParam on exit, this keeps what
    happens to pyplot's global state inside the block: pyplot imported and its backend activated
    there for the first time (IPython's inline backend then turns interactive mode on, which a
    full restore would turn off again, and no later figure of the session would show) stays as
    if the user had done it outside.
    """
    params = matplotlib.rcParams
    before = {k: params[k] for k in rc}
    params.update(rc)
    try:
        yield
    finally:
        params.update(before)


def figure_style(size=None):
    """snoworm's style as a context manager: print font sizes for ``size``, TrueType in PDF, text
    as text in SVG; on exit those rcParams, and only those, get their earlier values back
    (:func:`own_rc`: interactive mode, the backend and every other rcParam are never changed).
    Use it around your own ``fig.savefig(...)`` to embed the fonts the same way :func:`save` does."""
    return own_rc(style_rc(size))


@contextlib.contextmanager
def headless():
    """Figures created inside are bare :class:`~matplotlib.figure.Figure` objects (for files):
    pyplot is not imported and no window can open."""
    token = _HEADLESS.set(True)
    try:
        yield
    finally:
        _HEADLESS.reset(token)


def figure_function(fn):
    """Decorator of the plotting functions: a ``size=`` keyword (see :func:`parse_size`) and
    drawing inside :func:`figure_style` at that size."""

    @functools.wraps(fn)
    def wrapper(*args, size=None, **kwargs):
        parse_size(size)  # a bad size fails before any drawing
        token = _SIZE.set(size)
        try:
            with figure_style(size):
                fig = fn(*args, **kwargs)
                _titles_into_legends(fig)
                return fig
        finally:
            _SIZE.reset(token)

    return wrapper


def figure_size(natural, rows=1, row_in=None):
    """The size [in] of a new figure: the current ``size=`` (:func:`figure_function`) or, for a
    width alone, the figure's ``natural`` (width, height) scaled to that width with room for
    ``rows`` panels of readable height (``row_in`` inches each; print-size fonts do not shrink
    with the figure)."""
    s = parse_size(_SIZE.get())
    if isinstance(s, tuple):
        return s
    w = FIGURE_SIZES["page"] if s is None else s
    nat_w, nat_h = natural
    per_row = row_in or (1.3 if w < 5.0 else 1.5)
    h = max(nat_h * w / nat_w, per_row * rows + 0.8, 0.7 * w if rows == 1 else 0.0)
    return (w, float(min(h, 9.5)))


class NotebookFigure(Figure):
    """The Figure class of snoworm's own figures: a :class:`matplotlib.figure.Figure` that
    IPython/Jupyter shows exactly once.

    A cell ending with a figure is shown by IPython's display hook, and pyplot's inline backend
    shows every figure it manages again after the cell; IPython calls this class's
    ``_ipython_display_`` for both, which shows the figure as a PNG and releases it from pyplot
    (as the inline backend does after showing it).  A figure an interactive backend shows itself
    (Qt, Tk, ipympl widgets, ...) is left to it.
    """

    def _shown_by_its_manager(self) -> bool:
        c = self.canvas
        return c.manager is not None and (
            getattr(c, "required_interactive_framework", None) is not None
            or any(k in type(c).__module__ for k in ("ipympl", "nbagg", "webagg"))
        )

    def _ipython_display_(self):
        if self._shown_by_its_manager():
            return
        from IPython.display import display  # lazy: only IPython calls this method, so it is there

        buf = io.BytesIO()
        self.savefig(buf, format="png", bbox_inches="tight", facecolor="white")
        display({"image/png": buf.getvalue(), "text/plain": repr(self)}, raw=True)
        if self.canvas.manager is not None:
            Gcf.destroy_fig(self)  # shown: the inline backend would show it again after the cell


def _create(figsize):
    if _HEADLESS.get():
        return NotebookFigure(figsize=figsize, layout="constrained")
    import matplotlib.pyplot as plt  # lazy: only figures for notebooks and scripts need pyplot's figure manager

    return plt.figure(figsize=figsize, layout="constrained", FigureClass=NotebookFigure)


def series_style(k: int, n_points: int = 0, n_series: int = 1) -> dict:
    """Line keyword arguments of the ``k``-th of ``n_series`` series: colour, line style, a sparse
    marker.

    Each series gets 12 markers when alone or in a pair, fewer with more series (about 24 in all,
    at least 3 each), placed at ``n_points // markers``-sample intervals and interleaved evenly
    between the series, so that coinciding traces show one marker at a time instead of a pile.
    """
    per = min(12, max(3, 24 // max(int(n_series), 1)))
    every = max(n_points // per, 1)
    return {
        "color": COLOURS[k % len(COLOURS)],
        "ls": LINESTYLES[k % len(LINESTYLES)],
        "marker": MARKERS[k % len(MARKERS)],
        "ms": 4,
        "markevery": (int(((k % max(n_series, 1)) * every) // max(n_series, 1)) % every, every) if n_points else None,
    }


def new_figure(ax=None, fig=None, nrows=1, ncols=1, figsize=(8, 5), **subplot_kw):
    """(figure, 2-D array of axes) to draw on.

    ``ax``: the user's axes (one, or a sequence of ``nrows * ncols``); ``fig``: the user's figure,
    in which the axes are created; neither: a new figure of :func:`figure_size` (``figsize`` is
    the natural size), through pyplot's figure manager unless :func:`headless` (constrained layout).
    """
    if ax is not None:
        axes = np.atleast_1d(np.asarray(ax, dtype=object)).reshape(-1)
        if axes.size != nrows * ncols:
            raise ValueError(
                f"this plot draws {nrows * ncols} panel(s): pass as many axes (got {axes.size}), or pass fig= instead"
            )
        return axes[0].get_figure(), axes.reshape(nrows, ncols)
    if fig is None:
        fig = _create(figure_size(figsize, nrows))
    axes = fig.subplots(nrows, ncols, squeeze=False, **subplot_kw)
    return fig, axes


def blank_figure(figsize, rows=1, row_in=None):
    """A new empty figure of :func:`figure_size` (natural size ``figsize``, ``rows`` panels), for
    layouts :func:`new_figure` does not make; pyplot-managed unless :func:`headless`."""
    return _create(figure_size(figsize, rows, row_in))


def save(fig, path, fmt: str | None = None, dpi: int = DPI) -> Path:
    """Save ``fig`` atomically to ``path`` (format from ``fmt`` or the suffix; PNG at ``dpi``).

    Fonts are embedded as TrueType in PDF and kept as text in SVG (:data:`FONT_RC`).  Returns the
    path written.  The figure stays usable (nothing is closed).
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
        with own_rc(FONT_RC):
            fig.savefig(tmp, dpi=dpi, format=fmt, metadata=meta)
    return path


def write_figure(path, draw, *args, fmt=None, size=None, **kwargs):
    """Draw ``draw(*args, size=size, **kwargs)`` as a headless figure (:func:`headless`) and
    :func:`save` it to ``path``; returns the path written."""
    with headless():
        fig = draw(*args, size=size, **kwargs)
    return save(fig, path, fmt)


#: Words and units of the scenario keys and quantities the figures show.
_LABELS = {
    "terrain.xt": "terrain coefficient X_t",
    "xt": "terrain coefficient X_t",
    "tow.force_N": "tow force [N]",
    "tow_N": "tow force [N]",
    "vehicle.segments": "number of segments",
    "mean_speed_mps": "mean speed [m/s]",
    "mean_slip": "mean slip (2nd half)",
    "max_slip": "max slip",
    "max_link_force_N": "max |link force| [N]",
    "energy_per_m_J": "energy per metre [J/m]",
    "late_speed_mps": "late speed [m/s]",
    "distance_m": "distance [m]",
}


def quantity_label(key: str) -> str:
    """A scenario key or column name in words with its unit: ``"tow.force_N"`` -> ``"tow force [N]"``.

    Known keys have hand-written labels; others are read as ``section.name_unit`` (the unit
    suffix of the project's naming convention) and become ``"section name [unit]"``.
    """
    if key in _LABELS:
        return _LABELS[key]
    *sections, name = str(key).split(".")
    name, unit = split_unit(name)
    words = " ".join(re.sub(r"[_\-]+", " ", p) for p in [*sections[-1:], name] if p)
    return f"{words} [{unit}]" if unit else words


def force_text(force_N: float, digits: int = 1) -> str:
    """A signed force as text, ``"+12.3 N"`` or ``"\u221212.3 N"`` (a real minus sign, U+2212); a
    value that rounds to zero is ``"0.0 N"`` (never ``"\u22120.0 N"``)."""
    v = round(float(force_N), digits)
    if v == 0:
        return f"{0.0:.{digits}f} N"
    return f"{v:+.{digits}f} N".replace("-", "\u2212")


def legend_outside(ax, **kw):
    """A legend outside the data: to the right of ``ax`` on a wide figure, above it in columns on
    a narrow one (below 5 in, where a side legend would take half the width); constrained layout
    makes room for it."""
    fig = ax.get_figure()
    if fig.get_figwidth() >= 5.0:
        return ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, **kw)
    handles, labels = kw.pop("handles", None), kw.pop("labels", None)
    if handles is None:
        handles, labels = ax.get_legend_handles_labels()
    elif labels is None:
        labels = [h.get_label() for h in handles]
    n = len(handles)
    ncol = kw.pop("ncol", None) or (n if n <= 3 else (3 if n % 3 == 0 or n > 8 else 2))
    leg = ax.legend(
        handles,
        labels,
        loc="lower left",
        bbox_to_anchor=(0.0, 1.02),
        borderaxespad=0.0,
        ncol=min(ncol, max(n, 1)),
        frameon=False,
        columnspacing=1.0,
        handlelength=1.6,
        **kw,
    )
    leg.set_gid(_ABOVE)  # a title of these axes becomes the legend's title (see figure_function)
    return leg


#: gid of a legend placed above its axes (narrow figures).
_ABOVE = "snoworm-legend-above"


def _titles_into_legends(fig):
    """An axes title and a legend placed above the same axes would collide: the title becomes the
    legend's title (left-aligned, above the entries)."""
    for a in fig.axes:
        leg = a.get_legend()
        if leg is not None and leg.get_gid() == _ABOVE and a.get_title():
            width_in = 0.8 * a.get_position().width * fig.get_figwidth()  # the legend starts at the axes' left
            leg.set_title(
                wrap_title(" ".join(a.get_title().split()), width_in),
                prop={"size": matplotlib.rcParams["axes.titlesize"]},
            )
            leg._legend_box.align = "left"
            a.set_title("")


def small_pt() -> float:
    """The size [pt] of small text (annotations, ticks, legends) in the current style (>= 7 pt)."""
    return (
        float(matplotlib.rcParams["xtick.labelsize"])
        if isinstance(matplotlib.rcParams["xtick.labelsize"], (int, float))
        else 7.0
    )


def wrap_title(text: str, width_in: float, size_key: str = "axes.titlesize") -> str:
    """``text`` broken into lines that fit ``width_in`` inches in the font size of the rcParam
    ``size_key`` (about 0.6 em per character: an upper bound for the default sans-serif font)."""
    pt = matplotlib.rcParams[size_key]
    pt = float(pt) if isinstance(pt, (int, float)) else float(matplotlib.rcParams["font.size"])
    return textwrap.fill(text, width=max(16, int(0.95 * width_in * 72 / (0.6 * pt))))


def seg_label(k):
    """A segment's name in legends: the leader (segment 0) or a follower."""
    return "leader 0" if k == 0 else f"follower {k}"


def title(fig, axes, text, own):
    """A title on the figure (our own figure) or on the first panel (the user's axes/figure),
    wrapped to the figure's width."""
    if own:
        fig.suptitle(wrap_title(text, fig.get_figwidth(), "figure.titlesize"))
    else:
        axes.flat[0].set_title(wrap_title(text, axes.flat[0].get_position().width * fig.get_figwidth()))
