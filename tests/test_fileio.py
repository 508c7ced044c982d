"""Atomic file writing (snoworm.fileio): a reader never sees a half-written file."""
import pytest

from snoworm.fileio import atomic_path, atomic_write_text


def test_atomic_write_text_writes_and_replaces(tmp_path):
    p = tmp_path / "sub" / "out.csv"
    assert atomic_write_text(p, "a,b\n1,2\n") == p          # creates the directory
    assert p.read_text() == "a,b\n1,2\n"
    atomic_write_text(p, "new\n")
    assert p.read_text() == "new\n"
    assert sorted(x.name for x in p.parent.iterdir()) == ["out.csv"]


def test_failure_leaves_no_temp_file_and_the_old_file_intact(tmp_path):
    p = tmp_path / "summary.json"
    p.write_text("old")
    with pytest.raises(RuntimeError, match="disk full"):
        with atomic_path(p) as tmp:
            tmp.write_text("half of the new conte")
            assert tmp.parent == p.parent and tmp.exists()
            raise RuntimeError("disk full")
    assert p.read_text() == "old"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["summary.json"]


def test_failure_before_any_file_leaves_nothing(tmp_path):
    p = tmp_path / "new.txt"
    with pytest.raises(KeyboardInterrupt):           # BaseException too: interrupted writes clean up
        with atomic_path(p):
            raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []


def test_failure_of_text_encoding_leaves_no_temp_file(tmp_path):
    p = tmp_path / "bad.txt"
    with pytest.raises(UnicodeEncodeError):
        atomic_write_text(p, "surrogate \udcff")
    assert list(tmp_path.iterdir()) == []
