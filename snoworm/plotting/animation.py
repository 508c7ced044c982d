"""The chain moving along its route: one drawing for the animation and the environments' images.

:func:`draw_chain` draws one :class:`ChainFrame` (the segments' positions and the link forces at
one time) of a :class:`ChainScene` (the chain's geometry and the terrain, from the scenario) on a
matplotlib axes; called again on the same axes it moves the artists it made.  It serves both
:func:`animate_result` (``snoworm animate``, :meth:`snoworm.results.result.Result.animate`) and the
Gymnasium environments' ``render_mode="rgb_array"`` (:func:`render_rgb`).

What is drawn, to scale (equal units on both axes):

* the **terrain**: the elevation profile ``z(s)`` of the scenario (level when it has none) as the
  ground line, over a band coloured by X_t (colour bar "X_t"); the horizontal axis is the distance
  along the track ``s`` (the chain's coordinate, docs/model.md section 7), so on a grade the drawing
  is shortened by ``cos(theta)`` horizontally (1.5 % at 10 deg);
* each **segment** as its two wheels (circles of radius ``R_w`` on the ground, at the axles
  ``x_k +- b/2``) under a chassis from axle to axle (``b`` long, ``R_w`` high: the height is
  schematic, the parameter sets give none), tilted to the chord grade under the segment (the grade
  the kernel uses).  Wheels of neighbours may overlap where the parameters put them closer than
  ``2 R_w`` (FrostyBoy: rest spacing 1.5 m, wheelbase 1.094 m, ``R_w`` 0.265 m);
* each **link** as a bar from a segment's rear to the next one's front (their rest spacing is the
  centre distance, so the bars' length follows the link's stretch), coloured by its force on a
  diverging map (red tension, blue compression, white zero; colour bar in N);
* the **time** and the **gait phase** (or the mode) in the top-left corner;
* a **view window** following the chain (centred on its mean position, 1.6 chain lengths wide).
"""

from __future__ import annotations

import math
import os
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib import colormaps
from matplotlib.animation import FFMpegWriter, PillowWriter
from matplotlib.cm import ScalarMappable
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from PIL import Image

from ..infra.folders import add_file
from .phases import gait_spans

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from numpy.typing import NDArray

    from ..config.scenario import Scenario
    from ..slope import ElevationProfile
    from ..terrain import TerrainProfile

__all__ = [
    "ANIMATION_FORMATS",
    "AnimationOptionError",
    "MAX_FRAMES",
    "ChainFrame",
    "ChainScene",
    "animate_result",
    "draw_chain",
    "ffmpeg_available",
    "frame_times",
    "new_canvas",
    "render_rgb",
    "result_frames",
]

#: Video formats: GIF (Pillow, always there) and MP4 (needs the ``ffmpeg`` program).
ANIMATION_FORMATS = ("gif", "mp4")
#: Most frames of one animation: a GIF keeps every frame in memory (~170 kB each at the default
#: 640 x 260 pixels) until it is written, so ~250 MB at most.
MAX_FRAMES = 1500
#: Default length of a video [s]: the speed-up by default plays a run in at most this time.
DEFAULT_VIDEO_S = 20.0
#: Default size of a frame [in] and its resolution [dpi]: 640 x 260 pixels.
FRAME_SIZE_IN = (6.4, 2.6)
FRAME_DPI = 100
#: Width of the view window in chain lengths (at rest: front of the leader to the back of the last).
WINDOW_CHAINS = 1.6
#: Link force colour map (diverging: tension red, compression blue) and the X_t band's.
FORCE_CMAP, XT_CMAP = "RdBu_r", "YlGnBu"


def ffmpeg_available() -> bool:
    """True when the ``ffmpeg`` program is on the PATH (MP4 output needs it)."""
    return shutil.which("ffmpeg") is not None


@dataclass(frozen=True)
class ChainFrame:
    """The chain at one time: ``t_s`` [s], segment positions ``x_m`` (N,) [m] (the reference points,
    the results' ``x_m``), link forces ``link_force_N`` (N-1,) [N, tension positive] and the gait
    phase's text (empty: the scene's mode is shown)."""

    t_s: float
    x_m: NDArray[np.float64]
    link_force_N: NDArray[np.float64]
    phase: str = ""


@dataclass(frozen=True)
class ChainScene:
    """What does not change from frame to frame: the chain's geometry, the terrain, the scales.

    Attributes
    ----------
    wheel_radius_m, wheelbase_m : ndarray (N,)
        Per segment (``vehicle.segment`` with its overrides).
    rest_spacing_m : float
        Centre-to-centre spacing of unloaded segments (``vehicle.links.rest_spacing_m``).
    elevation : ElevationProfile or None
        The scenario's elevation along the track (None: level).
    xt : TerrainProfile
        X_t along the track.
    force_scale_N : float
        Link force at the ends of the colour map (> 0).
    label : str
        Shown under the time when a frame has no gait phase (the mode).
    """

    wheel_radius_m: NDArray[np.float64]
    wheelbase_m: NDArray[np.float64]
    rest_spacing_m: float
    elevation: ElevationProfile | None
    xt: TerrainProfile
    force_scale_N: float
    label: str = ""

    @classmethod
    def from_scenario(cls, sc: Scenario, force_scale_N: float | None = None) -> ChainScene:
        """The scene of scenario ``sc``.  ``force_scale_N``: the colour map's limit (default: the
        larger of the prismatic joints' force limit and the weight of a segment, a force every chain
        meets)."""
        segs = sc.vehicle.segment_params()
        if force_scale_N is None:
            force_scale_N = max(float(sc.vehicle.links.force_max_N), max(s.mass_kg * s.gravity_mps2 for s in segs))
        return cls(
            np.array([s.wheel_radius_m for s in segs], float),
            np.array([s.wheelbase_m for s in segs], float),
            float(sc.vehicle.links.rest_spacing_m),
            sc.terrain.elevation_profile(),
            sc.terrain.compile(),
            float(force_scale_N),
            f"{sc.name}: {sc.mode.type}",
        )

    @property
    def n(self) -> int:
        return int(self.wheel_radius_m.size)

    @property
    def window_m(self) -> float:
        """Width of the view window [m]: :data:`WINDOW_CHAINS` chain lengths at rest."""
        length = (self.n - 1) * self.rest_spacing_m + float(np.max(self.wheelbase_m + 2 * self.wheel_radius_m))
        return WINDOW_CHAINS * length

    def ground(self, s_m: NDArray[np.float64]) -> NDArray[np.float64]:
        """Elevation of the ground at ``s_m`` [m] (0 on level ground)."""
        return np.zeros_like(s_m) if self.elevation is None else np.asarray(self.elevation.elevation(s_m), float)

    def sin_grade(self, x_m: NDArray[np.float64]) -> NDArray[np.float64]:
        """Sine of the chord grade under each segment (the kernel's, docs/model.md section 7)."""
        if self.elevation is None:
            return np.zeros_like(x_m)
        return np.asarray(self.elevation.sin_grade(x_m, self.wheelbase_m / 2.0), float) * np.ones_like(x_m)


@dataclass(frozen=True)
class SegmentShapes:
    """The drawn shapes of the segments at one frame (data coordinates ``(s, z)``):
    ``chassis`` (N, 4, 2) corners, ``wheels`` (N, 2, 2) wheel centres (front, rear), ``links``
    (N-1, 2, 2) bar ends."""

    chassis: NDArray[np.float64]
    wheels: NDArray[np.float64]
    links: NDArray[np.float64]


def segment_shapes(scene: ChainScene, x_m: NDArray[np.float64]) -> SegmentShapes:
    """Where the segments at positions ``x_m`` are drawn (see the module docstring)."""
    x = np.asarray(x_m, float)
    R, b = scene.wheel_radius_m, scene.wheelbase_m
    s = scene.sin_grade(x)
    c = np.sqrt(1.0 - s * s)
    u = np.stack([c, s], axis=-1)  # along the chord
    nrm = np.stack([-s, c], axis=-1)  # up from the chord
    axles = x[:, None] + np.stack([b / 2.0, -b / 2.0], axis=-1)  # (N, 2): front, rear
    contact = np.stack([axles, scene.ground(axles)], axis=-1)  # (N, 2, 2)
    wheels = contact + (R[:, None] * np.ones(2))[..., None] * nrm[:, None, :]
    mid = wheels.mean(axis=1)  # (N, 2): the middle of the axles
    half = np.maximum(b / 2.0, 0.25 * R)[:, None]  # a wheelbase of 0 is drawn as a short block
    H = R[:, None]
    chassis = np.stack([mid - half * u, mid + half * u, mid + half * u + H * nrm, mid - half * u + H * nrm], axis=1)
    level = mid + 0.5 * H * nrm  # middle height of the chassis
    front = level + half * u
    rear = level - half * u
    links = np.stack([rear[:-1], front[1:]], axis=1)
    return SegmentShapes(chassis, wheels, links)


#: A unit circle as a 48-gon (the wheels' outline).
_CIRCLE = np.stack([np.cos(np.linspace(0, 2 * np.pi, 49)[:-1]), np.sin(np.linspace(0, 2 * np.pi, 49)[:-1])], axis=-1)


def _time_text(frame: ChainFrame, scene: ChainScene, decimals: int) -> str:
    return f"t = {frame.t_s:.{decimals}f} s\n{frame.phase or scene.label}"


class _ChainArtists:
    """The artists :func:`draw_chain` made on one axes, moved at every later frame."""

    def __init__(self, ax: Axes, scene: ChainScene, colourbars: bool) -> None:
        self.scene, self.ax = scene, ax
        self.force_norm = Normalize(-scene.force_scale_N, scene.force_scale_N)
        self.force_cmap = colormaps[FORCE_CMAP]
        self.xt_norm = Normalize(0.0, 1.0)
        n = scene.n
        self.chassis = PolyCollection(
            list(np.zeros((n, 4, 2))),
            facecolor="#d9d9d9",
            edgecolor="#333333",
            linewidth=0.8,
            zorder=3,
        )
        self.wheels = PolyCollection(
            list(np.zeros((2 * n, _CIRCLE.shape[0], 2))),
            facecolor="#555555",
            edgecolor="#111111",
            linewidth=0.6,
            zorder=4,
        )
        self.link_edges = LineCollection(
            list(np.zeros((max(n - 1, 0), 2, 2))), linewidths=5.0, colors="#333333", zorder=5
        )
        self.links = LineCollection(
            list(np.zeros((max(n - 1, 0), 2, 2))),
            linewidths=3.5,
            cmap=self.force_cmap,
            norm=self.force_norm,
            zorder=5.5,
        )
        ax.add_collection(self.chassis)
        ax.add_collection(self.wheels)
        ax.add_collection(self.link_edges)
        ax.add_collection(self.links)
        self.text = ax.text(
            0.01,
            0.97,
            "",
            transform=ax.transAxes,
            va="top",
            ha="left",
            fontsize=8,
            bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "none", "pad": 1.5},
            zorder=6,
        )
        self.terrain_range = (math.inf, -math.inf)
        self.ground_line = ax.plot([], [], color="#3b2f2f", linewidth=1.0, zorder=1)[0]
        self.band = PolyCollection(
            [], cmap=colormaps[XT_CMAP], norm=self.xt_norm, linewidth=0, antialiased=False, zorder=0
        )
        ax.add_collection(self.band)
        ax.set_xlabel("distance along the track [m]")
        ax.set_ylabel("elevation [m]")
        self.colourbar_axes: list[Axes] = []
        if colourbars:  # beside the axes (inset axes: they take no room from a user's axes layout)
            fig = ax.get_figure()
            assert fig is not None
            cf = ax.inset_axes((1.02, 0.0, 0.025, 1.0))
            cx = ax.inset_axes((1.25, 0.0, 0.025, 1.0))
            fig.colorbar(ScalarMappable(self.force_norm, self.force_cmap), cax=cf, label="link force [N], tension +")
            fig.colorbar(ScalarMappable(self.xt_norm, colormaps[XT_CMAP]), cax=cx, label="$X_t$")
            self.colourbar_axes = [cf, cx]

    def terrain(self, lo: float, hi: float) -> None:
        """Draw the ground line and the X_t band over ``[lo, hi]`` (extended by a window each side)."""
        if lo >= self.terrain_range[0] and hi <= self.terrain_range[1]:
            return
        scene = self.scene
        w = scene.window_m
        lo, hi = lo - w, hi + w
        s = np.linspace(lo, hi, 801)
        if scene.elevation is not None and not scene.elevation.is_constant:
            P = np.asarray(scene.elevation.positions_m, float)
            s = np.union1d(s, P[(P > lo) & (P < hi)])  # the table's kinks drawn as kinks
        z = scene.ground(s)
        depth = 2.0 * float(np.max(scene.wheel_radius_m))
        self.ground_line.set_data(s, z)
        quads = np.stack(
            [np.stack([s[:-1], z[:-1]], -1), np.stack([s[1:], z[1:]], -1), np.stack([s[1:], z[1:] - depth], -1)]
            + [np.stack([s[:-1], z[:-1] - depth], -1)],
            axis=1,
        )
        self.band.set_verts(list(quads))
        self.band.set_array(scene.xt(0.5 * (s[:-1] + s[1:])))
        self.terrain_range = (lo, hi)

    def update(self, frame: ChainFrame, decimals: int) -> None:
        scene, ax = self.scene, self.ax
        x = np.asarray(frame.x_m, float)
        shapes = segment_shapes(scene, x)
        self.chassis.set_verts(list(shapes.chassis))
        centres = shapes.wheels.reshape(-1, 2)
        self.wheels.set_verts(list(centres[:, None, :] + self.wheel_radii[:, None, None] * _CIRCLE))
        self.links.set_segments(list(shapes.links))
        self.link_edges.set_segments(list(shapes.links))
        self.links.set_array(np.asarray(frame.link_force_N, float))
        self.text.set_text(_time_text(frame, scene, decimals))
        centre = float(np.mean(x))
        w = scene.window_m
        self.terrain(centre - w / 2, centre + w / 2)
        ax.set_xlim(centre - w / 2, centre + w / 2)
        zc = float(np.mean(shapes.wheels[..., 1]))
        box = ax.get_window_extent()  # pixels: equal units on both axes
        half_h = w / 2 * box.height / box.width
        ax.set_ylim(zc - half_h, zc + half_h)

    def remove(self) -> None:
        """Take the artists (and the colour bars' axes) off the axes."""
        for a in (self.chassis, self.wheels, self.links, self.link_edges, self.band, self.ground_line, self.text):
            a.remove()
        for cax in self.colourbar_axes:
            cax.remove()

    @property
    def wheel_radii(self) -> NDArray[np.float64]:
        return np.repeat(self.scene.wheel_radius_m, 2)


def draw_chain(
    ax: Axes, frame: ChainFrame, scene: ChainScene, *, colourbars: bool = True, decimals: int = 2
) -> _ChainArtists:
    """Draw ``frame`` of ``scene`` on ``ax`` (the first call on an axes makes the artists and the
    colour bars; a later call with the same scene moves them).  Returns the artists (``chassis``,
    ``wheels``, ``links``: matplotlib collections in data coordinates; ``text``).  ``decimals``:
    of the time shown."""
    artists = getattr(ax, "_snoworm_chain", None)
    if artists is not None and artists.scene is not scene:  # another chain on these axes: replaced
        artists.remove()
        artists = None
    if artists is None:
        artists = _ChainArtists(ax, scene, colourbars)
        ax._snoworm_chain = artists  # type: ignore[attr-defined]  # the artists travel with their axes
    artists.update(frame, decimals)
    return artists


def new_canvas(size_in: tuple[float, float] = FRAME_SIZE_IN, dpi: int = FRAME_DPI) -> tuple[Figure, Axes]:
    """A headless figure and its axes for frames (fixed margins: the view window's aspect is
    computed from them, so no layout engine moves the axes between frames)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg  # lazy: the Agg canvas, for pixels

    fig = Figure(figsize=size_in, dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.09, 0.18, 0.62, 0.78))
    return fig, ax


def render_rgb(fig: Figure, ax: Axes, frame: ChainFrame, scene: ChainScene) -> NDArray[np.uint8]:
    """``frame`` drawn on ``(fig, ax)`` (from :func:`new_canvas`) as an ``H x W x 3`` uint8 image."""
    draw_chain(ax, frame, scene)
    fig.canvas.draw()
    rgba = np.asarray(fig.canvas.buffer_rgba())  # type: ignore[attr-defined]  # the Agg canvas has it
    return np.array(rgba[..., :3], dtype=np.uint8)


# ------------------------------------------------------------------ a run's animation
def frame_times(t_start_s: float, t_end_s: float, fps: float, speed_up: float) -> NDArray[np.float64]:
    """Times of the frames: every ``speed_up / fps`` simulated seconds from ``t_start_s`` to
    ``t_end_s`` (the last within it): ``floor((t_end - t_start) fps / speed_up) + 1`` frames."""
    step = speed_up / fps
    n = int(math.floor((t_end_s - t_start_s) / step + 1e-9)) + 1
    return np.asarray(t_start_s + step * np.arange(n), float)


def _interp_rows(t: NDArray[np.float64], series: NDArray[np.float64], tf: NDArray[np.float64]) -> NDArray[np.float64]:
    """Linear interpolation of the rows of ``series`` (n_t, M) at times ``tf``."""
    if series.shape[1] == 0:
        return np.zeros((tf.size, 0))
    j = np.clip(np.searchsorted(t, tf, side="right") - 1, 0, max(t.size - 2, 0))
    if t.size < 2:
        return np.repeat(series[:1], tf.size, axis=0)
    w = np.clip((tf - t[j]) / np.where(t[j + 1] > t[j], t[j + 1] - t[j], 1.0), 0.0, 1.0)[:, None]
    return np.asarray((1.0 - w) * series[j] + w * series[j + 1], float)


def _phase_labels(result: Any, tf: NDArray[np.float64]) -> list[str]:
    spans = gait_spans(result)
    out = []
    for t in tf:
        label = ""
        for t0, t1, k, moving in spans:
            if t0 - 1e-9 <= t <= t1 + 1e-9:
                label = f"gait phase {k}" + (f": moving segments {moving}" if moving else "")
        out.append(label)
    return out


def result_frames(result: Any, fps: float, speed_up: float) -> list[ChainFrame]:
    """The frames of a run (a :class:`~snoworm.results.result.Result`) at :func:`frame_times`, its
    series interpolated linearly between output samples."""
    t = np.asarray(result.t, float)
    tf = frame_times(float(t[0]), float(t[-1]), fps, speed_up)
    x = _interp_rows(t, np.asarray(result.segments["x_m"], float), tf)
    F = _interp_rows(t, np.asarray(result.links["force_N"], float), tf)
    phases = _phase_labels(result, tf)
    return [ChainFrame(float(tf[j]), x[j], F[j], phases[j]) for j in range(tf.size)]


class AnimationOptionError(ValueError):
    """A bad option of an animation (the CLI: exit status 2); the message names it and the fix."""


def check_options(duration_s: float, fps: int, speed_up: float | None, fmt: str) -> float:
    """Check the options of an animation (:class:`AnimationOptionError` naming the option, the rule and the fix);
    returns the speed-up (default: a video of at most :data:`DEFAULT_VIDEO_S` seconds, at least 1)."""
    if fmt not in ANIMATION_FORMATS:
        raise AnimationOptionError(f"format: expected one of {', '.join(ANIMATION_FORMATS)}, got {fmt!r}")
    if fmt == "mp4" and not ffmpeg_available():
        raise AnimationOptionError(
            "format mp4: needs the ffmpeg program, which is not on the PATH; install ffmpeg "
            "(e.g. apt install ffmpeg, conda install ffmpeg) or write a GIF (--format gif)"
        )
    if isinstance(fps, bool) or not isinstance(fps, (int, np.integer)) or not 1 <= fps <= 60:
        raise AnimationOptionError(f"fps: frames per second must be a whole number from 1 to 60, got {fps!r}")
    if speed_up is None:
        speed_up = max(1.0, duration_s / DEFAULT_VIDEO_S)
    if not (isinstance(speed_up, (int, float)) and math.isfinite(speed_up) and speed_up > 0):
        raise AnimationOptionError(
            f"speed_up: simulated seconds per video second must be a positive number, got {speed_up!r}"
        )
    n = int(math.floor(duration_s * fps / speed_up + 1e-9)) + 1
    if n > MAX_FRAMES:
        need = duration_s * fps / (MAX_FRAMES - 1)
        raise AnimationOptionError(
            f"the animation would have {n} frames ({duration_s:g} s simulated x {fps:g} fps / speed-up "
            f"{speed_up:g}), over the limit of {MAX_FRAMES}; give a speed-up of at least {need:.3g} "
            "(--speed-up) or fewer frames per second (--fps)"
        )
    return float(speed_up)


class _GifWriter(PillowWriter):
    """Pillow's GIF writer keeping each frame as a palette image (a quarter of the memory of RGB;
    the GIF holds palette images anyway)."""

    _frames: list[Any]

    def grab_frame(self, **savefig_kwargs: Any) -> None:
        super().grab_frame(**savefig_kwargs)
        # fast octree: ~3 ms a 640 x 260 frame and closer colours than the adaptive median cut (~18 ms)
        self._frames[-1] = self._frames[-1].quantize(256, method=Image.Quantize.FASTOCTREE)


def animate_result(
    result: Any,
    path: str | os.PathLike[str],
    fps: int = 20,
    speed_up: float | None = None,
    fmt: str | None = None,
    progress: Callable[[int, int], None] | None = None,
    force_scale_N: float | None = None,
) -> Path:
    """Write the animation of a run to ``path`` atomically (temporary file, then renamed) and return it.

    ``fps``: frames per second of the video (a whole number, 1 to 60); ``speed_up``: simulated seconds per video
    second (default: the run in at most :data:`DEFAULT_VIDEO_S` s, never faster than 1); ``fmt``:
    ``"gif"`` (Pillow) or ``"mp4"`` (ffmpeg), default from the suffix of ``path`` (else gif);
    ``progress(done, total)``: called after each frame; ``force_scale_N``: the link force at the
    ends of the colour map (default: the run's largest |force|).  :func:`frame_times` gives the
    frames.  Into a snoworm output folder the file is written under the folder's lock and listed in
    its manifest (:func:`snoworm.infra.folders.add_file`).

    Raises
    ------
    AnimationOptionError
        A bad option, MP4 without ffmpeg, or more than :data:`MAX_FRAMES` frames (nothing written);
        a ValueError.
    snoworm.infra.folders.OutputError
        The folder is another snoworm process's, or the file cannot be written (nothing written).
    """
    path = Path(path)
    fmt = (fmt or path.suffix.lstrip(".") or "gif").lower()
    t = np.asarray(result.t, float)
    duration = float(t[-1] - t[0]) if t.size else 0.0
    speed_up = check_options(duration, fps, speed_up, fmt)
    if path.suffix.lower() != "." + fmt:
        raise AnimationOptionError(f"{path}: the file name must end in .{fmt} for a {fmt.upper()} animation")
    frames = result_frames(result, fps, speed_up)
    if force_scale_N is None:  # the run's largest |force|: its colours use the whole map
        F = np.abs(np.asarray(result.links["force_N"], float))
        force_scale_N = float(F.max()) if F.size and F.max() > 0 else None
    scene = ChainScene.from_scenario(result.scenario, force_scale_N)
    fig, ax = new_canvas()
    decimals = min(3, max(0, math.ceil(-math.log10(speed_up / fps) - 1e-9)))  # times that differ print apart
    writer = (
        _GifWriter(fps=fps) if fmt == "gif" else FFMpegWriter(fps=fps, codec="h264", extra_args=["-pix_fmt", "yuv420p"])
    )
    with add_file(path) as tmp, writer.saving(fig, str(tmp), FRAME_DPI):
        for j, frame in enumerate(frames):  # one draw per frame (FuncAnimation would draw twice)
            draw_chain(ax, frame, scene, decimals=decimals)
            writer.grab_frame()
            if progress is not None:
                progress(j + 1, len(frames))
    return path
