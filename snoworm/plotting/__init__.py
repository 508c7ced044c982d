"""Figures of runs and studies, for notebooks and for files.

Every plotting function draws on the axes (``ax=``) or figure (``fig=``) you pass, or on a new
figure made through pyplot's figure manager (so it shows inline in Jupyter and with
``plt.show()`` in a script; the backend is never selected or changed), and returns the Figure.
Figures for files (:func:`write_figure`, :func:`plot_result`, the CLI) are headless
:class:`matplotlib.figure.Figure` objects.  ``size=``: print size, ``"column"`` (3.5 in wide),
``"page"`` (7.16 in, the default) or ``"WxH"`` inches; text is at least 7 pt at that size.
:func:`save` writes a figure atomically as PNG (200 dpi), PDF (TrueType fonts) or SVG (text
kept as text).  Colours are the Okabe-Ito colour-blind-safe palette, cycled with line styles
and markers.

Modules: :mod:`.style` (palette, sizes, fonts, labels, saving), :mod:`.runs` (one run: forces,
speeds, positions, force diagram, route), :mod:`.quantities` (slip, motor torque and power,
energy), :mod:`.overlay` (several runs on one figure: :func:`compare`), :mod:`.phases` (gait
phases as shaded spans), :mod:`.studies` (Table 2, terrain curves, sweeps, mobility map,
gradeability).
"""

from .overlay import COMPARE_KINDS, compare
from .quantities import plot_energy, plot_motor, plot_slip
from .runs import (
    PLOT_KINDS,
    moving_groups,
    plot_force_diagram,
    plot_forces,
    plot_groups,
    plot_positions,
    plot_result,
    plot_route,
    plot_speeds,
)
from .studies import (
    plot_gradeability,
    plot_mobility_map,
    plot_sweep,
    plot_sweep_heatmap,
    plot_table2,
    plot_terrain_curves,
)
from .style import (
    COLOURS,
    DPI,
    FIGURE_SIZES,
    PLOT_FORMATS,
    figure_style,
    force_text,
    headless,
    new_figure,
    parse_size,
    quantity_label,
    save,
    series_style,
    write_figure,
)

# the kinds of .quantities join Result.plot's table here (.quantities imports .runs, not the reverse)
PLOT_KINDS.update(slip=plot_slip, motor=plot_motor, energy=plot_energy)

__all__ = [
    "PLOT_KINDS",
    "COMPARE_KINDS",
    "compare",
    "plot_slip",
    "plot_motor",
    "plot_energy",
    "PLOT_FORMATS",
    "DPI",
    "COLOURS",
    "FIGURE_SIZES",
    "save",
    "write_figure",
    "figure_style",
    "headless",
    "parse_size",
    "new_figure",
    "series_style",
    "quantity_label",
    "force_text",
    "moving_groups",
    "plot_result",
    "plot_forces",
    "plot_speeds",
    "plot_positions",
    "plot_groups",
    "plot_force_diagram",
    "plot_route",
    "plot_table2",
    "plot_terrain_curves",
    "plot_sweep",
    "plot_sweep_heatmap",
    "plot_mobility_map",
    "plot_gradeability",
]
