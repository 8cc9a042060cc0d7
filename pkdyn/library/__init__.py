"""The robot library: one module per family, each a frozen parameter dataclass and a builder.

Each family module defines ``NAME``, ``SUMMARY``, ``Params`` (frozen dataclass, SI units,
documented defaults), ``build_urdf(params)`` and ``home(params)``; its closed forms live in
:mod:`pkdyn.closed_form`. Importing this package registers the families with
:mod:`pkdyn.model.families` (their modules are imported on first use). The committed
``urdf/<name>.urdf`` files are the builders' output on the default parameters (a test keeps
them in sync).

Layering: may import :mod:`pkdyn.model` and :mod:`pkdyn.closed_form`; nothing above.
"""

from __future__ import annotations

from pkdyn.model.families import FAMILIES, Family, family, register

__all__ = ["FAMILIES", "Family", "family"]

for _name in (
    "delta",
    "gough_stewart",
    "planar_3rrr",
    "five_bar",
    "tripod",
    "parallel_ankle",
    "four_bar_knee",
):
    register(Family(_name, f"pkdyn.library.{_name}"))
