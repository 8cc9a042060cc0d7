"""Outputs go to regular files only, inputs are read from regular files only, errors are one line.

- an output path that is a FIFO, a device, a directory, a dangling link, or a link through
  ``/dev`` or ``/proc`` (``/dev/stdout``) is refused, before any work, and left as it was; a
  link to a regular file is followed: the file is written atomically and the link kept;
- a name longer than the file system allows is refused with its length (also the study's
  derived files: the partial file adds 13 characters);
- a figure's extension is checked before the work;
- a study file or a catalog that is a FIFO, a device or too large is refused before it is
  opened (reading never blocks);
- an error or a warning whose text holds a library's multi-line message is printed on one line.
"""

import os
import stat
import threading
import time
import warnings

import pytest

import pkdyn.cli as cli
from pkdyn.cli import main
from pkdyn.design.table import output_paths
from pkdyn.exceptions import OutputError, PkdynError, StudyError
from pkdyn.files import atomic_write, output_target, read_text


def _one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.startswith("pkdyn: error:") and len(err.strip().splitlines()) == 1, err
    return err


@pytest.fixture
def fifo(tmp_path):
    """A FIFO; a thread feeds it after 20 s, so that a regression fails instead of hanging."""
    path = tmp_path / "fifo.csv"
    os.mkfifo(path)
    done = threading.Event()

    def unblock():
        if not done.wait(20.0):
            with open(path, "w") as fh:  # a reader is blocked on it: release it
                fh.write("garbage")

    threading.Thread(target=unblock, daemon=True).start()
    yield path
    done.set()


# ---------------------------------------------------------------------- outputs


def test_a_link_to_a_regular_file_is_followed_and_kept(tmp_path):
    real = tmp_path / "real.urdf"
    real.write_text("old")
    link = tmp_path / "link.urdf"
    link.symlink_to(real)
    assert main(["urdf", "delta", "-o", str(link)]) == 0
    assert link.is_symlink() and os.readlink(link) == str(real)
    assert "<robot" in real.read_text()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temp left


@pytest.mark.parametrize(
    "target, match",
    [
        ("fifo", "a FIFO (named pipe), not a regular file"),
        ("device", "a character device, not a regular file"),
        ("stdout", "a symbolic link to '/proc/self/fd/1'"),
        ("dangling", "a symbolic link to nothing"),
        ("directory", "a directory, not a regular file"),
        ("link to fifo", "a symbolic link to a FIFO (named pipe)"),
        ("long name", "the file name is 304 bytes long; at most 255"),
        ("missing directory", "does not exist"),
    ],
)
def test_outputs_that_are_not_regular_files_are_refused(tmp_path, fifo, capsys, target, match):
    paths = {
        "fifo": str(fifo),
        "device": "/dev/null",
        "stdout": "/dev/stdout",
        "dangling": str(tmp_path / "dangling.urdf"),
        "directory": str(tmp_path) + "/",
        "link to fifo": str(tmp_path / "tofifo.urdf"),
        "long name": str(tmp_path / ("a" * 299 + ".urdf")),
        "missing directory": str(tmp_path / "no" / "x.urdf"),
    }
    (tmp_path / "dangling.urdf").symlink_to(tmp_path / "nowhere")
    (tmp_path / "tofifo.urdf").symlink_to(fifo)
    path = paths[target]
    assert main(["urdf", "delta", "-o", path]) == 1
    assert match in _one_line(capsys)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)  # left as it was
    assert (tmp_path / "dangling.urdf").is_symlink() and (tmp_path / "tofifo.urdf").is_symlink()
    with pytest.raises(OutputError):
        with atomic_write(path) as fh:  # the API refuses the same
            fh.write("x")


def test_study_outputs_are_checked_before_any_work(tmp_path, fifo, capsys):
    base = ["design", "delta", "--range", "la=0.2:0.3", "--metric", "moving_mass", "--n", "2"]
    cases = [
        (["--out", str(fifo)], "a FIFO"),
        (
            ["--out", str(tmp_path / ("b" * 245 + ".csv"))],
            "the study file: the file name is 256 bytes long; at most 255",
        ),  # fmt: skip
        (["--out", str(tmp_path / "o.csv"), "--plot", str(tmp_path / "p.foo")], "unknown figure"),
        (["--out", str(tmp_path / "o.csv"), "--plot", str(tmp_path / "p")], "no file extension"),
        (["--out", str(tmp_path / "o.csv"), "--save-study", "/dev/stdout"], "/proc/self/fd/1"),
        (["--out", str(tmp_path / "o.csv"), "--urdf", str(tmp_path)], "a directory"),
    ]
    for extra, match in cases:
        t0 = time.monotonic()
        assert main([*base, *extra, "--workers", "1"]) == 1
        assert match in _one_line(capsys), extra
        assert time.monotonic() - t0 < 5.0
        assert not output_paths(tmp_path / "o.csv")["partial"].exists()  # nothing evaluated


@pytest.mark.parametrize(
    "command",
    [
        ["size", "delta", "--plot", "x.foo"],
        ["size", "delta", "--catalog", "example", "--operating-points", "x.foo"],
        ["workspace", "delta", "--plot", "x.foo"],
        ["tripod", "scenario", "--plot", "x.foo"],
    ],
)
def test_figure_extensions_are_checked_before_the_work(tmp_path, monkeypatch, capsys, command):
    monkeypatch.chdir(tmp_path)
    t0 = time.monotonic()
    assert main(command) == 1
    assert "unknown figure format '.foo'" in _one_line(capsys)
    assert time.monotonic() - t0 < 5.0


# ---------------------------------------------------------------------- inputs


@pytest.mark.parametrize("what", ["study", "catalog"])
@pytest.mark.parametrize("source", ["fifo", "/dev/zero", "directory", "large"])
def test_inputs_that_are_not_regular_files_are_refused(tmp_path, fifo, capsys, what, source):
    big = tmp_path / "big.yaml"
    big.write_text("#" * 3_000_000)
    path = {"fifo": str(fifo), "/dev/zero": "/dev/zero", "directory": str(tmp_path),
            "large": str(big)}[source]  # fmt: skip
    t0 = time.monotonic()
    if what == "study":
        code = main(["design", "--study", path])
    else:
        code = main(["size", "delta", "--catalog", path])
    err = _one_line(capsys)
    assert code == 1 and time.monotonic() - t0 < 10.0
    assert ("cannot be read" in err) != (source == "large")
    assert ("MB accepted" in err) == (source == "large")


def test_read_text_limits(tmp_path):
    f = tmp_path / "t.txt"
    f.write_bytes(b"\xff\xfe")
    with pytest.raises(StudyError, match="not utf-8 text"):
        read_text(f, 100, lambda m: StudyError("t", m))
    f.write_text("hello")
    assert read_text(f, 5, lambda m: StudyError("t", m)) == "hello"
    with pytest.raises(StudyError, match="more than"):
        read_text(f, 4, lambda m: StudyError("t", m))


def test_output_target_resolves_links(tmp_path):
    real = tmp_path / "a.csv"
    real.write_text("x")
    (tmp_path / "l.csv").symlink_to("a.csv")
    assert output_target(tmp_path / "l.csv") == real
    assert output_target(tmp_path / "new.csv") == tmp_path / "new.csv"


# ---------------------------------------------------------------------- one line


def test_multi_line_messages_are_printed_on_one_line(monkeypatch, capsys):
    def boom(args):
        warnings.warn("first line\nsecond line", UserWarning, stacklevel=1)
        raise PkdynError("a library said:\n  line one\n  line two")

    monkeypatch.setattr(cli, "_parser", lambda argv=None: _Stub(boom))
    assert main(["info", "delta"]) == 1
    err = capsys.readouterr().err.splitlines()
    assert err == [
        "pkdyn: warning: first line second line",
        "pkdyn: error: a library said: line one line two",
    ]


def test_out_of_memory_is_one_line(monkeypatch, capsys):
    def boom(args):
        raise MemoryError

    monkeypatch.setattr(cli, "_parser", lambda argv=None: _Stub(boom))
    assert main(["info", "delta"]) == 1
    assert "out of memory" in _one_line(capsys)


class _Stub:
    def __init__(self, fn):
        self.fn = fn

    def parse_args(self, argv):
        import argparse

        return argparse.Namespace(func=self.fn)
