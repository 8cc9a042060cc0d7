"""Reading description files: size-checked text, XML trees that remember line numbers.

Every importer reads its file through :func:`read_text` (regular files only, bounded size: a
device or a FIFO would block or never end) and parses XML through :func:`parse_xml`, which keeps
the line of each element so that errors can say where the culprit is, and refuses entity
declarations (no entity expansion at all: neither "billion laughs" nor external files).

Leniencies that Drake's and Gazebo's parsers (tinyxml2) have, applied by :func:`lenient` before
any parser sees the text (line numbers are kept): a comment that contains ``--`` (illegal in XML;
the comment ends at the first ``-->``), a ``drake:`` prefix used without its ``xmlns:drake``
declaration (declared on the root element), and Drake's namespace as the default namespace of
the root element (``<robot xmlns="http://drake.mit.edu">``, dropped: URDF has no namespace).
None of them lets an entity or an external resource in: :func:`parse_xml` still refuses every
entity declaration.
"""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

import numpy as np

from pkdyn.exceptions import DescriptionError

__all__ = [
    "DRAKE_NAMESPACE",
    "MAX_FILE_BYTES",
    "XmlDoc",
    "finite_numbers",
    "lenient",
    "parse_xml",
    "read_text",
    "root_start",
]

MAX_FILE_BYTES = 64 * 1024 * 1024
"""Largest description or sidecar file pkdyn reads [bytes] (64 MiB)."""

DRAKE_NAMESPACE = "http://drake.mit.edu"
"""Namespace URI declared for an undeclared ``drake:`` prefix (Drake's own)."""

_DEFAULT_NS = re.compile(r"""\sxmlns\s*=\s*(["'])[^"']*drake\.mit\.edu[^"']*\1""")
_ROOT = re.compile(r"<([A-Za-z_][\w.-]*)(?=[\s/>])")


def _comments(text: str) -> str:
    """Comments with ``--`` inside made legal (``- -``), as tinyxml2 reads them."""
    if "<!--" not in text:
        return text
    out: list[str] = []
    i = 0
    while True:
        start = text.find("<!--", i)
        if start < 0:
            out.append(text[i:])
            return "".join(out)
        end = text.find("-->", start + 4)
        if end < 0:  # unterminated: left for the parser to report
            out.append(text[i:])
            return "".join(out)
        body = text[start + 4 : end]
        if "--" in body or body.endswith("-"):
            body = body.replace("--", "- ").replace("--", "- ")
            if body.endswith("-"):
                body = body[:-1] + " "
        out.append(text[i : start + 4] + body + "-->")
        i = end + 3


def root_start(text: str) -> re.Match[str] | None:
    """The root element's start tag (after the prolog, comments and processing instructions)."""
    i = 0
    while True:
        m = _ROOT.search(text, i)
        if m is None:
            return None
        before = text[: m.start()]
        # inside a comment, a processing instruction or the document type: look further
        if before.rfind("<!--") > before.rfind("-->") or before.rfind("<?") > before.rfind("?>"):
            i = m.end()
            continue
        return m


def lenient(text: str) -> str:
    """The text with the leniencies of Drake's and Gazebo's parsers applied (see the module).

    Args:
        text: A description.

    Returns:
        The same document with comments containing ``--`` made legal and an undeclared
        ``drake:`` prefix declared on the root element (line numbers unchanged).

    """
    text = _comments(text)
    undeclared = "drake:" in text and "xmlns:drake" not in text
    if not undeclared and "drake.mit.edu" not in text:
        return text
    m = root_start(text)
    if m is None:
        return text
    k = m.end()
    end = text.find(">", k)
    head = text[k:end] if end > 0 else ""
    head = _DEFAULT_NS.sub("", head)  # Drake's default namespace on the root
    if undeclared:
        head = f' xmlns:drake="{DRAKE_NAMESPACE}"' + head
    return text[:k] + head + (text[end:] if end > 0 else text[k:])


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
    from pkdyn import files

    name = str(path)
    mib = MAX_FILE_BYTES // 2**20

    def error(msg: str) -> DescriptionError:
        if "MB" in msg:  # (the limit in the unit descriptions are known by)
            msg = f"is larger than {mib} MiB; pkdyn reads descriptions of at most {mib} MiB"
        return DescriptionError(name, what, msg)

    data = files.read_bytes(path, MAX_FILE_BYTES, error)
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
    text = lenient(text)
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


def finite_numbers(source: str, where: str, text: str | None, n: int) -> np.ndarray:
    """The ``n`` finite numbers of an element's text (white-space separated).

    Args:
        source: The file, named in errors.
        where: The element, named in errors.
        text: The element's text (``None``: empty).
        n: How many numbers it must hold.

    Returns:
        (n,) the numbers.

    Raises:
        DescriptionError: A token is not a number, or there are not ``n`` finite ones.

    """
    try:
        v = np.array([float(t) for t in (text or "").split()], dtype=float)
    except ValueError:
        raise DescriptionError(source, where, f"expected {n} numbers, got '{text}'") from None
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise DescriptionError(source, where, f"expected {n} finite numbers, got '{text}'")
    return v
