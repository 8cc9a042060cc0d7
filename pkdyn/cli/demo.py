"""``pkdyn demo``: the main job on built-in defaults."""

from __future__ import annotations

import argparse
from typing import Any

__all__ = ["register"]


def _cmd_demo(args: argparse.Namespace) -> None:
    from pkdyn.demo import run_demo

    run_demo()


def register(sub: Any) -> None:
    """Add ``demo`` to the ``pkdyn`` parser."""
    sp = sub.add_parser("demo", help="run the demonstration on built-in defaults")
    sp.set_defaults(func=_cmd_demo)
