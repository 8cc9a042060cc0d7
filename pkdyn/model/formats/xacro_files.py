"""xacro: ROS's macro language for URDF (``robot.urdf.xacro``), expanded before loading.

Most ROS descriptions are written in xacro. :func:`expand_xacro` runs the ``xacro`` package from
PyPI (an optional dependency: ``pip install "pkdyn[xacro]"``) on a file with its arguments
(``<xacro:arg name>`` values, ``name:=value`` on ROS's command line) and returns the URDF text.

No code from data: xacro evaluates ``${...}`` with Python's ``eval``; pkdyn's expansion replaces
that evaluator (inside :func:`expand_xacro` only, never for other users of the ``xacro`` module)
by the restricted, bounded one of :mod:`pkdyn.model.formats.xacro_eval`: arithmetic,
comparisons, properties, ``math`` and the pure ``xacro.`` helpers; an attribute walk, a lambda, a
comprehension, a call of an unlisted function or a number too large is refused with one line
naming the expression. ``$(eval ...)`` goes through the same evaluator; ``$(env NAME)`` is
refused and ``$(optenv NAME DEFAULT)`` gives ``DEFAULT`` (the environment is not read);
``$(arg)``, ``$(dirname)``, ``$(cwd)`` are xacro's; ``$(find package)`` needs a ROS
installation and fails with xacro's message. One expansion evaluates at most
:data:`MAX_EVALUATIONS` expressions and elements in at most :data:`MAX_SECONDS`.

Every file xacro reads (the top file, its ``<xacro:include>`` files and ``xacro.load_yaml``
files) goes through pkdyn's own guards first: regular files of bounded size, and no XML entity
declarations (xacro's XML parser would expand them).
"""

from __future__ import annotations

import os
import re
import threading
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from pkdyn.exceptions import DescriptionError, InvalidInputError
from pkdyn.model.formats.xacro_eval import XacroEvaluator, XacroRefused, safe_symbols

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


MAX_EVALUATIONS = 500_000
"""Most expressions and elements one expansion evaluates (a macro that calls itself twice per
level doubles the work with each level)."""

MAX_SECONDS = 60.0
"""Longest time one expansion may take [s]."""

MAX_YAML_BYTES = 4 * 1024 * 1024
"""Largest YAML file ``xacro.load_yaml`` reads [bytes] (4 MiB)."""

_LOCK = threading.Lock()
"""One expansion at a time: the ``xacro`` module keeps its state in module globals."""


def _refused(source: str, err: XacroRefused) -> DescriptionError:
    reason = err.reason if "not allowed" in err.reason else f"{err.reason} (not allowed)"
    from pkdyn.files import shown

    if not err.expression:  # the whole expansion's budget
        return DescriptionError(source, "xacro expansion", reason)
    return DescriptionError(source, f"xacro expression '{shown(err.expression, 60)}'", reason)


def _load_yaml(xacro: Any, evaluator: XacroEvaluator) -> Any:
    """``xacro.load_yaml``: a regular YAML file of bounded size, units tags evaluated safely."""
    import yaml

    from pkdyn.files import read_text

    class _Loader(yaml.SafeLoader):
        pass

    for unit in xacro.ConstructUnits:

        def construct(
            loader: Any, node: Any, factor: float = unit.value.conversion_constant
        ) -> Any:
            return float(evaluator(loader.construct_scalar(node), xacro._global_symbols)) * factor

        _Loader.add_constructor(unit.value.tag, construct)

    def load_yaml(filename: Any) -> Any:
        path = xacro.abs_filename_spec(str(filename))
        text = read_text(
            path,
            MAX_YAML_BYTES,
            lambda msg: DescriptionError(path, "xacro.load_yaml", msg),
        )
        try:
            data = yaml.load(text, Loader=_Loader)  # noqa: S506 (a SafeLoader)
        except yaml.YAMLError as err:
            raise DescriptionError(path, "xacro.load_yaml", f"not YAML: {err}") from None
        return xacro.YamlListWrapper.wrap(data)

    return load_yaml


def _extension(xacro: Any, evaluator: XacroEvaluator) -> Any:
    """The ``$(...)`` substitutions of an expansion.

    ``arg``, ``find``, ``dirname``, ``cwd`` as xacro does them; ``eval`` by the safe evaluator;
    ``optenv`` gives its default and ``env`` is refused (pkdyn does not read the environment
    into a description).
    """
    from xacro.substitution_args import convert_value

    original = xacro.eval_extension

    def eval_extension(s: str) -> Any:
        inner = s[2:-1].strip()
        word, _, rest = inner.partition(" ")
        if word == "eval":
            args = xacro.substitution_args_context.get("arg", {})
            names: dict[str, Any] = {k: convert_value(str(v), "auto") for k, v in args.items()}
            names.update(xacro._global_symbols)
            return str(evaluator(rest, names))
        if word == "env":
            raise XacroRefused(
                s,
                "reading an environment variable is not allowed; give the value as an "
                "argument (--xacro-arg NAME:=VALUE, xacro_args=)",
            )
        if word == "optenv":
            parts = rest.split(None, 1)
            return parts[1] if len(parts) > 1 else ""  # the default: the environment is not read
        return original(s)

    return eval_extension


def _counted(fn: Any, budget: dict[str, float]) -> Any:
    def call(*args: Any, **kwargs: Any) -> Any:
        budget["count"] += 1
        if budget["count"] > MAX_EVALUATIONS:  # (read at each call: tests lower it)
            raise XacroRefused(
                "",
                f"the expansion evaluates more than {MAX_EVALUATIONS:,} expressions and "
                "elements (a macro that expands without end?)",
            )
        if budget["count"] % 1000 == 0 and time.monotonic() > budget["deadline"]:
            raise XacroRefused("", f"the expansion takes more than {MAX_SECONDS:g} s")
        return fn(*args, **kwargs)

    return call


@contextmanager
def _safe_xacro(xacro: Any) -> Iterator[None]:
    """The ``xacro`` module with pkdyn's evaluator, budget and guarded reads, for one expansion.

    Patched inside this context only (and restored after, whatever happens): ``parse``
    (files through pkdyn's guards, no entities), ``safe_eval`` and ``_global_symbols`` (the
    evaluator of :mod:`pkdyn.model.formats.xacro_eval`), ``eval_extension`` (``$(...)``),
    ``eval_text`` and ``eval_all`` (counted against :data:`MAX_EVALUATIONS` and
    :data:`MAX_SECONDS`).
    """
    import xml.dom.minidom

    from pkdyn.model.formats.xmldoc import lenient, parse_xml, read_text

    names = ("parse", "safe_eval", "_global_symbols", "eval_extension", "eval_text", "eval_all")
    saved = {n: getattr(xacro, n) for n in names}
    original_parse = saved["parse"]

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
        return original_parse(inp, filename)

    helpers: dict[str, Any] = {
        "arg": lambda name: xacro.substitution_args_context["arg"][name],
        "tokenize": xacro.tokenize,
        "abs_filename": xacro.abs_filename_spec,
        "dotify": xacro.YamlDictWrapper,
        "fatal": lambda *args: _fatal(xacro, args),
    }
    evaluator_box: list[XacroEvaluator] = []

    def lazy_yaml(filename: Any) -> Any:
        return _load_yaml(xacro, evaluator_box[0])(filename)

    helpers["load_yaml"] = lazy_yaml
    symbols = safe_symbols(helpers)
    evaluator = XacroEvaluator({k: v for k, v in symbols.items() if callable(v)})
    evaluator_box.append(evaluator)
    budget = {"count": 0.0, "deadline": time.monotonic() + MAX_SECONDS}
    with _LOCK:
        xacro.parse = parse
        xacro.safe_eval = lambda expr, globals, locals=None: evaluator(expr, globals)
        xacro._global_symbols = symbols
        xacro.eval_extension = _extension(xacro, evaluator)
        xacro.eval_text = _counted(saved["eval_text"], budget)
        xacro.eval_all = _counted(saved["eval_all"], budget)
        try:
            yield
        finally:
            for n, v in saved.items():
                setattr(xacro, n, v)


def _fatal(xacro: Any, args: tuple[Any, ...]) -> None:
    raise xacro.XacroException(" ".join(map(str, args)))


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
        with _safe_xacro(xacro):
            doc = xacro.process_file(str(Path(path)), mappings=mappings)
        text: str = doc.toxml()
    except XacroRefused as err:
        raise _refused(source, err) from None
    except (DescriptionError, MemoryError):
        raise
    except RecursionError:
        raise DescriptionError(
            source, "xacro", "expansion failed: macros nested too deeply (a macro calling itself?)"
        ) from None
    except Exception as err:  # xacro raises its own, and whatever its expressions raise
        first = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise DescriptionError(source, "xacro", f"expansion failed: {first}") from err
    return text
