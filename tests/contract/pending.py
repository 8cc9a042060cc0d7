"""Cases of the drive known to fail on this branch because their fix is on another branch.

Each becomes ``xfail(strict=True)``: when the fix is merged the case passes, the strict mark
fails the run, and the line is removed here. (The cli branch's paths, reads and negative
numbers, and dep1's checked control-loop step, were merged: their lines are gone.)
"""

from __future__ import annotations

__all__ = ["PENDING_CLI"]

PENDING_CLI: dict[str, str] = {}
"""Test id (or a prefix ending with ``|``) -> the branch that fixes it."""
