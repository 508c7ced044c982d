"""Field data (snoworm.studies.field_data): the shipped Table 2 file, the reader's tolerance and its
messages (bad values through the CLI are in test_studies_calibrate.py)."""

from pathlib import Path

import numpy as np
import pytest

from snoworm.config.schema import ScenarioError
from snoworm.studies import field_data as fd

ROOT = Path(__file__).resolve().parents[1]
CASES = ("1", "2", "3", "4", "5")
HEADER = ",".join(fd.FIELD_COLUMNS)  # the field-data CSV header


def test_shipped_data_is_table2(data):
    assert data.case == CASES
    np.testing.assert_allclose(data.speed_mps, [2.5, 1.23, 1.98, 1.84, 1.11], rtol=0, atol=1e-12)
    np.testing.assert_allclose(data.wheel_speed_mps, [2.66, 1.28, 2.05, 1.93, 1.58], rtol=0, atol=1e-12)
    np.testing.assert_allclose(data.slip, [0.06, 0.039, 0.034, 0.047, 0.30], rtol=0, atol=1e-12)
    np.testing.assert_allclose(data.torque_Nm, [10, 27, 30, 32.8, 45], rtol=0, atol=1e-12)
    np.testing.assert_allclose(data.drawbar_N, [0, 0, 0, 28.8, 0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(data.xt, [1, 0.83, 0.8, 0.8, 0.65], rtol=0, atol=1e-12)
    # the repository copy (data/) is the package data
    assert (ROOT / "data" / "frostyboy_2020.csv").read_bytes() == fd.default_data_path().read_bytes()


def test_reader_tolerates_comments_blank_lines_extra_columns(tmp_path):
    f = tmp_path / "field.csv"
    f.write_text(
        "# my rover\n\n" + HEADER + ",note\n# a comment between rows\n"
        'a,"snow, wet",1.0,1.1,0.0909,20,0,0.9,x\n\n  # indented comment\nb,snow,1.0,1.1,0.09,21,5,0.9,y\n'
    )
    d = fd.read_field_data(f)
    assert d.case == ("a", "b")
    assert d.surface[0] == "snow, wet"
    np.testing.assert_allclose(d.drawbar_N, [0.0, 5.0], atol=0)


def test_bad_input_api_raises_scenario_error(tmp_path):
    with pytest.raises(ScenarioError, match="no such file"):
        fd.read_field_data(tmp_path / "missing.csv")


@pytest.mark.parametrize(
    "row, needle",
    [
        (
            "a,snow,1.0,1.1,6,20,0,0.9",
            r"slip 6 is outside \[-1, 1\]; slip is a fraction\. Did you give it in percent\?",
        ),
        ("a,snow,1.0,0,0.09,20,0,0.9", r"wheel_speed_mps must be greater than 0 m/s"),
        ("a,snow,1.0,1.1,0.09,20,0,1.5", r"xt must be in \(0, 1\], got 1\.5"),
        ("a,snow,1.0,1.1,0.09,20,,0.9", r"line 2, column 'drawbar_N': expected a number .* Write 0 for no drawbar\."),
        ("a,snow,1.0,1.1,0.09,inf,0,0.9", r"line 2, column 'torque_Nm': must be a finite number"),
        ("a,snow,1.0,1.1,0.09,20,0", r"line 2 has 7 fields but the header has 8"),
    ],
)
def test_each_bad_value_names_the_line_and_the_rule(tmp_path, row, needle):
    f = tmp_path / "field.csv"
    f.write_text(HEADER + "\n" + row + "\n")
    with pytest.raises(ScenarioError, match=needle):
        fd.read_field_data(f)


def test_missing_columns_duplicates_and_empty_files_are_refused(tmp_path):
    f = tmp_path / "field.csv"
    f.write_text(HEADER.replace("torque_Nm", "torque") + "\n")
    with pytest.raises(ScenarioError, match=r"missing column\(s\) 'torque_Nm'.*Did you mean 'torque'"):
        fd.read_field_data(f)
    f.write_text(HEADER + "\n")
    with pytest.raises(ScenarioError, match="has a header but no data rows"):
        fd.read_field_data(f)
    f.write_text("# only a comment\n\n")
    with pytest.raises(ScenarioError, match="no header and no data rows"):
        fd.read_field_data(f)
    f.write_text(HEADER + "\na,snow,1.0,1.1,0.09,20,0,0.9\na,ice,1.0,1.1,0.09,20,0,0.9\n")
    with pytest.raises(ScenarioError, match=r"case label\(s\) 'a' appear more than once"):
        fd.read_field_data(f)
