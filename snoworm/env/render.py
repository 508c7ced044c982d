"""Images of the environments (``render_mode="rgb_array"``): the drawing of a run's animation.

The environments' :meth:`render` returns the chain at its current state as an ``H x W x 3`` uint8
array (640 x 260 pixels), drawn by :func:`snoworm.plotting.animation.draw_chain`, the function
that draws ``snoworm animate``'s frames: segments, wheels and links to scale, the links coloured
by their force, the terrain's elevation and X_t band under it, the time in a corner, the view
following the chain.  The figure is made on the first :meth:`ChainRenderer.image` and reused
(one Agg canvas per environment; never pyplot, so no window opens); it is not copied or pickled
with the environment (a copy makes its own).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from numpy.typing import ArrayLike, NDArray

    from ..config.scenario import Scenario
    from ..plotting.animation import ChainScene

__all__ = ["RENDER_MODES", "ChainRenderer", "check_render_mode"]

#: The render modes of the environments (Gymnasium's ``metadata["render_modes"]``).
RENDER_MODES = ["rgb_array"]


def check_render_mode(render_mode: str | None) -> str | None:
    """``render_mode`` if it is None or one of :data:`RENDER_MODES`, else ValueError naming them."""
    if render_mode is not None and render_mode not in RENDER_MODES:
        raise ValueError(
            f"render_mode: the environment renders {', '.join(repr(m) for m in RENDER_MODES)} "
            f"(an H x W x 3 uint8 image) or nothing (None); got {render_mode!r}"
        )
    return render_mode


class ChainRenderer:
    """Draws a scenario's chain as rgb_array images (see the module docstring)."""

    def __init__(self, scenario: Scenario) -> None:
        self.scenario = scenario
        self._scene: ChainScene | None = None
        self._canvas: tuple[Figure, Axes] | None = None

    def image(self, t_s: float, x_m: ArrayLike, link_force_N: ArrayLike, label: str = "") -> NDArray[np.uint8]:
        """The chain with segment positions ``x_m`` [m] and link forces ``link_force_N`` [N] at time
        ``t_s``, as an ``H x W x 3`` uint8 array; ``label`` under the time (default: the scenario's
        name and mode)."""
        from ..plotting import animation  # lazy: matplotlib costs ~0.5 s to import; only when rendering

        if self._scene is None:
            self._scene = animation.ChainScene.from_scenario(self.scenario)
        if self._canvas is None:
            self._canvas = animation.new_canvas()
        frame = animation.ChainFrame(
            float(t_s), np.asarray(x_m, float), np.asarray(link_force_N, float).reshape(-1), label
        )
        return animation.render_rgb(*self._canvas, frame, self._scene)

    def close(self) -> None:
        """Drop the figure (made again by the next :meth:`image`)."""
        self._canvas = None

    def __getstate__(self) -> dict[str, Any]:
        return {"scenario": self.scenario, "_scene": None, "_canvas": None}
