"""Manifests never reach outside --out (issue 24, critical): hostile folders built in tmp_path.

Every hostile folder sits beside a sentinel file OUTSIDE it; each test asserts the sentinel
survives, and the exit status and message of the refusal.
"""

from __future__ import annotations

import json
import os
import threading

import pytest
from click.testing import CliRunner

from snoworm.cli import main
from snoworm.infra.folders import OutputError, atomic_write_text, folder_report, folder_state, output_folder
from snoworm.infra.manifest import (
    MANIFEST,
    MAX_MANIFEST_BYTES,
    ManifestProblem,
    entry_problem,
    load_manifest,
    read_small_file,
    short,
)

SHORT = ["--set", "simulation.duration_s=2", "--no-plot"]


def cli(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture
def sentinel(tmp_path):
    """A precious file outside every output folder of the test."""
    d = tmp_path / "outside"
    d.mkdir()
    s = d / "thesis.tex"
    s.write_text("precious")
    return s


def _manifest(folder, files):
    (folder / MANIFEST).write_text(json.dumps({"snoworm_version": "0", "command": "x", "files": files}))


def _hostile(tmp_path, sentinel, kind):
    """A folder whose manifest names the sentinel (or is itself hostile); returns it."""
    out = tmp_path / "received"
    out.mkdir()
    (out / "summary.json").write_text("{}")
    entries = {
        "absolute": [str(sentinel)],
        "dotdot": ["../outside/thesis.tex"],
        "dot": ["./summary.json"],
        "nonstring": [1, None, {"a": 1}],
        "nul": ["a\x00b"],
        "backslash": ["..\\outside\\thesis.tex"],
    }
    if kind in entries:
        _manifest(out, entries[kind] + ["summary.json"])
    elif kind == "symlinked_subfolder":
        os.symlink(sentinel.parent, out / "sub")
        _manifest(out, ["sub/thesis.tex", "summary.json"])
    elif kind == "fifo":
        os.mkfifo(out / MANIFEST)
    elif kind == "dev_zero":
        os.symlink("/dev/zero", out / MANIFEST)
    elif kind == "symlink_manifest":
        other = tmp_path / "elsewhere.json"
        other.write_text(json.dumps({"files": ["summary.json"]}))
        os.symlink(other, out / MANIFEST)
    elif kind == "oversized":
        with open(out / MANIFEST, "wb") as fh:  # sparse: no disk used, never read
            fh.truncate(MAX_MANIFEST_BYTES + 1)
    elif kind == "not_an_object":
        (out / MANIFEST).write_text("[" * 100000)
    else:
        raise AssertionError(kind)
    return out


KINDS = [
    "absolute",
    "dotdot",
    "dot",
    "nonstring",
    "nul",
    "backslash",
    "symlinked_subfolder",
    "fifo",
    "dev_zero",
    "symlink_manifest",
    "oversized",
    "not_an_object",
]


def _bounded(fn, *args):
    """fn(*args) in a thread that must end within 30 s (a FIFO read would block forever)."""
    box = {}

    def target():
        try:
            box["value"] = fn(*args)
        except BaseException as exc:  # noqa: BLE001 - handed back to the test
            box["error"] = exc

    th = threading.Thread(target=target, daemon=True)
    th.start()
    th.join(30)
    assert not th.is_alive(), f"{fn.__name__} blocked on a hostile manifest"
    if "error" in box:
        raise box["error"]
    return box["value"]


@pytest.mark.parametrize("kind", KINDS)
def test_a_hostile_manifest_makes_the_folder_foreign_and_nothing_is_touched(tmp_path, sentinel, kind):
    out = _hostile(tmp_path, sentinel, kind)
    state, why = _bounded(folder_report, out)
    assert state == "foreign" and why
    with pytest.raises(OutputError, match="--overwrite"):
        _bounded(lambda: output_folder(out).__enter__())
    with output_folder(out, overwrite=True) as stage:  # overwrite: same-named files only
        atomic_write_text(stage / "summary.json", '{"new": 1}')
    assert sentinel.read_text() == "precious"
    assert json.loads((out / "summary.json").read_text()) == {"new": 1}


@pytest.mark.parametrize("kind", ["absolute", "dotdot", "symlinked_subfolder", "fifo", "oversized", "nonstring"])
def test_run_and_sweep_refuse_a_hostile_folder_with_exit_2_and_overwrite_spares_the_outside(tmp_path, sentinel, kind):
    out = _hostile(tmp_path, sentinel, kind)
    r = cli("run", "tow6_uniform", "--out", out, *SHORT)
    assert r.exit_code == 2, r.output
    assert str(out) in r.output and "--overwrite" in r.output
    r = cli("run", "tow6_uniform", "--out", out, *SHORT, "--overwrite")
    assert r.exit_code == 0, r.output
    assert sentinel.read_text() == "precious"
    (tmp_path / "s").mkdir()
    out2 = _hostile(tmp_path / "s", sentinel, kind)
    r = cli(
        "sweep",
        "tow6_uniform",
        "--set",
        "terrain.xt=0.7",
        "--set",
        "simulation.duration_s=2",
        "--out",
        out2,
        "--no-plot",
    )
    assert r.exit_code == 2, r.output
    assert str(out2) in r.output
    assert sentinel.read_text() == "precious"


def test_a_symlinked_out_with_a_hostile_manifest_touches_nothing_outside(tmp_path, sentinel):
    real = _hostile(tmp_path, sentinel, "absolute")
    link = tmp_path / "link"
    os.symlink(real, link)
    r = cli("run", "tow6_uniform", "--out", link, *SHORT)
    assert r.exit_code == 2 and "is an absolute path" in r.output, r.output
    r = cli("run", "tow6_uniform", "--out", link, *SHORT, "--overwrite")
    assert r.exit_code == 0, r.output
    assert sentinel.read_text() == "precious" and link.is_symlink()


def test_a_command_run_from_inside_a_hostile_out_touches_nothing_outside(tmp_path, sentinel, monkeypatch):
    out = _hostile(tmp_path, sentinel, "dotdot")
    monkeypatch.chdir(out)
    r = cli("run", "tow6_uniform", "--out", ".", *SHORT, "--overwrite")
    assert r.exit_code == 0, r.output
    assert sentinel.read_text() == "precious"


def test_a_trusted_snoworm_folder_is_still_replaced_as_a_whole(tmp_path, sentinel):
    out = tmp_path / "run"
    assert cli("run", "tow6_uniform", "--out", out, *SHORT).exit_code == 0
    assert folder_state(out) == "snoworm"
    assert cli("run", "tow6_uniform", "--out", out, *SHORT).exit_code == 0
    assert sentinel.read_text() == "precious"


def test_overwrite_never_removes_a_users_folder_carrying_an_outputs_name(tmp_path):
    out = tmp_path / "mine"
    (out / "scenario.yaml").mkdir(parents=True)
    (out / "scenario.yaml" / "draft.txt").write_text("mine")
    r = cli("run", "tow6_uniform", "--out", out, *SHORT, "--overwrite")
    assert r.exit_code == 2, r.output
    assert "scenario.yaml" in r.output and "did not write" in r.output
    assert (out / "scenario.yaml" / "draft.txt").read_text() == "mine"
    assert sorted(os.listdir(out)) == ["scenario.yaml"]  # nothing written beside it


def test_a_sweep_over_a_hostile_earlier_sweep_with_overwrite_touches_nothing_outside(tmp_path, sentinel):
    out = tmp_path / "s"
    args = ["sweep", "tow6_uniform", "--set", "simulation.duration_s=2", "--out", out, "--no-plot"]
    assert cli(*args, "--set", "terrain.xt=0.7").exit_code == 0
    man = json.loads((out / MANIFEST).read_text())
    man["files"].append(str(sentinel))
    (out / MANIFEST).write_text(json.dumps(man))
    r = cli(*args, "--set", "terrain.xt=0.9", "--overwrite")  # another sweep: the old one cleared
    assert r.exit_code == 0, r.output
    assert sentinel.read_text() == "precious"


def test_a_resumed_save_cases_sweep_never_writes_through_a_planted_symlink(tmp_path, sentinel):
    out = tmp_path / "s"
    args = [
        "sweep",
        "tow6_uniform",
        "--set",
        "terrain.xt=0.7,0.9",
        "--set",
        "simulation.duration_s=2",
        "--out",
        out,
        "--no-plot",
        "--save-cases",
    ]
    assert cli(*args).exit_code == 0
    cases = sorted(os.listdir(out / "cases"))
    lines = (out / "summary.csv").read_text().splitlines(keepends=True)
    (out / "summary.csv").write_text("".join(lines[:-1]))  # the last case "not yet run"
    victim = out / "cases" / cases[-1]
    for f in os.listdir(victim):
        os.unlink(victim / f)
    victim.rmdir()
    os.symlink(sentinel.parent, victim)
    before = sorted(os.listdir(sentinel.parent))
    r = cli(*args)
    assert r.exit_code == 2, r.output
    assert str(victim) in r.output and "symbolic link" in r.output
    assert sorted(os.listdir(sentinel.parent)) == before and sentinel.read_text() == "precious"
    os.unlink(victim)  # the fix: the sweep resumes
    r = cli(*args)
    assert r.exit_code == 0, r.output
    assert folder_state(victim) == "snoworm"


def test_a_summary_csv_symlink_is_never_appended_through(tmp_path, sentinel):
    out = tmp_path / "s"
    args = [
        "sweep",
        "tow6_uniform",
        "--set",
        "terrain.xt=0.7",
        "--set",
        "simulation.duration_s=2",
        "--out",
        out,
        "--no-plot",
    ]
    assert cli(*args).exit_code == 0
    os.unlink(out / "summary.csv")
    os.symlink(sentinel, out / "summary.csv")
    r = cli(*args)
    assert r.exit_code == 2 and "summary.csv is not a regular file" in r.output, r.output
    assert sentinel.read_text() == "precious"


# ------------------------------------------------------------------ the checks themselves
@pytest.mark.parametrize(
    "entry,ok",
    [
        ("a.csv", True),
        ("cases/c0/segments.csv", True),
        ("/etc/passwd", False),
        ("../x", False),
        ("a/../b", False),
        ("./a", False),
        ("a//b", False),
        ("", False),
        ("a\\b", False),
        ("a\x00", False),
        (3, False),
        ("x" * 5000, False),
        (MANIFEST, False),
    ],
)
def test_entry_rules(entry, ok):
    assert (entry_problem(entry) is None) == ok


def test_read_small_file_refuses_fifos_devices_symlinks_and_big_files_unread(tmp_path):
    os.mkfifo(tmp_path / "fifo")
    with pytest.raises(ManifestProblem, match="not a regular file"):
        _bounded(read_small_file, tmp_path / "fifo", 100)
    os.symlink("/dev/zero", tmp_path / "zero")
    with pytest.raises(ManifestProblem, match="symbolic link"):
        _bounded(read_small_file, tmp_path / "zero", 100)
    with pytest.raises(ManifestProblem, match="not a regular file"):
        _bounded(read_small_file, "/dev/zero", 100)
    (tmp_path / "big").write_bytes(b"x" * 101)
    with pytest.raises(ManifestProblem, match="101 bytes"):
        read_small_file(tmp_path / "big", 100)
    (tmp_path / "ok").write_bytes(b"x" * 100)
    assert read_small_file(tmp_path / "ok", 100) == b"x" * 100


def test_load_manifest_names_the_problem(tmp_path):
    assert load_manifest(tmp_path) is None
    _manifest(tmp_path, ["ok.csv", "/abs"])
    with pytest.raises(ManifestProblem, match="absolute path"):
        load_manifest(tmp_path)
    (tmp_path / MANIFEST).write_text('{"files": "a.csv"}')
    with pytest.raises(ManifestProblem, match="'files' list"):
        load_manifest(tmp_path)


def test_messages_quote_at_most_about_100_characters():
    assert len(short("x" * 10**6)) <= 100
    assert len(entry_problem("../" + "y" * 10**5)) < 300


def test_a_manifest_changed_after_a_good_one_is_checked_again(tmp_path):
    """The entries' checks are skipped only for the very bytes checked last (a command reads its
    folder's manifest several times): a manifest rewritten with a bad entry is refused."""
    from snoworm.infra.manifest import MANIFEST, ManifestProblem, load_manifest

    (tmp_path / MANIFEST).write_text(json.dumps({"files": ["a.csv", "b/c.csv"]}))
    assert load_manifest(tmp_path)["files"] == ["a.csv", "b/c.csv"]
    assert load_manifest(tmp_path)["files"] == ["a.csv", "b/c.csv"]
    (tmp_path / MANIFEST).write_text(json.dumps({"files": ["a.csv", "/etc/passwd"]}))
    with pytest.raises(ManifestProblem, match="absolute path"):
        load_manifest(tmp_path)
