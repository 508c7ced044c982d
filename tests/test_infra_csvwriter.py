"""snoworm.infra.csvwriter: cell formatting, CSV text, atomic writing."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from snoworm.infra import csvwriter
from snoworm.infra.csvwriter import FULL, SHORT, CellFormat, csv_text, format_cell, write_csv


@pytest.mark.parametrize(
    "value, short, full",
    [
        (None, "", ""),
        (True, "1", "true"),
        (np.bool_(False), "0", "false"),
        (3, "3", "3"),
        (np.int64(-7), "-7", "-7"),
        (0.1 + 0.2, "0.3", "0.30000000000000004"),
        (np.float64(1234567.0), "1.23457e+06", "1234567.0"),
        (-0.0, "-0", "-0.0"),
        (math.nan, "nan", "nan"),
        ("a,b", "a,b", "a,b"),
        ([1.5, {"b": 1, "a": 2}], '[1.5,{"a":2,"b":1}]', '[1.5,{"a":2,"b":1}]'),
    ],
)
def test_format_cell(value, short, full):
    assert format_cell(value, SHORT) == short
    assert format_cell(value, FULL) == full


def test_csv_text_from_mappings_and_sequences():
    fmt = CellFormat(comma=";")
    text = csv_text(["x", "note", "ok"], [{"x": 0.5, "note": "a, b", "ok": True}, [1e-7, 'say "hi"', None]], fmt)
    assert text == 'x,note,ok\n0.5,a; b,1\n1e-07,"say ""hi""",\n'
    assert csv_text(["x", "note"], [{"x": 2.0}]) == "x,note\n2,\n"
    assert csv_text(("a", "b"), []) == "a,b\n"


def test_write_csv_is_atomic(tmp_path, monkeypatch):
    path = tmp_path / "t.csv"
    assert write_csv(path, ["a"], [[1.0]]) == path and path.read_text() == "a\n1\n"

    def rows():
        yield [2.0]
        raise RuntimeError("computation failed half way")

    with pytest.raises(RuntimeError):
        write_csv(path, ["a"], rows())
    assert path.read_text() == "a\n1\n"  # the old file is untouched

    def no_disk(fd):
        raise OSError("disk full")

    monkeypatch.setattr(csvwriter.atomic_write_text.__globals__["os"], "fsync", no_disk)
    fresh = tmp_path / "new.csv"
    with pytest.raises(OSError, match="disk full"):
        write_csv(fresh, ["a"], [[1.0]])
    with pytest.raises(OSError, match="disk full"):
        write_csv(path, ["a"], [[3.0]])
    assert not fresh.exists() and path.read_text() == "a\n1\n"
    assert sorted(os.listdir(tmp_path)) == ["t.csv"]  # no temporary file left behind
