"""Sphinx extension: the command-line reference, generated from pkdyn's argparse parsers.

At every build (``builder-inited``) the parsers of :func:`pkdyn.cli.commands` are written out
as Markdown in ``docs/_generated/cli.md`` (rewritten only when it changes), which
``docs/guide/cli.md`` includes: one section per command with its help, aliases, usage and a
table of its arguments. Nothing is copied by hand, so the reference cannot drift from the
command line. Run as a script, it prints the Markdown.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

OUT = Path(__file__).resolve().parents[1] / "_generated" / "cli.md"
WIDTH = 92


def _cell(text: str) -> str:
    """Text for a Markdown table cell."""
    return " ".join(text.split()).replace("|", "\\|")


def _arguments(parser: argparse.ArgumentParser) -> list[tuple[str, str]]:
    """(invocation, help) of each argument shown by ``--help``."""
    fmt: Any = parser.formatter_class(prog=parser.prog, width=WIDTH)
    rows = []
    for action in parser._actions:
        if action.help == argparse.SUPPRESS or isinstance(
            action, argparse._SubParsersAction | argparse._HelpAction
        ):
            continue
        invocation = fmt._format_action_invocation(action)
        text = fmt._expand_help(action) if action.help else ""
        if not text and "--json" in action.option_strings:
            text = "print the result as one JSON object"
        rows.append((invocation, text))
    return rows


def _sentence(text: str) -> str:
    text = text.strip()
    return text[:1].upper() + text[1:] + ("" if text.endswith(".") else ".")


def _usage(parser: argparse.ArgumentParser) -> str:
    fmt: Any = parser.formatter_class(prog=parser.prog, width=WIDTH)
    fmt.add_usage(parser.usage, parser._actions, parser._mutually_exclusive_groups)
    return fmt.format_help().strip()


def markdown() -> str:
    """The reference of every ``pkdyn`` command, as Markdown (second-level sections)."""
    from pkdyn.cli import commands

    out: list[str] = []
    for command in commands():
        parser = command.parser
        name = " ".join(("pkdyn", *command.words))
        level = "#" * (2 + max(len(command.words) - 1, 0))
        out += [f"{level} `{name}`", ""]
        intro = [t for t in (command.help, parser.description) if t]
        if command.aliases:
            intro.append("Also: " + ", ".join(f"`pkdyn {a}`" for a in command.aliases) + ".")
        if intro:
            out += [" ".join(_sentence(t) for t in intro), ""]
        out += ["```text", _usage(parser), "```", ""]
        rows = _arguments(parser)
        if rows:
            out += ["| argument | meaning |", "|---|---|"]
            out += [f"| `{_cell(inv)}` | {_cell(text)} |" for inv, text in rows]
            out.append("")
        if parser.epilog:
            out += [_sentence(_cell(parser.epilog)), ""]
    return "\n".join(out)


def write(out: Path = OUT) -> bool:
    """Write the reference if it changed; whether it did."""
    text = markdown()
    if out.is_file() and out.read_text(encoding="utf-8") == text:
        return False
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text, encoding="utf-8")
    return True


def _builder_inited(app: Any) -> None:
    write()


def setup(app: Any) -> dict[str, Any]:
    """Generate the reference when a build starts."""
    app.connect("builder-inited", _builder_inited)
    return {"parallel_read_safe": True, "parallel_write_safe": True}


if __name__ == "__main__":
    print(markdown())
