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


def test_steps_when_enabled_and_silent_otherwise(capsys):
    from pkdyn.progress import progress_steps

    with progress_steps(3, "stages", "stage", enabled=True) as advance:
        for _ in range(3):
            advance()
    err = capsys.readouterr().err
    assert "stages" in err and "3/3" in err
    with progress_steps(3, "stages", "stage") as advance:
        advance()
    assert capsys.readouterr().err == ""


def test_no_direct_tqdm_and_one_progress_type():
    """Every bar goes through pkdyn.progress; every public ``progress`` flag is bool | None."""
    import ast
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    bad = []
    for p in sorted((root / "pkdyn").rglob("*.py")):
        tree = ast.parse(p.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Import | ast.ImportFrom) and p.name != "progress.py":
                names = [a.name for a in node.names]
                mod = node.module if isinstance(node, ast.ImportFrom) else None
                if mod == "tqdm" or "tqdm" in names:
                    bad.append(f"{p.relative_to(root)}:{node.lineno} imports tqdm")
            if isinstance(node, ast.FunctionDef) and not node.name.startswith("_"):
                for arg in node.args.args + node.args.kwonlyargs:
                    if arg.arg == "progress" and ast.unparse(arg.annotation) != "bool | None":
                        bad.append(f"{p.relative_to(root)}:{node.lineno} {node.name}")
    assert bad == []
