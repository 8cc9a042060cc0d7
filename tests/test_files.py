"""Output files are written to a temporary name and renamed when complete."""

import os

import pytest

from pkdyn.exceptions import OutputError
from pkdyn.files import atomic_path, atomic_write


def test_complete_write_replaces_the_file(tmp_path):
    out = tmp_path / "a.csv"
    out.write_text("old")
    with atomic_write(out) as fh:
        fh.write("new")
        assert out.read_text() == "old"  # not visible until complete
    assert out.read_text() == "new"
    assert os.listdir(tmp_path) == ["a.csv"]


def test_interrupted_write_keeps_the_old_file(tmp_path):
    out = tmp_path / "a.csv"
    out.write_text("old")
    with pytest.raises(KeyboardInterrupt), atomic_write(out) as fh:
        fh.write("half")
        raise KeyboardInterrupt
    assert out.read_text() == "old"
    assert os.listdir(tmp_path) == ["a.csv"]


def test_temporary_path_keeps_the_suffix(tmp_path):
    with atomic_path(tmp_path / "plot.png") as tmp:
        assert tmp.suffix == ".png" and tmp.parent == tmp_path
        tmp.write_bytes(b"png")
    assert (tmp_path / "plot.png").read_bytes() == b"png"


def test_new_file_gets_default_permissions(tmp_path):
    umask = os.umask(0o022)
    try:
        with atomic_write(tmp_path / "x.txt") as fh:
            fh.write("x")
    finally:
        os.umask(umask)
    assert (tmp_path / "x.txt").stat().st_mode & 0o777 == 0o644


@pytest.mark.parametrize("name", ["missing/x.csv", "."])
def test_bad_target_is_an_output_error_naming_it(tmp_path, name):
    with pytest.raises(OutputError, match="cannot write"), atomic_write(tmp_path / name) as fh:
        fh.write("x")
