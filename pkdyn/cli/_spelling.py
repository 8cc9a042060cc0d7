"""One spelling per option across commands; a renamed option's former spelling for one release.

Every option that means the same thing is spelled the same way in every command (``-o/--out``
for the main output, ``--band`` for a settling band, ``--top`` for how many entries of a
ranked list are shown, ``--measurements`` for a table of measurements, ``--step`` for an
integration step...; ``tests/test_spelling.py`` lists them). A renamed option keeps its former
spelling for one release: :func:`spelled_option` declares it beside the new one, and using it
prints one warning line naming the new spelling.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

__all__ = ["DeprecatedSpelling", "spelled_option"]


class DeprecatedSpelling(argparse.Action):
    """Stores like ``store``; a deprecated option string prints a one-line warning.

    :func:`spelled_option` makes the same warning over any other action (``append``,
    ``extend``, ``store_true``...).
    """

    def __init__(self, *args: Any, deprecated: tuple[str, ...] = (), **kwargs: Any) -> None:
        self.deprecated = deprecated
        super().__init__(*args, **kwargs)

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        if option_string in self.deprecated and getattr(self, "_warned", None) != id(namespace):
            self._warned = id(namespace)  # (once per command line)
            current = "/".join(s for s in self.option_strings if s not in self.deprecated)
            print(
                f"pkdyn: warning: {option_string} is deprecated and will be removed in the next "
                f"release; use {current}",
                file=sys.stderr,
            )
        self._act(parser, namespace, values, option_string)

    def _act(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None,
    ) -> None:
        setattr(namespace, self.dest, values)


_WARNING_ACTIONS: dict[type, type] = {}


def _warning_action(base: type) -> type:
    """``base`` (an argparse action class) that warns for its deprecated spellings first."""
    if base is argparse._StoreAction:
        return DeprecatedSpelling
    if base not in _WARNING_ACTIONS:

        def _act(
            self: Any,
            parser: argparse.ArgumentParser,
            namespace: argparse.Namespace,
            values: Any,
            option_string: str | None,
        ) -> None:
            base.__call__(self, parser, namespace, values, option_string)

        _WARNING_ACTIONS[base] = type(
            f"Deprecated{base.__name__}", (DeprecatedSpelling, base), {"_act": _act}
        )
    return _WARNING_ACTIONS[base]


def spelled_option(
    parser: Any, *flags: str, deprecated: tuple[str, ...] = (), **kwargs: Any
) -> Any:
    """``parser.add_argument(*flags, **kwargs)``, with former spellings still accepted.

    Args:
        parser: The command's parser (or a group of it).
        *flags: The option strings (the destination is named after the first long one).
        deprecated: Former option strings, accepted for one release with a warning.
        **kwargs: As for ``add_argument`` (any action: ``store``, ``append``, ``extend``...).

    Returns:
        The argparse action (its ``deprecated`` attribute: the former spellings).

    """
    if deprecated:
        base = parser._registry_get("action", kwargs.get("action"), kwargs.get("action"))
        if not isinstance(base, type):  # (a parser the quick start skips, or argparse's error)
            return parser.add_argument(*flags, *deprecated, **kwargs)
        kwargs["action"] = _warning_action(base)
        kwargs["deprecated"] = tuple(deprecated)
        flags = (*flags, *deprecated)
    return parser.add_argument(*flags, **kwargs)
