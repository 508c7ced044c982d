"""Figures of runs and studies, for files and for notebooks.

Every plotting function draws on a new :class:`matplotlib.figure.Figure` (no pyplot, the
matplotlib backend is never changed) or on the axes (``ax=``) or figure (``fig=``) you pass,
and returns the Figure; :func:`save` writes a figure atomically as PNG (200 dpi), PDF or SVG.
Colours are the Okabe-Ito colour-blind-safe palette, cycled with line styles and markers.

Modules: :mod:`.style` (palette, labels, saving), :mod:`.runs` (one run: forces, speeds,
positions, force diagram, route), :mod:`.studies` (Table 2, terrain curves, sweeps, mobility map).
"""
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
from .style import COLOURS, DPI, PLOT_FORMATS, force_text, new_figure, quantity_label, save, series_style

__all__ = ["PLOT_KINDS", "PLOT_FORMATS", "DPI", "COLOURS", "save", "new_figure", "series_style", "quantity_label",
           "force_text", "moving_groups", "plot_result", "plot_forces", "plot_speeds", "plot_positions",
           "plot_groups", "plot_force_diagram", "plot_route", "plot_table2", "plot_terrain_curves", "plot_sweep",
           "plot_sweep_heatmap", "plot_mobility_map", "plot_gradeability"]
