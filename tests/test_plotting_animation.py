"""The animation of a run (issue 34): frames, the drawing of a known state, files and the CLI."""

import math

import numpy as np
import pytest
from click.testing import CliRunner
from matplotlib import colormaps
from PIL import Image

from snoworm import load_scenario, simulate
from snoworm.cli import main
from snoworm.infra.folders import OutputError, folder_lock, folder_state, read_manifest
from snoworm.plotting import animation
from snoworm.plotting.animation import (
    AnimationOptionError,
    ChainFrame,
    ChainScene,
    draw_chain,
    frame_times,
    new_canvas,
    render_rgb,
)
from tests.conftest import SCENARIOS

# a tiny inching run: 2 segments, 1.2 s, sampled every 0.05 s
TINY = ["simulation.duration_s=1.2", "simulation.output_dt_s=0.05"]


@pytest.fixture(scope="module")
def tiny():
    return simulate(load_scenario(SCENARIOS / "inchworm2.yaml", TINY))


@pytest.fixture(scope="module")
def tiny_dir(tiny, tmp_path_factory):
    d = tmp_path_factory.mktemp("anim") / "run"
    tiny.write(d, plot=False)
    return d


def gif_frames(path):
    """The frames of a GIF as RGB arrays."""
    with Image.open(path) as im:
        out = []
        for k in range(im.n_frames):
            im.seek(k)
            out.append(np.asarray(im.convert("RGB")))
        return out, im.info["duration"]


def test_gif_has_the_frames_of_its_duration_fps_and_speed_up(tiny, tmp_path):
    fps, speed_up = 5, 0.5  # a frame every 0.1 s simulated
    path = tiny.animate(tmp_path / "a.gif", fps=fps, speed_up=speed_up)
    duration = tiny.t[-1] - tiny.t[0]
    expected = math.floor(duration * fps / speed_up + 1e-9) + 1  # frames at 0, 0.1, ..., 1.2 s: 13
    frames, ms = gif_frames(path)
    assert len(frames) == expected == frame_times(tiny.t[0], tiny.t[-1], fps, speed_up).size
    assert ms == 1000 // fps  # ms per frame: the video's frame rate
    # the chain moves: the drawing below the time's corner changes from the first frame to the last
    h, w, _ = frames[0].shape
    body = (slice(h // 4, h), slice(0, w))
    assert np.mean(np.any(frames[0][body] != frames[-1][body], axis=-1)) > 0.01


def test_frames_follow_the_series(tiny):
    frames = animation.result_frames(tiny, fps=4, speed_up=1.0)
    j = 10  # an output sample (t = 0.5 s): the frame at 0.5 s shows it exactly
    assert tiny.t[j] == pytest.approx(0.5)
    np.testing.assert_allclose(frames[2].x_m, tiny.segments["x_m"][j], rtol=0, atol=1e-12)
    np.testing.assert_allclose(frames[2].link_force_N, tiny.links["force_N"][j], rtol=0, atol=1e-9)
    # between samples: the linear interpolation of the two neighbours
    mid = animation.result_frames(tiny, fps=40, speed_up=1.0)[21]  # t = 0.525 s, halfway 0.5 -> 0.55
    np.testing.assert_allclose(mid.x_m, 0.5 * (tiny.segments["x_m"][10] + tiny.segments["x_m"][11]), atol=1e-12)


def _scene(grade_deg=None, n=3):
    raw = [f"vehicle.segments={n}", "simulation.duration_s=1"]
    if grade_deg is not None:
        raw.append(f"terrain.grade_deg={grade_deg}")
    sc = load_scenario(SCENARIOS / "tow6_uniform.yaml", raw)
    return sc, ChainScene.from_scenario(sc, force_scale_N=100.0)


def test_a_known_state_is_drawn_to_scale_on_level_ground():
    sc, scene = _scene()
    seg = sc.vehicle.segment
    R, b = seg.wheel_radius_m, seg.wheelbase_m
    x = np.array([3.0, 1.4, -0.2])
    F = np.array([60.0, -40.0])
    fig, ax = new_canvas()
    art = draw_chain(ax, ChainFrame(1.0, x, F, ""), scene)
    chassis = [p.vertices[:4] for p in art.chassis.get_paths()]
    for k in range(3):  # axle to axle, from the axles' height R up to 2R
        assert chassis[k][:, 0].min() == pytest.approx(x[k] - b / 2, abs=1e-12)
        assert chassis[k][:, 0].max() == pytest.approx(x[k] + b / 2, abs=1e-12)
        assert chassis[k][:, 1].min() == pytest.approx(R, abs=1e-12)
        assert chassis[k][:, 1].max() == pytest.approx(2 * R, abs=1e-12)
    wheels = np.array([p.vertices[:-1].mean(axis=0) for p in art.wheels.get_paths()]).reshape(3, 2, 2)
    np.testing.assert_allclose(wheels[..., 0], x[:, None] + [b / 2, -b / 2], atol=1e-12)
    np.testing.assert_allclose(wheels[..., 1], R, atol=1e-12)
    # a link runs from a segment's rear to the next one's front, coloured by its force
    ends = [p.vertices for p in art.links.get_paths()]
    assert ends[0][0, 0] == pytest.approx(x[0] - b / 2) and ends[0][1, 0] == pytest.approx(x[1] + b / 2)
    fig.canvas.draw()  # colours are mapped when drawn
    colours = art.links.get_colors()
    cmap = colormaps[animation.FORCE_CMAP]
    np.testing.assert_allclose(colours[0], cmap((60.0 + 100.0) / 200.0), atol=1e-9)
    assert colours[0][0] > colours[0][2] and colours[1][2] > colours[1][0]  # tension red, compression blue
    # the view window follows the chain, centred on its mean position, equal units on both axes
    lo, hi = ax.get_xlim()
    assert (lo + hi) / 2 == pytest.approx(np.mean(x)) and hi - lo == pytest.approx(scene.window_m)
    box = ax.get_window_extent()
    y0, y1 = ax.get_ylim()
    assert (y1 - y0) / (hi - lo) == pytest.approx(box.height / box.width, rel=1e-9)
    assert "t = 1.00 s" in art.text.get_text()


def test_a_known_state_on_a_grade_sits_on_the_slope():
    theta = math.radians(10.0)
    sc, scene = _scene(grade_deg=10.0, n=2)
    seg = sc.vehicle.segment
    R, b = seg.wheel_radius_m, seg.wheelbase_m
    x = np.array([2.0, 0.5])
    fig, ax = new_canvas()
    art = draw_chain(ax, ChainFrame(0.0, x, np.array([0.0]), ""), scene)
    wheels = np.array([p.vertices[:-1].mean(axis=0) for p in art.wheels.get_paths()]).reshape(2, 2, 2)
    # by hand: the contact point (s, s sin theta) of the ground z = s sin(theta), the centre R along the normal
    s_axle = x[:, None] + [b / 2, -b / 2]
    np.testing.assert_allclose(wheels[..., 0], s_axle - R * math.sin(theta), atol=1e-9)
    np.testing.assert_allclose(wheels[..., 1], s_axle * math.sin(theta) + R * math.cos(theta), atol=1e-9)
    ground = art.ground_line.get_xydata()
    np.testing.assert_allclose(ground[:, 1], ground[:, 0] * math.sin(theta), atol=1e-9)


def test_a_second_frame_moves_the_same_artists():
    sc, scene = _scene()
    fig, ax = new_canvas()
    x = np.array([3.0, 1.4, -0.2])
    a1 = draw_chain(ax, ChainFrame(0.0, x, np.zeros(2)), scene)
    before = np.array([p.vertices[:4] for p in a1.chassis.get_paths()])
    a2 = draw_chain(ax, ChainFrame(0.5, x + 0.7, np.zeros(2)), scene)
    after = np.array([p.vertices[:4] for p in a2.chassis.get_paths()])
    assert a2 is a1 and len(ax.collections) == len({id(c) for c in ax.collections})
    np.testing.assert_allclose(after[..., 0] - before[..., 0], 0.7, atol=1e-12)
    # another chain on the same axes replaces the first (no artists or colour bars left behind)
    n_artists = len(ax.collections), len(ax.child_axes), len(ax.texts)
    sc1, one = _scene(n=1)
    a3 = draw_chain(ax, ChainFrame(0.0, np.array([0.0]), np.zeros(0)), one)
    assert a3 is not a1 and (len(ax.collections), len(ax.child_axes), len(ax.texts)) == n_artists
    assert len(a3.chassis.get_paths()) == 1 and len(a3.links.get_paths()) == 0


def test_render_rgb_is_an_image():
    sc, scene = _scene()
    fig, ax = new_canvas()
    img = render_rgb(fig, ax, ChainFrame(0.0, np.array([3.0, 1.4, -0.2]), np.zeros(2)), scene)
    w, h = fig.canvas.get_width_height()
    assert img.shape == (h, w, 3) and img.dtype == np.uint8
    assert len(np.unique(img.reshape(-1, 3), axis=0)) > 10  # a picture, not a blank


def test_mp4_without_ffmpeg_is_refused(tiny, tmp_path, monkeypatch):
    monkeypatch.setattr(animation.shutil, "which", lambda name: None)
    with pytest.raises(AnimationOptionError, match="ffmpeg"):
        tiny.animate(tmp_path / "a.mp4")
    assert not list(tmp_path.iterdir())
    r = CliRunner().invoke(main, ["animate", str(tmp_path / "nowhere"), "--format", "mp4"])
    assert r.exit_code == 2 and "needs the ffmpeg program" in r.output and "--format gif" in r.output


def test_bad_options_name_the_fix(tiny, tmp_path):
    with pytest.raises(AnimationOptionError, match="speed-up of at least"):
        tiny.animate(tmp_path / "a.gif", fps=60, speed_up=0.01)  # 7201 frames
    with pytest.raises(AnimationOptionError, match="fps"):
        tiny.animate(tmp_path / "a.gif", fps=0)
    with pytest.raises(AnimationOptionError, match=r"must end in \.gif"):
        tiny.animate(tmp_path / "a.png", fmt="gif")
    assert not list(tmp_path.iterdir())


def test_animation_into_a_results_folder_keeps_it_snoworms(tiny, tmp_path):
    d = tmp_path / "run"
    tiny.write(d, plot=False)
    tiny.animate(d / "animation.gif", fps=2, speed_up=1.2)
    assert folder_state(d) == "snoworm" and "animation.gif" in read_manifest(d)["files"]
    tiny.write(d, plot=False)  # a later run into the folder replaces it as a whole (not refused as foreign)
    assert not (d / "animation.gif").exists()
    with folder_lock(d):  # another writer holds the folder: refused, nothing written
        with pytest.raises(OutputError, match="lock|process"):
            tiny.animate(d / "animation.gif", fps=2, speed_up=1.2)
    assert not (d / "animation.gif").exists() and folder_state(d) == "snoworm"


def test_cli_animate(tiny_dir, tmp_path):
    r = CliRunner().invoke(main, ["animate", str(tiny_dir), "--fps", "2", "--speed-up", "0.6", "--format", "gif"])
    assert r.exit_code == 0, r.output
    assert len(gif_frames(tiny_dir / "animation.gif")[0]) == math.floor(1.2 * 2 / 0.6 + 1e-9) + 1
    assert folder_state(tiny_dir) == "snoworm"
    mine = tmp_path / "mine.gif"
    mine.write_bytes(b"a user's file")
    r = CliRunner().invoke(main, ["animate", str(tiny_dir), "--format", "gif", "--out", str(mine)])
    assert r.exit_code == 2 and "--overwrite" in r.output and mine.read_bytes() == b"a user's file"
    r = CliRunner().invoke(main, ["animate", str(tiny_dir), "--fps", "1", "--out", str(tmp_path / "v" / "a.gif")])
    assert r.exit_code == 0, r.output  # the format from the suffix (whether ffmpeg is installed or not)
    assert len(gif_frames(tmp_path / "v" / "a.gif")[0]) == 2  # 1.2 s at 1 fps, speed-up 1: t = 0, 1 s
    r = CliRunner().invoke(main, ["animate", str(tmp_path), "--format", "gif"])
    assert r.exit_code == 2 and "not a snoworm run folder" in r.output


@pytest.mark.skipif(not animation.ffmpeg_available(), reason="needs the ffmpeg program")
def test_mp4_has_the_frames_of_its_duration_fps_and_speed_up(tiny, tmp_path):
    import re
    import subprocess

    path = tiny.animate(tmp_path / "a.mp4", fps=5, speed_up=0.6)
    out = subprocess.run(["ffmpeg", "-i", str(path), "-f", "null", "-"], capture_output=True, text=True, check=True)
    frames = int(re.findall(r"frame=\s*(\d+)", out.stderr)[-1])
    assert frames == math.floor(1.2 * 5 / 0.6 + 1e-9) + 1 and "yuv420p" in out.stderr
