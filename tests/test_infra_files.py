"""A user's small file read without hanging (snoworm.infra.files): regular files only, bounded."""

import os

import pytest

from snoworm.infra.files import FileProblem, read_regular_file


def test_a_regular_file_is_read_whole(tmp_path):
    p = tmp_path / "a.txt"
    p.write_bytes(b"x" * 1000)
    assert read_regular_file(p, 1000) == b"x" * 1000


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs on this platform")
def test_a_fifo_is_refused_at_once_not_waited_on(tmp_path):
    """Opened with O_NONBLOCK: no writer is needed for the refusal (a plain open() blocks forever)."""
    p = tmp_path / "scenario.yaml"
    os.mkfifo(p)
    with pytest.raises(FileProblem, match=r"^not a regular file \(a FIFO") as err:
        read_regular_file(p, 1000)
    assert not err.value.too_large


@pytest.mark.parametrize("path", ["/dev/zero", "folder"])
def test_a_device_or_a_folder_is_refused(tmp_path, path):
    if path == "folder":
        path = tmp_path
    elif not os.path.exists(path):
        pytest.skip(f"no {path} here")
    with pytest.raises(FileProblem, match="not a regular file"):
        read_regular_file(path, 1000)


def test_a_file_larger_than_the_limit_is_refused_unread(tmp_path):
    p = tmp_path / "big.csv"
    p.write_bytes(b"1" * 1001)
    with pytest.raises(FileProblem, match=r"^1001 bytes, more than the 1000 accepted") as err:
        read_regular_file(p, 1000)
    assert err.value.too_large


@pytest.mark.skipif(not hasattr(os, "symlink"), reason="no symlinks on this platform")
def test_symlinks_are_followed_unless_asked_not_to(tmp_path):
    target = tmp_path / "t.txt"
    target.write_bytes(b"abc")
    link = tmp_path / "l.txt"
    link.symlink_to(target)
    assert read_regular_file(link, 10) == b"abc"
    with pytest.raises(OSError):
        read_regular_file(link, 10, follow_symlinks=False)


def test_a_missing_file_raises_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError):
        read_regular_file(tmp_path / "nope", 10)
