"""xacro: ROS's macro language for URDF (``robot.urdf.xacro``), expanded before loading.

Most ROS descriptions are written in xacro. :func:`expand_xacro` runs the ``xacro`` package from
PyPI (an optional dependency: ``pip install "pkdyn[xacro]"``) on a file with its arguments
(``<xacro:arg name>`` values, ``name:=value`` on ROS's command line) and returns the URDF text.

Every file xacro reads (the top file and its ``<xacro:include>`` files) goes through pkdyn's own
guards first: regular files of bounded size, and no XML entity declarations (xacro's XML parser
would expand them). ``$(find package)`` needs a ROS installation and fails with xacro's message.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from pkdyn.exceptions import DescriptionError, InvalidInputError

__all__ = ["XACRO_SUFFIX", "expand_xacro", "is_xacro", "parse_xacro_args"]

XACRO_SUFFIX = ".xacro"
"""File suffix of xacro files (``robot.urdf.xacro``, ``robot.xacro``)."""

_NAME = re.compile(r"^[A-Za-z_][\w.-]*$")


def is_xacro(path: str | os.PathLike[str]) -> bool:
    """Whether a file is a xacro file (by its name)."""
    return str(path).lower().endswith(XACRO_SUFFIX)


def parse_xacro_args(items: list[str] | None) -> dict[str, str]:
    """``name:=value`` strings (the CLI's ``--xacro-arg``) as a mapping.

    Raises:
        InvalidInputError: An item without ``:=``, an invalid name or a name given twice.

    """
    out: dict[str, str] = {}
    for item in items or []:
        name, sep, value = item.partition(":=")
        if not sep or not _NAME.match(name):
            raise InvalidInputError(
                "--xacro-arg", f"'{item}': expected NAME:=VALUE (e.g. --xacro-arg prefix:=left_)"
            )
        if name in out:
            raise InvalidInputError("--xacro-arg", f"'{name}' is given twice")
        out[name] = value
    return out


def _check_args(source: str, args: Mapping[str, Any] | None) -> dict[str, str]:
    if args is None:
        return {}
    if not isinstance(args, Mapping):
        raise InvalidInputError("xacro_args", f"expected a mapping name -> value, got {args!r}")
    out = {}
    for k, v in args.items():
        if not isinstance(k, str) or not _NAME.match(k):
            raise InvalidInputError("xacro_args", f"invalid argument name {k!r}")
        if not isinstance(v, str | int | float | bool):
            raise InvalidInputError("xacro_args", f"argument '{k}': {v!r} is not text or a number")
        out[k] = str(v).lower() if isinstance(v, bool) else str(v)
    return out


@contextmanager
def _guarded_parse(xacro: Any) -> Iterator[None]:
    """The xacro ``parse`` function, reading files through pkdyn's guards (no entities)."""
    import xml.dom.minidom

    from pkdyn.model.formats.xmldoc import lenient, parse_xml, read_text

    original = xacro.parse

    def parse(inp: Any, filename: str | None = None) -> Any:
        if inp is None and filename is not None:
            path = os.path.join(getattr(xacro, "root_dir", ""), filename)
            inp = read_text(path, "xacro file")
            source = path
        else:
            source = filename or "xacro input"
        if isinstance(inp, str):
            text = lenient(inp)
            parse_xml(text, source)  # malformed XML and entity declarations: refused here
            return xml.dom.minidom.parseString(text)
        return original(inp, filename)

    xacro.parse = parse
    try:
        yield
    finally:
        xacro.parse = original


def expand_xacro(path: str | os.PathLike[str], args: Mapping[str, Any] | None = None) -> str:
    """The URDF text of a xacro file.

    Args:
        path: The ``.xacro`` file.
        args: xacro arguments (``<xacro:arg name>``): name -> value (text or number).

    Returns:
        The expanded document.

    Raises:
        DescriptionError: The ``xacro`` package is not installed (with the command that
            installs it), or xacro refuses the file (its message, one line).
        InvalidInputError: Malformed ``args``.

    """
    source = str(path)
    mappings = _check_args(source, args)
    try:
        import xacro
    except ImportError:
        raise DescriptionError(
            source,
            "xacro file",
            "needs the 'xacro' package, which is not installed: pip install \"pkdyn[xacro]\" "
            "(or pip install xacro), or expand it first: xacro FILE > robot.urdf",
        ) from None
    from pkdyn.model.formats.xmldoc import read_text

    read_text(path, "xacro file")  # a regular file of bounded size, before xacro opens it
    try:
        with _guarded_parse(xacro):
            doc = xacro.process_file(str(Path(path)), mappings=mappings)
        text: str = doc.toxml()
    except (DescriptionError, MemoryError):
        raise
    except Exception as err:  # xacro raises its own, and whatever its expressions raise
        first = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise DescriptionError(source, "xacro", f"expansion failed: {first}") from err
    return text
