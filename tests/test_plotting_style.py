"""The figures' style and plumbing (snoworm.plotting.style): labels, force text, saving, axes."""
import struct

import pytest
from matplotlib.figure import Figure

from snoworm.plotting.style import COLOURS, DPI, force_text, new_figure, quantity_label, save, series_style


@pytest.mark.parametrize("key, label", [
    ("tow.force_N", "tow force [N]"),
    ("terrain.xt", "terrain coefficient X_t"),
    ("simulation.duration_s", "simulation duration [s]"),
    ("vehicle.links.stiffness_N_per_m", "links stiffness [N/m]"),
    ("mode.target_speed_mps", "mode target speed [m/s]"),
    ("mean_speed_mps", "mean speed [m/s]"),
])
def test_quantity_label_words_and_units(key, label):
    assert quantity_label(key) == label
    assert "." not in quantity_label(key).split("[")[0]      # no dotted keys left


@pytest.mark.parametrize("value, text", [(-0.04, "0.0 N"), (-0.0, "0.0 N"), (0.049, "0.0 N"), (-1.26, "-1.3 N"),
                                         (2, "+2.0 N"), (-165.33, "-165.3 N")])
def test_force_text_never_prints_minus_zero(value, text):
    assert force_text(value) == text


def test_series_styles_differ_beyond_colour():
    styles = [series_style(k, 100) for k in range(6)]
    for key in ("color", "ls", "marker"):
        assert len({repr(s[key]) for s in styles}) == 6, key
    assert all(c.startswith("#") for c in COLOURS)


def _png_size(path):
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])


def test_save_formats_and_resolution(tmp_path):
    fig = Figure(figsize=(4, 3))
    fig.subplots().plot([0, 1], [1, 0])
    p = save(fig, tmp_path / "a.png")
    assert DPI >= 200 and _png_size(p) == (4 * DPI, 3 * DPI)
    assert save(fig, tmp_path / "a.png", "pdf").read_bytes()[:5] == b"%PDF-"     # suffix follows the format
    assert b"<svg" in save(fig, tmp_path / "b", "svg").read_bytes()
    with pytest.raises(ValueError, match="png, pdf, svg"):
        save(fig, tmp_path / "c.jpg")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.pdf", "a.png", "b.svg"]   # no temporary files


def test_new_figure_uses_the_given_axes_or_figure():
    user = Figure()
    axes = user.subplots(2, 1)
    fig, got = new_figure(ax=axes, nrows=2)
    assert fig is user and got.shape == (2, 1) and got[1, 0] is axes[1]
    with pytest.raises(ValueError, match="2 panel"):
        new_figure(ax=axes[0], nrows=2)
    fig2, got2 = new_figure(fig=user, nrows=1, ncols=3)
    assert fig2 is user and got2.shape == (1, 3) and len(user.axes) == 5
    fig3, _ = new_figure()
    assert isinstance(fig3, Figure) and fig3 is not user
