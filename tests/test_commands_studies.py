"""The study commands (snoworm.commands.studies), added by snoworm.cli to the snoworm group."""

from click.testing import CliRunner

from snoworm.cli import main
from snoworm.commands.studies import STUDY_COMMANDS


def test_every_study_command_is_in_the_group_under_its_name():
    names = {c.name for c in STUDY_COMMANDS}
    assert names == {"groundtruth", "terrain-curves", "calibrate", "mobility-map", "paper"}
    for c in STUDY_COMMANDS:
        assert main.get_command(None, c.name) is c
        r = CliRunner().invoke(main, [c.name, "--help"])
        assert r.exit_code == 0 and "Usage:" in r.output, r.output


def test_terrain_curves_writes_its_table_and_bad_input_is_exit_2(tmp_path):
    r = CliRunner().invoke(
        main,
        ["terrain-curves", "--xt", "1", "--xt", "0.5", "--points", "11", "--no-plot", "--out", str(tmp_path / "tc")],
    )
    assert r.exit_code == 0, r.output
    lines = (tmp_path / "tc" / "terrain_curves.csv").read_text().splitlines()
    assert len(lines) == 1 + 2 * 11  # a header, then 11 slips for each X_t
    bad = CliRunner().invoke(main, ["terrain-curves", "--xt", "inf", "--out", str(tmp_path / "bad")])
    assert bad.exit_code == 2 and not (tmp_path / "bad").exists()
