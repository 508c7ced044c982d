"""Readability checks of a drawn figure, shared by the plotting tests: print width, text sizes,
labels that do not overlap one another, everything inside the figure."""

from matplotlib.text import Text

#: The smallest text allowed at print size [pt] (the usual journal minimum).
MIN_PT = 7.0


def _visible_text(t):
    return isinstance(t, Text) and t.get_visible() and t.get_text().strip() != "" and t.figure is not None


def _labels(fig):
    """(name, artist) of every label-like artist: axis labels, titles, visible tick labels,
    legends (as a whole), texts placed in axes and on the figure."""
    out = []
    for i, a in enumerate(fig.axes):
        if a.get_visible():
            out += _axes_labels(i, a)
    for t in fig.texts:
        if _visible_text(t) and t is not fig._suptitle:
            out.append((f"figure.text:{t.get_text()!r}", t))
    if fig._suptitle is not None and _visible_text(fig._suptitle):
        out.append(("suptitle", fig._suptitle))
    for leg in fig.legends:
        out.append(("figure.legend", leg))
    return out


def _axes_labels(i, a):
    """The label-like artists of the visible axes ``a`` (the ``i``-th of its figure)."""
    out = []
    for name, t in (
        ("xlabel", a.xaxis.label),
        ("ylabel", a.yaxis.label),
        ("title", a.title),
        ("ltitle", a._left_title),
        ("rtitle", a._right_title),
    ):
        if _visible_text(t):
            out.append((f"axes{i}.{name}:{t.get_text()!r}", t))
    for axis in (a.xaxis, a.yaxis) if a.axison else ():
        lo, hi = sorted(axis.get_view_interval())
        for tick in axis.get_major_ticks():
            if lo - 1e-9 * abs(hi - lo) <= tick.get_loc() <= hi + 1e-9 * abs(hi - lo):
                for t in (tick.label1, tick.label2):
                    if _visible_text(t):
                        out.append((f"axes{i}.tick:{t.get_text()!r}", t))
    if a.get_legend() is not None and a.get_legend().get_visible():
        out.append((f"axes{i}.legend", a.get_legend()))
        out += [(f"axes{i}.legend.text:{t.get_text()!r}", t) for t in a.get_legend().get_texts() if _visible_text(t)]
    for t in a.texts:
        if _visible_text(t):
            out.append((f"axes{i}.text:{t.get_text()!r}", t))
    return out


def problems(fig, width_in=None, min_pt=MIN_PT):
    """Readability problems of ``fig`` (an empty list when it is fine)."""
    bad = []
    if width_in is not None and abs(fig.get_figwidth() - width_in) > 1e-6:
        bad.append(f"width {fig.get_figwidth()} in, expected {width_in}")
    fig.draw_without_rendering()
    r = fig._get_renderer()
    for t in fig.findobj(Text):
        if _visible_text(t) and t.get_fontsize() < min_pt - 1e-9:
            bad.append(f"text {t.get_text()!r} at {t.get_fontsize():.1f} pt < {min_pt} pt")
    boxes = [(name, art.get_window_extent(r)) for name, art in _labels(fig)]
    page = fig.bbox
    for name, b in boxes:
        if b.x0 < page.x0 - 1 or b.y0 < page.y0 - 1 or b.x1 > page.x1 + 1 or b.y1 > page.y1 + 1:
            bad.append(f"{name} sticks out of the figure")
    for i, (n1, b1) in enumerate(boxes):
        for n2, b2 in boxes[i + 1 :]:
            if n2.startswith(n1 + ".") or n1.startswith(n2 + "."):  # a legend and its own texts
                continue
            w = min(b1.x1, b2.x1) - max(b1.x0, b2.x0)
            h = min(b1.y1, b2.y1) - max(b1.y0, b2.y0)
            if w > 1.0 and h > 1.0:
                bad.append(f"{n1} overlaps {n2}")
    return bad
