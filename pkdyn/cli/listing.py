"""``pkdyn list``: the library families and their builder parameters (from the registry)."""

from __future__ import annotations

import argparse
import dataclasses
import re
from typing import Any

from pkdyn.cli._common import emit

__all__ = ["family_parameters", "plain_text", "register"]


_ROLE = re.compile(r":[\w:]+:`~?([^`<]*?)\s*(?:<[^`>]*>)?`")
_LITERAL = re.compile(r"``(.+?)``|`([^`]+)`")


def plain_text(text: str) -> str:
    """Docstring text as plain text, for a terminal: no Sphinx roles, no literal markup.

    A role keeps its target (only the last dotted part when the target starts with a tilde), or
    its title when it has one; literals and interpreted text lose their backquotes.

    Args:
        text: Docstring text (reStructuredText).

    Returns:
        The text without markup.

    """

    def role(m: re.Match[str]) -> str:
        return m.group(1).rsplit(".", 1)[-1] if m.group(0).count("`~") else m.group(1)

    text = _ROLE.sub(role, text)
    return _LITERAL.sub(lambda m: m.group(1) or m.group(2), text)


def _attribute_docs(doc: str) -> dict[str, str]:
    """``{name: text}`` of the ``Attributes:`` section of a Google-style docstring."""
    out: dict[str, str] = {}
    lines = doc.expandtabs().splitlines()
    try:
        start = next(i for i, line in enumerate(lines) if line.strip() == "Attributes:")
    except StopIteration:
        return out
    indent = None
    name = None
    for line in lines[start + 1 :]:
        if not line.strip():
            continue
        width = len(line) - len(line.lstrip())
        if indent is None:
            indent = width
        if width < indent:
            break
        m = re.match(r"(\w+):\s*(.*)", line.strip())
        if width == indent and m:
            name = m[1]
            out[name] = m[2]
        elif name is not None:
            out[name] += " " + line.strip()
    return out


def family_parameters(name: str) -> list[dict[str, Any]]:
    """Builder parameters of a family: name, default, type and documentation.

    Args:
        name: Family name.

    Returns:
        One dict per parameter (``name``, ``default``, ``type``, ``doc``), in field order.

    """
    from pkdyn.model.families import family

    cls = family(name).params
    docs = _attribute_docs(cls.__doc__ or "")
    defaults = cls()
    out = []
    for f in dataclasses.fields(cls):
        value = getattr(defaults, f.name)
        out.append(
            {
                "name": f.name,
                "default": value,
                "type": type(value).__name__ if value is not None else "float",
                "doc": plain_text(docs.get(f.name, "")),
            }
        )
    return out


def _short(value: Any) -> str:
    text = repr(value) if isinstance(value, str) else str(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _cmd_list(args: argparse.Namespace) -> None:
    import pkdyn  # noqa: F401  (registers the families)
    from pkdyn.model.families import FAMILIES

    families: list[dict[str, Any]] = []
    for name, fam in FAMILIES.items():
        families.append(
            {"name": name, "summary": fam.summary, "parameters": family_parameters(name)}
        )
    lines = []
    for f in families:
        lines.append(f"{f['name']}: {f['summary']}")
        if args.params:
            for p in f["parameters"]:
                doc = p["doc"]
                lines.append(
                    f"    {p['name']} = {_short(p['default'])}" + (f"  # {doc}" if doc else "")
                )
        else:
            lines.append("    " + ", ".join(p["name"] for p in f["parameters"]))
    if not args.params:
        lines.append("(pkdyn list --params: defaults and meaning; pkdyn info NAME --param K=V ...)")
    payload = {
        "families": [
            {
                **f,
                "parameters": [{**p, "default": _jsonable(p["default"])} for p in f["parameters"]],
            }
            for f in families
        ]
    }
    emit(args, payload, "\n".join(lines))


def _jsonable(value: Any) -> Any:
    if isinstance(value, tuple):
        return [_jsonable(v) for v in value]
    return value


def register(sub: Any) -> None:
    """Add ``list`` to the ``pkdyn`` parser."""
    sp = sub.add_parser("list", help="library families and their builder parameters")
    sp.add_argument("--params", action="store_true", help="defaults and meaning of each parameter")
    sp.add_argument("--json", action="store_true")
    sp.set_defaults(func=_cmd_list)
