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
        for tick in axis.get_major_ticks() + axis.get_minor_ticks():
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


def _data_points(a):
    """Display coordinates (n, 2) of the line data of axes ``a`` that lie inside its box."""
    import numpy as np

    pts = []
    for line in a.get_lines():
        if not line.get_visible() or line.get_label() == "_nolegend_" and not len(line.get_xdata()):
            continue
        xy = np.column_stack([np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)])
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if xy.size:
            pts.append(line.get_transform().transform(xy))
    if not pts:
        return np.zeros((0, 2))
    p = np.concatenate(pts)
    box = a.bbox
    return p[(p[:, 0] >= box.x0) & (p[:, 0] <= box.x1) & (p[:, 1] >= box.y0) & (p[:, 1] <= box.y1)]


def _count_inside(p, x0, y0, x1, y1):
    return int(((p[:, 0] > x0) & (p[:, 0] < x1) & (p[:, 1] > y0) & (p[:, 1] < y1)).sum())


def legends_covering_data(fig):
    """Legends placed inside their axes that cover line data while one of the axes' four corners
    (a box of the legend's size, the legend's padding from the frame) covers none: the legend
    could sit there.  Returns one message per such legend."""
    fig.draw_without_rendering()
    r = fig._get_renderer()
    bad = []
    for i, a in enumerate(fig.axes):
        leg = a.get_legend()
        if leg is None or not leg.get_visible() or not a.get_visible():
            continue
        lb, box = leg.get_window_extent(r), a.bbox
        if not (lb.x0 >= box.x0 - 1 and lb.x1 <= box.x1 + 1 and lb.y0 >= box.y0 - 1 and lb.y1 <= box.y1 + 1):
            continue  # outside the axes: it covers no data
        p = _data_points(a)
        if _count_inside(p, lb.x0, lb.y0, lb.x1, lb.y1) == 0:
            continue
        pad = leg.borderaxespad * leg.prop.get_size_in_points() * fig.dpi / 72
        w, h = lb.width, lb.height
        corners = [
            (box.x0 + pad, box.y1 - pad - h),
            (box.x1 - pad - w, box.y1 - pad - h),
            (box.x0 + pad, box.y0 + pad),
            (box.x1 - pad - w, box.y0 + pad),
        ]
        if any(_count_inside(p, x, y, x + w, y + h) == 0 for x, y in corners):
            bad.append(f"axes{i}.legend covers data while a corner of the axes is free")
    return bad
