"""The figures' style and plumbing (snoworm.plotting.style): labels, force text, saving, axes."""

import struct

import pytest
from matplotlib.figure import Figure

from snoworm.plotting.style import COLOURS, DPI, force_text, new_figure, quantity_label, save, series_style


@pytest.mark.parametrize(
    "key, label",
    [
        ("tow.force_N", "tow force [N]"),
        ("terrain.xt", "terrain coefficient X_t"),
        ("simulation.duration_s", "simulation duration [s]"),
        ("vehicle.links.stiffness_N_per_m", "links stiffness [N/m]"),
        ("mode.target_speed_mps", "mode target speed [m/s]"),
        ("mean_speed_mps", "mean speed [m/s]"),
    ],
)
def test_quantity_label_words_and_units(key, label):
    assert quantity_label(key) == label
    assert "." not in quantity_label(key).split("[")[0]  # no dotted keys left


@pytest.mark.parametrize(
    "value, text",
    [
        (-0.04, "0.0 N"),
        (-0.0, "0.0 N"),
        (0.049, "0.0 N"),
        (-1.26, "\u22121.3 N"),
        (2, "+2.0 N"),
        (-165.33, "\u2212165.3 N"),
    ],
)
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
    assert save(fig, tmp_path / "a.png", "pdf").read_bytes()[:5] == b"%PDF-"  # suffix follows the format
    assert b"<svg" in save(fig, tmp_path / "b", "svg").read_bytes()
    with pytest.raises(ValueError, match="png, pdf, svg"):
        save(fig, tmp_path / "c.jpg")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.pdf", "a.png", "b.svg"]  # no temporary files


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


# ---------------------------------------------------------------------------- print sizes and fonts
import re  # noqa: E402

import matplotlib  # noqa: E402

from snoworm import load_scenario, simulate  # noqa: E402
from snoworm.plotting import FIGURE_SIZES, PLOT_KINDS, figure_style, headless, parse_size, plot_result  # noqa: E402
from tests.conftest import SCENARIOS  # noqa: E402
from tests.figure_checks import problems  # noqa: E402


@pytest.fixture(scope="module")
def runs():
    return {
        n: simulate(load_scenario(SCENARIOS / f"{n}.yaml", ["simulation.duration_s=4"]))
        for n in ("inchworm6", "pi3_equal", "tow6_uniform")
    }


@pytest.mark.parametrize("size", ["column", "page"])
def test_every_run_figure_is_readable_at_print_size(runs, size):
    """Width, text >= 7 pt, no label overlapping another, everything inside the figure."""
    with headless():
        for name, res in runs.items():
            for kind, draw in PLOT_KINDS.items():
                fig = draw(res, size=size)
                assert problems(fig, FIGURE_SIZES[size]) == [], (name, kind)


def test_sizes_parse_and_bad_ones_say_the_rule():
    assert parse_size("column") == 3.5 and parse_size("PAGE") == 7.16 and parse_size(None) is None
    assert parse_size("3.5x2.25") == (3.5, 2.25) and parse_size((4, 3)) == (4.0, 3.0)
    for bad in ("colum", "3.5", "0.2x3", "3x100"):
        with pytest.raises(ValueError, match="figure size"):
            parse_size(bad)


def test_style_never_changes_the_users_rcparams(runs):
    before = dict(matplotlib.rcParams)
    with headless():
        fig = runs["pi3_equal"].plot("forces", size="column")
    assert dict(matplotlib.rcParams) == before
    assert fig.get_size_inches()[0] == 3.5
    with figure_style("column"):
        assert matplotlib.rcParams["pdf.fonttype"] == 42 and matplotlib.rcParams["svg.fonttype"] == "none"
    assert dict(matplotlib.rcParams) == before


def test_pdf_embeds_truetype_and_svg_keeps_text(runs, tmp_path):
    """Column-width PDFs: 3.5 in (252 pt) wide, fonts TrueType (FontFile2), no Type 3; SVGs hold <text>."""
    res = runs["inchworm6"]
    pdfs = plot_result(res, tmp_path / "pdf", "pdf", size="column")
    for p in pdfs:
        data = p.read_bytes()
        assert b"/Subtype /Type3" not in data, p.name
        # fonttype 42: TrueType outlines (FontFile2), as a simple TrueType or a CID font over TrueType
        assert b"/FontFile2" in data and (b"/Subtype /TrueType" in data or b"/Subtype /CIDFontType2" in data), p.name
        box = re.search(rb"/MediaBox \[\s*0 0 ([0-9.]+) ([0-9.]+)\s*\]", data)
        assert box and float(box.group(1)) == pytest.approx(252.0, abs=0.01), p.name
    svgs = plot_result(res, tmp_path / "svg", "svg", size="3.5x3")
    for p in svgs:
        text = p.read_text(encoding="utf-8")
        assert "<text" in text, p.name
        assert 'width="252pt"' in text, p.name


def test_save_embeds_truetype_for_figures_drawn_elsewhere(tmp_path):
    fig = Figure(figsize=(3.5, 2))
    fig.subplots().set_title("−resistance")
    data = save(fig, tmp_path / "own.pdf").read_bytes()
    assert b"/Subtype /Type3" not in data and b"/FontFile2" in data


def test_the_readability_check_can_fail():
    """tests/figure_checks.problems finds small text, overlapping legend entries and labels
    outside the figure (so the readability tests above can fail)."""
    fig = Figure(figsize=(3.5, 2.5), layout="constrained")
    a = fig.subplots()
    for k in range(3):
        a.plot([0, 1], [k, k], label=f"a rather long label number {k}")
    a.legend(loc="lower left", bbox_to_anchor=(0, 1.02, 1, 0.1), mode="expand", ncol=3)  # entries collide
    a.set_xlabel("tiny", fontsize=5)
    a.text(1.5, 0.5, "far outside", transform=a.transAxes)
    found = " | ".join(problems(fig, 3.5))
    assert "'tiny' at 5.0 pt" in found
    assert "legend.text" in found and "overlaps" in found
    assert "'far outside' sticks out" in found


@pytest.mark.parametrize(
    "size", [True, False, 3.5, (3.5,), (1, 2, 3), [True, True], ("3", "2"), b"3x2", {"w": 3}, [None, 2]]
)
def test_a_figure_size_that_is_not_a_size_is_a_value_error_naming_the_rule(size):
    """Issue 30: Result.write(figure_size=True) was a TypeError ('bool' object is not iterable)."""
    from snoworm.plotting.style import parse_size

    with pytest.raises(ValueError, match=r"figure size .*expected column, page, 'WxH'"):
        parse_size(size)


def test_a_long_figure_size_is_not_echoed_in_full():
    """Hostile battery (benchmarks/hostile.py): a 14 000-character --figure-size came back whole."""
    from snoworm.plotting.style import parse_size

    with pytest.raises(ValueError, match="figure size") as info:
        parse_size("3.5x2.5" * 2000)
    assert len(str(info.value)) < 200


def test_result_write_checks_the_figure_size_before_writing(tmp_path):
    from snoworm import load_scenario, simulate

    res = simulate(load_scenario("tow6_uniform", ["simulation.duration_s=0.2"]))
    with pytest.raises(ValueError, match="figure size True"):
        res.write(tmp_path / "o", figure_size=True)
    assert not (tmp_path / "o").exists()


# ---------------------------------------------------------------------------- pyplot's global state
import json  # noqa: E402
import os  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402

from tests.conftest import ROOT  # noqa: E402

#: A fresh interpreter that draws figures and prints pyplot's global state after each step:
#: interactive mode, the backend and a full copy of rcParams.  ``kernel``: an IPython shell with
#: the inline backend, as a Jupyter kernel has (loading that backend turns interactive mode on);
#: ``script``: a plain interpreter whose user chose the svg backend.  ``user``: the user's own
#: figure only (the reference); ``snoworm``: snoworm's figures first (pyplot first imported
#: inside them), then the user's own, then snoworm's again.
_STATE_SCRIPT = """
import json, sys
env, who = sys.argv[1], sys.argv[2]
if env == "kernel":
    from IPython.core.interactiveshell import InteractiveShell
    InteractiveShell.instance()
import matplotlib
if env == "script":
    matplotlib.use("svg")

def state(step):
    p = matplotlib.rcParams
    rc = {k: repr(p[k]) for k in sorted(p)}
    print(json.dumps({"step": step, "interactive": matplotlib.is_interactive(), "backend": matplotlib.get_backend(), "rc": rc}))

def users_figure():
    import matplotlib.pyplot as plt
    plt.figure()
    plt.plot([0, 1], [1, 0])

def snoworm_figures():
    import snoworm
    from snoworm import plotting
    sc = snoworm.load_scenario("tow6_uniform").with_({"simulation.duration_s": 0.5})
    res = snoworm.simulate(sc)
    res.plot("speeds")
    res.plot("forces", size="column")
    plotting.compare([res, res], "speeds", labels=["a", "b"], size="3.5x3")
    with plotting.headless():
        fig = res.plot("slip")
    plotting.save(fig, sys.argv[3] + "/slip.pdf")

if who == "user":
    users_figure()
    state("user")
else:
    snoworm_figures()
    state("snoworm")
    users_figure()
    state("snoworm, then the user's")
    snoworm_figures()
    state("snoworm again")
"""


def _pyplot_states(env, who, tmp_path):
    environ = {**os.environ, "PYTHONPATH": str(ROOT)}
    environ.pop("MPLBACKEND", None)
    if env == "kernel":
        environ["MPLBACKEND"] = "module://matplotlib_inline.backend_inline"  # what ipykernel sets
    r = subprocess.run(
        [sys.executable, "-c", _STATE_SCRIPT, env, who, str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=tmp_path,
        env=environ,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    return [json.loads(line) for line in r.stdout.splitlines() if line.startswith("{")]


@pytest.mark.parametrize("env", ["kernel", "script"])
def test_figures_never_change_pyplots_global_state(env, tmp_path):
    """snoworm's figures leave interactive mode, the backend and every rcParam as the user's own
    figure leaves them, whether pyplot is first imported inside snoworm's style or before
    (issue 30: in a Jupyter kernel, interactive mode was left off after snoworm's first figure,
    and no later figure of the session showed)."""
    if env == "kernel":
        pytest.importorskip("IPython")
        pytest.importorskip("matplotlib_inline")
    (reference,) = _pyplot_states(env, "user", tmp_path)
    assert reference["interactive"] is (env == "kernel")  # the inline backend turns it on
    assert reference["backend"] == ("module://matplotlib_inline.backend_inline" if env == "kernel" else "svg")
    states = _pyplot_states(env, "snoworm", tmp_path)
    assert len(states) == 3
    for s in states:
        assert s["interactive"] == reference["interactive"], s["step"]
        assert s["backend"] == reference["backend"], s["step"]
        changed = sorted(k for k in reference["rc"] if s["rc"].get(k) != reference["rc"][k])
        assert changed == [] and s["rc"].keys() == reference["rc"].keys(), (s["step"], changed)
