"""The evaluator of xacro's ``${...}`` expressions for pkdyn's loads: no code from data.

The ``xacro`` package evaluates ``${...}`` with Python's ``eval`` (it blocks only names that
start with ``__``), so a description file could reach ``os.system`` by walking attributes, or
never return (``${9**9**9}``). pkdyn replaces that evaluator, for its own loads only, by
:class:`XacroEvaluator`, a ``simpleeval`` evaluator restricted to what real xacro files use:

- literals (numbers, strings, ``True``/``False``, lists, tuples, dicts), arithmetic
  (``+ - * / // % **``), comparisons (``== != < <= > >= in not in``), ``and``/``or``/``not``,
  conditional expressions (``a if c else b``), indexing and slicing;
- names of properties, and the symbols xacro defines: ``pi``, ``e``, ``tau``, ``inf``, ``nan``,
  the pure functions of :mod:`math` (directly or as ``math.sin``), ``radians``/``degrees``, the
  builtins ``abs bool dict float int len list max min round sorted str sum tuple range zip
  enumerate reversed any all`` (directly or as ``python.len``), and the pure ``xacro.``
  helpers ``arg``, ``tokenize``, ``abs_filename``, ``dotify``, ``load_yaml`` (a regular file of
  bounded size, read by pkdyn's guarded reader), ``fatal``, ``message``/``warning``/``error``
  (reported as warnings);
- attributes only of those namespaces (``math.``, ``python.``, ``xacro.``), of xacro
  namespaces of included files, of YAML mappings (``config.joint.lower`` is
  ``config['joint']['lower']``), and the methods ``upper lower strip lstrip rstrip split
  startswith endswith`` of strings.

Everything else is refused with :class:`XacroRefused` before it runs: any other attribute
(dunder or not: ``().__class__``, ``[].copy``, ``math.os``), lambdas, comprehensions,
f-strings, assignments, calls of functions not listed, shifts. Sizes are bounded: integers of
at most :data:`MAX_INT_BITS` bits (checked before a power or a product is computed), strings
and lists of at most :data:`MAX_LENGTH` items, expressions of at most
:data:`MAX_EXPRESSION_CHARS` characters nested at most :data:`MAX_DEPTH` deep.
"""

from __future__ import annotations

import ast
import math
import operator
import re
import types
import warnings
from collections.abc import Callable, Mapping
from typing import Any

__all__ = [
    "MAX_DEPTH",
    "MAX_EXPRESSION_CHARS",
    "MAX_INT_BITS",
    "MAX_LENGTH",
    "XacroEvaluator",
    "XacroRefused",
    "safe_symbols",
]

MAX_INT_BITS = 1024
"""Largest integer an expression may make [bits] (a float's range: about 1.8e308)."""

MAX_LENGTH = 100_000
"""Longest string, list, tuple, dict or range an expression may make [items]."""

MAX_EXPRESSION_CHARS = 10_000
"""Longest expression text [characters]."""

MAX_DEPTH = 50
"""Deepest nesting of an expression's syntax tree."""

_MATH_FUNCTIONS = (
    "acos acosh asin asinh atan atan2 atanh cbrt ceil copysign cos cosh degrees dist erf erfc "
    "exp exp2 expm1 fabs floor fmod frexp fsum gamma gcd hypot isclose isfinite isinf isnan "
    "isqrt ldexp lgamma log log10 log1p log2 modf nextafter pow radians remainder sin sinh sqrt "
    "tan tanh trunc ulp"
).split()
"""Functions of :mod:`math` an expression may call: all take and return bounded numbers
(``factorial``, ``comb``, ``perm``, ``prod`` and ``lcm`` are left out: their work grows with
their arguments)."""

_MATH_CONSTANTS = ("pi", "e", "tau", "inf", "nan")

_STR_METHODS = frozenset("upper lower strip lstrip rstrip split startswith endswith".split())
"""Methods of a string an expression may call (each returns at most its input's size)."""


class XacroRefused(BaseException):  # noqa: N818 (a refusal, raised through xacro's handlers)
    """An expression of a xacro file that pkdyn does not evaluate (or one over a limit).

    A ``BaseException``: xacro wraps every ``Exception`` of an expression into its own, and
    ``get_boolean_value`` swallows them; a refusal must reach pkdyn's loader as raised.

    Attributes:
        expression: The expression text.
        reason: What is not allowed, in words.

    """

    def __init__(self, expression: str, reason: str) -> None:
        self.expression = expression
        self.reason = reason
        super().__init__(f"{expression!r}: {reason}")


class _Namespace:
    """A namespace of allowed symbols (``math``, ``python``, ``xacro``): attribute = key."""

    def __init__(self, name: str, symbols: Mapping[str, Any]) -> None:
        self.name = name
        self.symbols = dict(symbols)

    def lookup(self, attr: str) -> Any:
        try:
            return self.symbols[attr]
        except KeyError:
            raise LookupError(f"{self.name}.{attr} is not one of the allowed symbols") from None

    def __getitem__(self, key: str) -> Any:
        return self.lookup(key)

    def __repr__(self) -> str:
        return f"<xacro namespace {self.name}>"


def _length(x: Any) -> int:
    try:
        return len(x)
    except TypeError:
        return 0


class _Limit(ValueError):  # noqa: N818 (internal, becomes XacroRefused)
    """A size limit an operation would exceed (turned into :class:`XacroRefused`)."""


_MAX_TEXT = 4 * MAX_LENGTH
"""Largest size of a value as text [characters] (a list's items and their lengths summed)."""


def _size(x: Any) -> int:
    """About how many characters ``x`` takes as text (items of containers summed), capped.

    Walks containers without recursion and stops past :data:`_MAX_TEXT`: a list holding one
    long string many times is small in memory but not as text.
    """
    total, stack = 0, [x]
    while stack and total <= _MAX_TEXT:
        v = stack.pop()
        if isinstance(v, str | bytes):
            total += len(v) + 2
        elif isinstance(v, bool) or v is None:
            total += 5
        elif isinstance(v, int):
            total += v.bit_length() // 3 + 2
        elif isinstance(v, dict):
            total += 2
            stack.extend(v.keys())
            stack.extend(v.values())
        elif isinstance(v, list | tuple | set | frozenset):
            total += 2 + len(v)
            if len(v) <= MAX_LENGTH:
                stack.extend(v)
        elif isinstance(v, range):
            total += len(v)
        else:
            total += 25
    return total


def _check(x: Any) -> Any:
    """``x`` if within the size limits, else :class:`_Limit`."""
    if isinstance(x, bool | float) or x is None:
        return x
    if isinstance(x, int):
        if x.bit_length() > MAX_INT_BITS:
            raise _Limit(f"an integer of {x.bit_length()} bits (at most {MAX_INT_BITS})")
        return x
    if isinstance(x, str | bytes | list | tuple | dict | set | frozenset | range):
        if len(x) > MAX_LENGTH or _size(x) > _MAX_TEXT:
            raise _Limit(f"a value longer than {MAX_LENGTH} characters or items")
    return x


def _add(a: Any, b: Any) -> Any:
    if _length(a) + _length(b) > MAX_LENGTH:
        raise _Limit(f"a value of {_length(a) + _length(b)} items (at most {MAX_LENGTH})")
    return _check(a + b)


def _mul(a: Any, b: Any) -> Any:
    for seq, n in ((a, b), (b, a)):
        if isinstance(seq, str | bytes | list | tuple) and isinstance(n, int):
            if len(seq) * max(n, 0) > MAX_LENGTH:
                raise _Limit(f"a value of {len(seq) * n} items (at most {MAX_LENGTH})")
    if isinstance(a, int) and isinstance(b, int):
        if a.bit_length() + b.bit_length() > MAX_INT_BITS + 1:
            raise _Limit(f"an integer beyond {MAX_INT_BITS} bits")
    return _check(a * b)


def _pow(a: Any, b: Any) -> Any:
    if isinstance(a, int) and isinstance(b, int) and b > 0 and abs(a) > 1:
        if b > MAX_INT_BITS or (abs(a).bit_length() - 1) * b > MAX_INT_BITS:
            raise _Limit(f"{a} ** {b} is an integer beyond {MAX_INT_BITS} bits")
    if isinstance(a, float | int) and isinstance(b, float | int):
        try:
            return _check(a**b)
        except OverflowError:
            raise _Limit(f"{a} ** {b} overflows") from None
    raise TypeError(f"** of {type(a).__name__} and {type(b).__name__}")


_FORMAT_FIELD = re.compile(r"%[-#0 +]*(\*|\d+)?(?:\.(\*|\d+))?")


def _mod(a: Any, b: Any) -> Any:
    if isinstance(a, str):  # '%s_link' % prefix: widths bounded, none taken from the values
        for width, precision in _FORMAT_FIELD.findall(a):
            for n in (width, precision):
                if n == "*" or (n and int(n) > MAX_LENGTH):
                    raise _Limit(f"a format width of {n} (at most {MAX_LENGTH})")
    return _check(a % b)


def _floordiv(a: Any, b: Any) -> Any:
    return _check(a // b)


def _truediv(a: Any, b: Any) -> Any:
    return a / b


def _sub(a: Any, b: Any) -> Any:
    return _check(a - b)


def _neg(a: Any) -> Any:
    return -a


_OPERATORS: dict[type, Callable[..., Any]] = {
    ast.Add: _add,
    ast.Sub: _sub,
    ast.Mult: _mul,
    ast.Div: _truediv,
    ast.FloorDiv: _floordiv,
    ast.Mod: _mod,
    ast.Pow: _pow,
    ast.USub: _neg,
    ast.UAdd: operator.pos,
    ast.Not: operator.not_,
    ast.Invert: operator.invert,
    ast.BitAnd: operator.and_,
    ast.BitOr: operator.or_,
    ast.BitXor: operator.xor,
    ast.Eq: operator.eq,
    ast.NotEq: operator.ne,
    ast.Lt: operator.lt,
    ast.LtE: operator.le,
    ast.Gt: operator.gt,
    ast.GtE: operator.ge,
    ast.In: lambda a, b: a in b,
    ast.NotIn: lambda a, b: a not in b,
    ast.Is: operator.is_,
    ast.IsNot: operator.is_not,
}


def _bounded_range(*args: int) -> range:
    r = range(*args)
    if len(r) > MAX_LENGTH:
        raise _Limit(f"a range of {len(r)} items (at most {MAX_LENGTH})")
    return r


def _bounded(fn: Callable[..., Any]) -> Callable[..., Any]:
    """``fn`` whose result is checked against the size limits."""

    def call(*args: Any, **kwargs: Any) -> Any:
        return _check(fn(*args, **kwargs))

    call.__name__ = getattr(fn, "__name__", "function")
    return call


def _int(x: Any = 0, *base: int) -> int:
    if isinstance(x, str) and len(x) > 400:  # 400 decimal digits: about 1300 bits
        raise _Limit(f"int() of {len(x)} digits")
    return int(_check(x), *base) if base else _check(int(x))


def _round(x: Any, ndigits: int | None = None) -> Any:
    if ndigits is not None and abs(int(ndigits)) > 400:  # round(5, -10**9) computes 10**10**9
        raise _Limit(f"round() to {ndigits} digits")
    return round(x) if ndigits is None else round(x, ndigits)


def _sum(values: Any, start: Any = 0) -> Any:
    if not isinstance(start, int | float):  # sum(lists, []): quadratic, unbounded
        raise _Limit("sum() of anything but numbers")
    return _check(sum(values, start))


def _builtins() -> dict[str, Any]:
    return {
        "abs": abs,
        "all": all,
        "any": any,
        "bool": bool,
        "dict": _bounded(dict),
        "enumerate": enumerate,
        "float": float,
        "int": _int,
        "len": len,
        "list": _bounded(list),
        "max": max,
        "min": min,
        "range": _bounded_range,
        "reversed": reversed,
        "round": _round,
        "sorted": _bounded(sorted),
        "str": _bounded(str),
        "sum": _sum,
        "tuple": _bounded(tuple),
        "zip": zip,
        "True": True,
        "False": False,
    }


def _math() -> dict[str, Any]:
    out: dict[str, Any] = {k: getattr(math, k) for k in _MATH_FUNCTIONS if hasattr(math, k)}
    out.update({k: getattr(math, k) for k in _MATH_CONSTANTS})
    return out


def _message(kind: str) -> Callable[..., str]:
    def say(*args: Any, **kwargs: Any) -> str:
        warnings.warn(f"xacro {kind}: {' '.join(str(a) for a in args)}", stacklevel=2)
        return ""

    return say


def safe_symbols(xacro_helpers: Mapping[str, Any]) -> dict[str, Any]:
    """The global symbols of an expansion: xacro's, each replaced by an allowed one.

    Args:
        xacro_helpers: The ``xacro.`` helpers (``arg``, ``tokenize``, ``abs_filename``,
            ``dotify``, ``load_yaml``, ``fatal``), pure or guarded by the caller.

    Returns:
        Name -> value: builtins, math (directly and as ``math.``), ``python.`` and ``xacro.``.

    """
    builtins = _builtins()
    maths = _math()
    helpers = dict(xacro_helpers)
    for kind in ("message", "warning", "error"):
        helpers[kind] = _message(kind)
    helpers["print_location"] = lambda *a, **k: ""
    symbols: dict[str, Any] = {**builtins, **maths}
    symbols["load_yaml"] = helpers["load_yaml"]
    symbols["abs_filename"] = helpers["abs_filename"]
    symbols["dotify"] = helpers["dotify"]
    symbols["math"] = _Namespace("math", maths)
    symbols["python"] = _Namespace("python", builtins)
    symbols["xacro"] = _Namespace("xacro", helpers)
    return symbols


def _depth(node: ast.AST) -> int:
    deepest, stack = 0, [(node, 1)]
    while stack:
        n, d = stack.pop()
        deepest = max(deepest, d)
        if deepest > MAX_DEPTH:
            return deepest
        stack.extend((c, d + 1) for c in ast.iter_child_nodes(n))
    return deepest


def _refuse_node(node: ast.AST) -> str | None:
    """Why a syntax node is refused, else ``None``."""
    kind = type(node).__name__
    if isinstance(node, ast.Lambda):
        return "a lambda is not allowed"
    if isinstance(node, ast.ListComp | ast.SetComp | ast.DictComp | ast.GeneratorExp):
        return "a comprehension is not allowed"
    if isinstance(node, ast.JoinedStr | ast.FormattedValue):
        return "an f-string is not allowed"
    if isinstance(node, ast.NamedExpr | ast.Assign | ast.AugAssign | ast.AnnAssign):
        return "an assignment is not allowed"
    if isinstance(node, ast.Starred):
        return "unpacking (*x) is not allowed"
    if isinstance(node, ast.LShift | ast.RShift):
        return "a shift (<<, >>) is not allowed"
    if isinstance(node, ast.Attribute) and node.attr.startswith("_"):
        return f"attribute '{node.attr}' is not allowed"
    if isinstance(node, ast.Name) and node.id.startswith("__"):
        return f"name '{node.id}' is not allowed"
    if isinstance(node, ast.Await | ast.Yield | ast.YieldFrom | ast.Import | ast.ImportFrom):
        return f"{kind} is not allowed"
    return None


class XacroEvaluator:
    """Evaluates one xacro expression against a table of symbols (module docstring).

    Args:
        functions: The callable symbols (looked up for ``f(...)`` by name).

    """

    def __init__(self, functions: Mapping[str, Any]) -> None:
        from simpleeval import SimpleEval

        self._functions = dict(functions)
        self._cls = _evaluator_class(SimpleEval)

    def __call__(self, expression: str, names: Mapping[str, Any]) -> Any:
        """The value of ``expression`` with ``names`` (a xacro symbol table).

        Raises:
            XacroRefused: The expression is not allowed, or exceeds a limit.
            Exception: What a legal expression raises (an undefined name, a division by
                zero...), for xacro to report.

        """
        text = expression.strip()
        if len(text) > MAX_EXPRESSION_CHARS:
            raise XacroRefused(
                text[:60] + "...",
                f"{len(text)} characters long (at most {MAX_EXPRESSION_CHARS})",
            )
        try:
            tree = ast.parse(text, mode="eval")
        except (RecursionError, MemoryError):
            raise XacroRefused(text, f"nested too deeply (at most {MAX_DEPTH})") from None
        except SyntaxError as err:
            if "nested" in str(err) or "too many" in str(err):
                raise XacroRefused(text, f"nested too deeply (at most {MAX_DEPTH})") from None
            raise
        if _depth(tree) > MAX_DEPTH:
            raise XacroRefused(text, f"nested too deeply (at most {MAX_DEPTH})")
        for node in ast.walk(tree):
            why = _refuse_node(node)
            if why is not None:
                raise XacroRefused(text, why)
        ev = self._cls(operators=dict(_OPERATORS), functions=self._functions, names=names)
        try:
            return ev.eval(text, previously_parsed=tree.body)
        except _Limit as err:
            raise XacroRefused(text, f"{err} is not allowed") from None
        except RecursionError:
            raise XacroRefused(text, f"nested too deeply (at most {MAX_DEPTH})") from None
        except Exception as err:
            from simpleeval import FeatureNotAvailable, FunctionNotDefined, OperatorNotDefined

            if isinstance(err, FunctionNotDefined):
                raise XacroRefused(text, f"function '{err.func_name}' is not allowed") from None
            if isinstance(err, FeatureNotAvailable | OperatorNotDefined):
                raise XacroRefused(text, f"{err} (not allowed)") from None
            raise


def _evaluator_class(base: type) -> type:
    """The evaluator class: simpleeval's, pkdyn's attribute rule, literals and size checks."""

    class _Evaluator(base):  # type: ignore[misc, valid-type]
        def __init__(self, **kwargs: Any) -> None:
            super().__init__(**kwargs)
            self.nodes.pop(ast.JoinedStr, None)
            self.nodes.pop(ast.FormattedValue, None)
            self.nodes.pop(ast.Assign, None)
            self.nodes.pop(ast.AugAssign, None)
            self.nodes.update(
                {
                    ast.List: lambda n: _check([self._eval(x) for x in n.elts]),
                    ast.Tuple: lambda n: _check(tuple(self._eval(x) for x in n.elts)),
                    ast.Dict: self._eval_dict_literal,
                }
            )

        def _eval_dict_literal(self, node: ast.Dict) -> dict[Any, Any]:
            out: dict[Any, Any] = {}
            for k, v in zip(node.keys, node.values, strict=True):
                if k is None:
                    raise XacroRefused(self.expr, "unpacking (**x) is not allowed")
                out[self._eval(k)] = self._eval(v)
            return _check(out)

        def _eval_attribute(self, node: ast.Attribute) -> Any:
            obj = self._eval(node.value)
            return _attribute(self.expr, obj, node.attr)

        def _eval(self, node: ast.AST) -> Any:
            try:
                handler = self.nodes[type(node)]
            except KeyError:
                raise XacroRefused(self.expr, f"{type(node).__name__} is not allowed") from None
            return _check(handler(node))  # (sizes first: simpleeval's walk of a huge value)

        def _check_disallowed_items(self, item: Any) -> None:
            if isinstance(item, types.ModuleType):  # (none is reachable: no symbol is one)
                raise XacroRefused(self.expr, "a module is not allowed")

    return _Evaluator


def _attribute(expression: str, obj: Any, attr: str) -> Any:
    """``obj.attr`` where the rule of the module docstring allows it."""
    if attr.startswith("_"):
        raise XacroRefused(expression, f"attribute '{attr}' is not allowed")
    if isinstance(obj, _Namespace):
        try:
            return obj.lookup(attr)
        except LookupError as err:
            raise XacroRefused(expression, f"{err} (not allowed)") from None
    if isinstance(obj, dict):  # YAML mappings (xacro's dotify) and xacro namespaces
        if type(obj).__name__ in ("YamlDictWrapper", "NameSpace"):
            return obj[attr]
    if isinstance(obj, str) and attr in _STR_METHODS:
        return getattr(obj, attr)
    raise XacroRefused(expression, f"attribute '{attr}' of a {type(obj).__name__} is not allowed")
