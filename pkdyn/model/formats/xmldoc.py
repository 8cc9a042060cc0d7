"""Reading description files: size-checked text, XML trees that remember line numbers.

Every importer reads its file through :func:`read_text` (regular files only, bounded size: a
device or a FIFO would block or never end) and parses XML through :func:`parse_xml`, which keeps
the line of each element so that errors can say where the culprit is, and refuses entity
declarations (no entity expansion at all: neither "billion laughs" nor external files).
"""

from __future__ import annotations

import os
import stat
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from pkdyn.exceptions import DescriptionError

__all__ = ["MAX_FILE_BYTES", "XmlDoc", "parse_xml", "read_text"]

MAX_FILE_BYTES = 64 * 1024 * 1024
"""Largest description or sidecar file pkdyn reads [bytes] (64 MiB)."""


def read_text(path: str | os.PathLike[str], what: str = "file") -> str:
    """Text of a regular file of bounded size.

    Args:
        path: The file.
        what: What it is, for messages (``file``, ``sidecar``...).

    Returns:
        The text (UTF-8).

    Raises:
        DescriptionError: Not a regular file (a directory, a device, a FIFO...), larger than
            :data:`MAX_FILE_BYTES`, unreadable or not UTF-8 text.

    """
    name = str(path)
    try:
        st = os.stat(path)
    except OSError as err:
        raise DescriptionError(name, what, f"cannot be read ({err.strerror or err})") from None
    if not stat.S_ISREG(st.st_mode):
        raise DescriptionError(
            name, what, "is not a regular file (a device, FIFO or directory is not read)"
        )
    if st.st_size > MAX_FILE_BYTES:
        raise DescriptionError(
            name,
            what,
            f"is {st.st_size / 2**20:.0f} MiB; pkdyn reads descriptions of at most "
            f"{MAX_FILE_BYTES // 2**20} MiB",
        )
    try:
        with open(path, "rb") as f:  # re-check: the file may have been swapped since stat
            if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):
                raise DescriptionError(name, what, "is not a regular file")
            data = f.read(MAX_FILE_BYTES + 1)
    except OSError as err:
        raise DescriptionError(name, what, f"cannot be read ({err.strerror or err})") from None
    if len(data) > MAX_FILE_BYTES:
        raise DescriptionError(name, what, f"is larger than {MAX_FILE_BYTES // 2**20} MiB")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise DescriptionError(name, what, f"is not UTF-8 text ({err.reason})") from None


@dataclass
class XmlDoc:
    """A parsed XML document whose elements know their line.

    Attributes:
        root: The root element.
        source: File or name, for messages.
        path: The file, when the document came from one (relative references resolve there).

    """

    root: ET.Element
    source: str
    path: Path | None = None
    _lines: dict[int, int] = field(default_factory=dict, repr=False)
    _keep: list[ET.Element] = field(default_factory=list, repr=False)

    def line(self, el: ET.Element) -> int:
        """Line of an element (0 if unknown)."""
        return self._lines.get(id(el), 0)

    def where(self, el: ET.Element, name: str | None = None) -> str:
        """``<tag name='...'> (line n)``: how messages name an element."""
        label = el.get("name") if name is None else name
        tag = f"<{el.tag}" + (f" name='{label}'" if label else "") + ">"
        n = self.line(el)
        return f"{tag} (line {n})" if n else tag

    def error(self, el: ET.Element, message: str, name: str | None = None) -> DescriptionError:
        """A :class:`DescriptionError` naming the element and its line."""
        return DescriptionError(self.source, self.where(el, name), message)

    def merge(self, other: XmlDoc) -> None:
        """Take over the line numbers of an included document's elements."""
        self._lines.update(other._lines)
        self._keep.extend(other._keep)


def parse_xml(text: str, source: str, path: Path | None = None) -> XmlDoc:
    """Parse XML text, keeping element lines; entity declarations are refused.

    Args:
        text: The document.
        source: File or name, for messages.
        path: File it came from, if any.

    Returns:
        The document.

    Raises:
        DescriptionError: Malformed XML, or a document type declaring entities.

    """
    builder = ET.TreeBuilder()
    parser = expat.ParserCreate()
    lines: dict[int, int] = {}
    keep: list[ET.Element] = []

    def start(tag: str, attrs: dict[str, str]) -> None:
        el = builder.start(tag, attrs)
        lines[id(el)] = parser.CurrentLineNumber
        keep.append(el)  # ids stay valid while the document lives

    def entity(name: str, *_: object) -> None:
        raise DescriptionError(
            source,
            f"entity '{name}' (line {parser.CurrentLineNumber})",
            "XML entity declarations are not allowed in robot descriptions",
        )

    parser.StartElementHandler = start
    parser.EndElementHandler = builder.end
    parser.CharacterDataHandler = builder.data
    parser.EntityDeclHandler = entity
    parser.UnparsedEntityDeclHandler = entity
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    try:
        parser.Parse(text, True)
        root = builder.close()
    except expat.ExpatError as err:
        raise DescriptionError(
            source,
            "XML",
            f"malformed document ({expat.errors.messages[err.code]}, line {err.lineno})",
        ) from None
    except (AssertionError, IndexError):  # TreeBuilder on an empty or unbalanced document
        raise DescriptionError(source, "XML", "malformed document (no root element)") from None
    return XmlDoc(root, source, path, lines, keep)
