"""Progress bars: shown when asked (or on a terminal), silent otherwise."""

from pkdyn.progress import progress


def test_bar_when_enabled_and_silent_otherwise(capsys):
    assert list(progress(range(5), "work", "item", enabled=True)) == [0, 1, 2, 3, 4]
    err = capsys.readouterr().err
    assert "work" in err and "5/5" in err
    # pytest's stderr is not a terminal: no bar by default, and none when disabled
    assert list(progress(iter("abc"), "work", "item")) == ["a", "b", "c"]
    assert list(progress(range(3), "work", "item", enabled=False)) == [0, 1, 2]
    assert capsys.readouterr().err == ""
