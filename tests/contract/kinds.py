"""The kinds of arguments an entry point takes, and the bad-input classes each kind is driven by.

A kind (``Real``, ``Count``, ``Vector``, ``Names``, ``PathIn``...) knows, for the API and for
the command line, which bad-input classes apply to it and, for each class, a ``hypothesis``
strategy of :class:`Case`: a recipe that builds one bad value in a scratch directory, and
whether the contract demands that it be refused (``refuse``) or lets the entry point either
accept it (with a valid result) or refuse it with a typed error.

The classes (names used in test ids and in ``docs/guide/guarantees.md``):

========================  =====================================================================
``non_finite``            NaN, +inf, -inf
``huge``                  1e12 .. 1e308 (beyond any plausible SI value or count)
``tiny``                  1e-300, the smallest subnormal (a step or tolerance that never ends)
``zero``                  0, -0.0
``negative``              negative values (on the command line in scientific notation too)
``fraction``              2.5 where a count is due
``wrong_type``            a string, bytes, complex, bool, list, dict, None, an object
``wrong_size``            one value too many or too few
``ragged``                nested lists of unequal lengths
``empty``                 an empty list, string or file
``unknown``               a name or choice the entry point does not know
``not_callable``          a number where a function is due
``raises``                a callback raising ``ValueError``
``exits``                 a callback calling ``sys.exit``
``returns_garbage``       a callback returning a string, ``None`` or NaN
``missing``               a file that does not exist
``directory``             a directory where a file is due
``fifo``                  a named pipe (reading it would block)
``device``                ``/dev/zero`` or ``/dev/null``
``link``                  a symbolic link to a device
``binary``                random bytes
``non_utf8``              Latin-1 text
``header_only``           a table with its header and no row
``bom``                   a table with a UTF-8 byte-order mark (Excel's): read like without
``crlf``                  a table with Windows line ends: read like without
``huge_cell``             a cell beyond the csv module's field limit (128 KiB)
``trailing_slash``        an output name ending in ``/``
``onto_input``            an output that is one of the entry point's inputs
========================  =====================================================================
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from hypothesis import strategies as st

__all__ = [
    "Arg",
    "Callback",
    "Case",
    "Choice",
    "Count",
    "Flag",
    "Kind",
    "Lazy",
    "Mapping",
    "Matrix",
    "Names",
    "Obj",
    "Opaque",
    "PathIn",
    "PathOut",
    "Pose",
    "Real",
    "RobotArg",
    "Scratch",
    "Text",
    "Vector",
]


@dataclass
class Scratch:
    """Where one example runs: a fresh directory, the entry's robot and its valid input files.

    Attributes:
        dir: The scratch directory (removed after the example).
        robot: The robot the entry's sizes and names refer to (``None`` for none).
        inputs: Valid input files of the entry, by argument or option name.

    """

    dir: Path
    robot: Any = None
    inputs: dict[str, Path] = field(default_factory=dict)

    def size(self, size: int | str | None) -> int | None:
        """A symbolic size (``nq``, ``nv``, ``n_a``) resolved on the robot."""
        if size is None or isinstance(size, int):
            return size
        r = self.robot
        return {"nq": r.nq, "nv": r.nv, "n_a": len(r.actuators), "task": len(r.task_rows)}[size]


@dataclass(frozen=True)
class Case:
    """One bad value: its class, how to build it, and what the contract demands.

    Attributes:
        cls: The bad-input class (module docstring).
        label: A short description for reports.
        make: Builds the value in a scratch directory (API: the value; CLI: the tokens that
            follow the option, or ``None`` to leave the option out).
        refuse: The contract demands a refusal: a typed pkdyn error (API), exit 1 or 2 with
            one line (CLI). Otherwise a valid result is allowed too.
        same: When accepted, the result must equal the baseline's (a table with a BOM...).
        usage_ok: On the command line, a usage error (exit 2) is an acceptable refusal
            (``False`` for a value argparse should take, like a negative number).

    """

    cls: str
    label: str
    make: Callable[[Scratch], Any]
    refuse: bool = True
    same: bool = False
    usage_ok: bool = True

    def __repr__(self) -> str:  # hypothesis prints it for a failing example
        return f"<{self.cls}: {self.label}>"


def _const(cls: str, values: Sequence[Any], refuse: bool = True, **kw: Any) -> st.SearchStrategy:
    return st.sampled_from(list(values)).map(
        lambda v: Case(cls, repr(v)[:80], lambda s, v=v: v, refuse, **kw)
    )


def _tokens(cls: str, values: Sequence[Sequence[str]], refuse: bool = True, **kw: Any):
    return st.sampled_from([list(v) for v in values]).map(
        lambda v: Case(cls, " ".join(v) or "(no value)", lambda s, v=v: list(v), refuse, **kw)
    )


class Kind:
    """The kind of an argument: its bad-input classes, for the API and for the command line."""

    optional: bool = False

    def api(self) -> dict[str, st.SearchStrategy]:
        """Strategies of bad values for a Python call, by class."""
        return {}

    def cli(self) -> dict[str, st.SearchStrategy]:
        """Strategies of bad tokens for a command-line option, by class."""
        return {}

    def _none(self) -> list[Any]:
        return [] if self.optional else [None]


_WRONG_SCALARS = ["1.0", "abc", b"1", 1 + 0j, [1.0], {"value": 1.0}, True, object()]


@dataclass
class Real(Kind):
    """A real number [unit] of a sign (``any``, ``positive``, ``non_negative``)."""

    unit: str = ""
    sign: str = "any"
    optional: bool = False
    inf_ok: bool = False
    nargs: int = 1

    def api(self) -> dict[str, st.SearchStrategy]:
        pos, nonneg = self.sign == "positive", self.sign in ("positive", "non_negative")
        nf = [math.nan, -math.inf] + ([] if self.inf_ok else [math.inf])
        return {
            "non_finite": _const("non_finite", nf + [np.float64("nan")]),
            "huge": _const("huge", [1e308, -1e308, 1e300, 1e12], refuse=False),
            "tiny": _const("tiny", [1e-300, 5e-324], refuse=False),
            "zero": _const("zero", [0.0, -0.0, 0], refuse=pos),
            "negative": st.one_of(
                _const("negative", [-1, -1e-300], refuse=nonneg),
                st.floats(-1e3, -1e-6).map(
                    lambda v: Case("negative", repr(v), lambda s, v=v: v, nonneg)
                ),
            ),
            "wrong_type": _const("wrong_type", _WRONG_SCALARS + self._none()),
        }

    def cli(self) -> dict[str, st.SearchStrategy]:
        pos, nonneg = self.sign == "positive", self.sign in ("positive", "non_negative")
        n = self.nargs

        def rep(vals: list[str]) -> list[list[str]]:
            return [[v] * n for v in vals]

        return {
            "non_finite": _tokens(
                "non_finite",
                rep(["nan", "-nan", "NaN"] + ["-inf"] * 1 + ([] if self.inf_ok else ["inf"])),
            ),
            "huge": _tokens("huge", rep(["1e308", "-1e308", "1e12"]), refuse=False),
            "tiny": _tokens("tiny", rep(["1e-300", "5e-324"]), refuse=False),
            "zero": _tokens("zero", rep(["0", "-0", "0e0"]), refuse=pos),
            "negative": _tokens(
                "negative",
                rep(["-3.6e-1", "-5E+1", "-.5", "-1e-3"]),
                refuse=nonneg,
                usage_ok=nonneg,
            ),
            "wrong_type": _tokens("wrong_type", rep(["abc", "1,5", "0x10", ""])),
        }


@dataclass
class Count(Kind):
    """A whole number >= ``minimum``."""

    minimum: int = 1
    optional: bool = False

    def api(self) -> dict[str, st.SearchStrategy]:
        return {
            "non_finite": _const("non_finite", [math.nan, math.inf]),
            "huge": _const("huge", [10**12, 10**18, 2**63, 10**100], refuse=False),
            "zero": _const("zero", [0], refuse=self.minimum > 0),
            "negative": _const("negative", [-1, -(10**6)], refuse=self.minimum >= 0),
            "fraction": _const("fraction", [2.5, 0.5]),
            "wrong_type": _const(
                "wrong_type", ["3", "abc", True, [3], 3 + 0j, object()] + self._none()
            ),
        }

    def cli(self) -> dict[str, st.SearchStrategy]:
        return {
            "non_finite": _tokens("non_finite", [["nan"], ["inf"]]),
            "huge": _tokens("huge", [["1000000000000"], ["99999999999999999999"]], refuse=False),
            "zero": _tokens("zero", [["0"]], refuse=self.minimum > 0),
            "negative": _tokens("negative", [["-1"], ["-1000000"]], refuse=self.minimum >= 0),
            "fraction": _tokens("fraction", [["2.5"], ["2e0"]], refuse=False),
            "wrong_type": _tokens("wrong_type", [["abc"], [""], ["3x"]]),
        }


@dataclass
class Flag(Kind):
    """``True`` or ``False`` (a command-line switch: nothing to drive)."""

    optional: bool = False

    def api(self) -> dict[str, st.SearchStrategy]:
        return {"wrong_type": _const("wrong_type", ["no", "False", "yes", [True]] + self._none())}


def _vectors(n: int | None, bound: float = 1.0) -> st.SearchStrategy:
    size = 3 if n is None else n
    return st.lists(st.floats(-bound, bound), min_size=size, max_size=size)


@dataclass
class Vector(Kind):
    """A flat array of ``size`` real numbers (an int, a symbolic ``nq``/``nv``/``n_a``, a
    tuple of accepted sizes, or ``None`` for any size)."""

    size: int | str | tuple[int, ...] | None = None
    unit: str = ""
    optional: bool = False
    inf_ok: bool = False
    empty_ok: bool = False
    scalar_ok: bool = False

    def _n(self, s: Scratch) -> int:
        if isinstance(self.size, tuple):
            return self.size[-1]
        return s.size(self.size) or 3

    def _wrong(self, s: Scratch, d: int) -> int:
        """A size the argument does not take: one less (``d < 0``) or one more than it does."""
        sizes = self.size if isinstance(self.size, tuple) else (self._n(s),)
        n = min(sizes) - 1 if d < 0 else max(sizes) + 1
        if n <= 0 or n in sizes:
            n = max(sizes) + 1
        return n

    def api(self) -> dict[str, st.SearchStrategy]:
        def make(cls: str, label: str, fn: Callable[[int], Any], refuse: bool = True):
            return Case(cls, label, lambda s: fn(self._n(s)), refuse)

        def poison(v: float) -> Callable[[int], Any]:
            return lambda n: [0.0] * (n - 1) + [v]

        bad_size = self.size is not None
        out = {
            "non_finite": st.sampled_from(
                [math.nan] + ([] if self.inf_ok else [math.inf]) + [-math.inf]
            ).map(lambda v: make("non_finite", f"[.., {v}]", poison(v))),
            "huge": st.sampled_from([1e308, 1e15]).map(
                lambda v: make("huge", f"[.., {v}]", poison(v), refuse=False)
            ),
            "ragged": st.just(
                make("ragged", "[[0, ...], [0]]", lambda n: [[0.0] * (n + 1), [0.0]])
            ),
            "empty": st.just(make("empty", "[]", lambda n: [], refuse=not self.empty_ok)),
            "wrong_type": st.sampled_from(
                ["abc", {"x": 1.0}, ["a", "b", "c"], 1j, object()] + self._none()
            ).map(
                lambda v: make(
                    "wrong_type",
                    repr(v)[:40],
                    lambda n, v=v: [v] * n if isinstance(v, complex) else v,
                )
            ),
        }
        if bad_size:
            out["wrong_size"] = st.sampled_from([-1, 1]).map(
                lambda d: Case(
                    "wrong_size", f"{d:+d} value", lambda s, d=d: [0.1] * self._wrong(s, d)
                )
            )
        return out

    def cli(self) -> dict[str, st.SearchStrategy]:
        def make(
            cls: str, label: str, fn: Callable[[int], list[str]], refuse: bool = True, **kw: Any
        ):
            return Case(cls, label, lambda s: fn(self._n(s)), refuse, **kw)

        def poison(v: str) -> Callable[[int], list[str]]:
            return lambda n: ["0"] * (n - 1) + [v]

        out = {
            "non_finite": st.sampled_from(["nan", "-inf"] + ([] if self.inf_ok else ["inf"])).map(
                lambda v: make("non_finite", f".. {v}", poison(v))
            ),
            "huge": st.sampled_from(["1e308", "-1e308"]).map(
                lambda v: make("huge", f".. {v}", poison(v), refuse=False)
            ),
            "negative": st.sampled_from(["-3.6e-1", "-5E-2", "-.05"]).map(
                lambda v: make("negative", f".. {v}", poison(v), refuse=False, usage_ok=False)
            ),
            "wrong_type": st.sampled_from(["abc", "1,5", ""]).map(
                lambda v: make("wrong_type", f".. {v!r}", poison(v))
            ),
        }
        if self.size is not None:
            out["wrong_size"] = st.sampled_from([-1, 1]).map(
                lambda d: Case(
                    "wrong_size", f"{d:+d} value", lambda s, d=d: ["0.1"] * self._wrong(s, d)
                )
            )
        return out


@dataclass
class Pose(Vector):
    """A platform pose: ``[x, y, z]`` or ``[x, y, z, roll, pitch, yaw]`` [m, rad] (or the
    components the robot controls), or a ``pin.SE3``."""

    size: int | str | tuple[int, ...] | None = (3, 6)


@dataclass
class Matrix(Kind):
    """A 2-D array of ``rows`` x ``cols`` real numbers (symbolic sizes as for :class:`Vector`;
    ``None``: any)."""

    rows: int | str | None = None
    cols: int | str | None = None
    optional: bool = False

    def _shape(self, s: Scratch) -> tuple[int, int]:
        return (s.size(self.rows) or 4, s.size(self.cols) or 3)

    def api(self) -> dict[str, st.SearchStrategy]:
        def make(cls: str, label: str, fn: Callable[[int, int], Any], refuse: bool = True):
            return Case(cls, label, lambda s: fn(*self._shape(s)), refuse)

        def poison(v: float) -> Callable[[int, int], Any]:
            def fn(r: int, c: int) -> np.ndarray:
                a = np.zeros((r, c))
                a[-1, -1] = v
                return a

            return fn

        return {
            "non_finite": st.sampled_from([math.nan, math.inf]).map(
                lambda v: make("non_finite", f"[[.., {v}]]", poison(v))
            ),
            "huge": st.just(make("huge", "[[.., 1e308]]", poison(1e308), refuse=False)),
            "ragged": st.just(
                make("ragged", "rows of unequal length", lambda r, c: [[0.0] * c, [0.0] * (c + 1)])
            ),
            "empty": st.just(make("empty", "[]", lambda r, c: [])),
            "wrong_size": st.just(
                make("wrong_size", "one column too many", lambda r, c: np.zeros((r, c + 1)))
            ),
            "wrong_type": st.sampled_from(["abc", {"a": 1}, 3j, object()] + self._none()).map(
                lambda v: make("wrong_type", repr(v)[:40], lambda r, c, v=v: v)
            ),
        }


@dataclass
class Names(Kind):
    """A list of names taken from the robot (``joints``, ``actuators``, ``frames``,
    ``actuated_joints``) or from a fixed list (``known``)."""

    source: str = "joints"
    known: tuple[str, ...] = ()
    optional: bool = False
    empty_ok: bool = False

    def api(self) -> dict[str, st.SearchStrategy]:
        return {
            "wrong_type": _const(
                "wrong_type", [[1, 2], 3, 1.5, {"a": 1}, [None], b"x"] + self._none()
            ),
            "ragged": _const("ragged", [[["a"], ["b", "c"]], [("x", 1)]]),
            "empty": _const("empty", [[], ()], refuse=not self.empty_ok),
            "unknown": _const("unknown", [["no_such_name"], ["", "x"]]),
        }

    def cli(self) -> dict[str, st.SearchStrategy]:
        return {"unknown": _tokens("unknown", [["no_such_name"], [""]])}


@dataclass
class Choice(Kind):
    """One string among ``options``."""

    options: tuple[str, ...] = ()
    optional: bool = False

    def api(self) -> dict[str, st.SearchStrategy]:
        wrong = [v for v in (3, ["a"], b"x", 1.5) if v not in self.options]
        return {
            "unknown": _const("unknown", ["no_such_choice", "x" * 300]),
            "empty": _const("empty", [""]),
            "wrong_type": _const("wrong_type", wrong + self._none()),
        }

    def cli(self) -> dict[str, st.SearchStrategy]:
        return {
            "unknown": _tokens("unknown", [["no_such_choice"], ["x" * 300]]),
            "empty": _tokens("empty", [[""]]),
        }


@dataclass
class Text(Kind):
    """A free string (a name, a title, a source label)."""

    optional: bool = False

    def api(self) -> dict[str, st.SearchStrategy]:
        return {"wrong_type": _const("wrong_type", [3, ["a"], b"x", 1.5] + self._none())}


@dataclass
class Mapping(Kind):
    """A mapping of names to values: ``example`` is a valid one; bad values replace its
    values by a string and by ``None``; unknown keys are refused unless ``open``."""

    example: dict[str, Any] = field(default_factory=dict)
    optional: bool = False
    open: bool = False

    def api(self) -> dict[str, st.SearchStrategy]:
        key = next(iter(self.example), "x")
        out = {
            "wrong_type": _const("wrong_type", [[1, 2], 3, "k=v", [("a", 1)]] + self._none()),
            "bad_value": _const("bad_value", [{key: "abc"}, {key: [1, [2]]}, {key: {"a": 1}}]),
        }
        if not self.open:
            out["unknown"] = _const("unknown", [{"no_such_key": 1.0}, {3: 1.0}])
        return out

    def cli(self) -> dict[str, st.SearchStrategy]:
        key = next(iter(self.example), "x")
        return {
            "wrong_type": _tokens("wrong_type", [[key], ["=1"], [f"{key}="]]),
            "bad_value": _tokens("bad_value", [[f"{key}=abc"], [f"{key}=nan"], [f"{key}=1e308"]]),
            "unknown": _tokens("unknown", [["no_such_key=1"]]),
        }


def _raise_value_error(*args: Any) -> Any:
    raise ValueError("boom")


def _exit(*args: Any) -> Any:
    raise SystemExit(0)


@dataclass
class Callback(Kind):
    """A user function (a torque law, a metric): it may raise, exit or return garbage."""

    optional: bool = False

    def api(self) -> dict[str, st.SearchStrategy]:
        return {
            "not_callable": _const("not_callable", [3, "f", [len]] + self._none()),
            "raises": _const("raises", [_raise_value_error]),
            "exits": _const("exits", [_exit]),
            "returns_garbage": _const(
                "returns_garbage",
                [lambda *a: "abc", lambda *a: None, lambda *a: math.nan, lambda *a: {"a": 1}],
            ),
        }


@dataclass
class RobotArg(Kind):
    """A :class:`pkdyn.Robot` (``pkdyn.load``)."""

    optional: bool = False

    def api(self) -> dict[str, st.SearchStrategy]:
        import pinocchio as pin

        return {
            "wrong_type": st.one_of(
                _const("wrong_type", [3, {"name": "delta"}, b"delta"] + self._none()),
                st.just(Case("wrong_type", "pin.Model()", lambda s: pin.Model())),
                _const("wrong_type", ["delta"], refuse=False),
            )
        }


@dataclass
class Obj(Kind):
    """An instance of a pkdyn type (``Measurements``, ``ElasticModel``, ``Material``...)."""

    what: str = ""
    optional: bool = False

    def api(self) -> dict[str, st.SearchStrategy]:
        return {"wrong_type": _const("wrong_type", [3, "x", {}, [1.0]] + self._none())}


@dataclass
class Opaque(Kind):
    """An argument the harness does not drive (a matplotlib axis, a Dask client...), with the
    reason."""

    reason: str = ""


_FIFO_OK = hasattr(os, "mkfifo")


def _file(name: str, data: bytes) -> Callable[[Scratch], Path]:
    def make(s: Scratch) -> Path:
        p = s.dir / name
        p.write_bytes(data)
        return p

    return make


def _fifo(s: Scratch) -> Path:
    p = s.dir / "pipe.csv"
    os.mkfifo(p)
    return p


def _link(target: str) -> Callable[[Scratch], Path]:
    def make(s: Scratch) -> Path:
        p = s.dir / "link.csv"
        p.symlink_to(target)
        return p

    return make


def _variant(key: str, fn: Callable[[bytes], bytes], name: str = "") -> Callable[[Scratch], Path]:
    """A variant of the entry's valid input file ``key``."""

    def make(s: Scratch) -> Path:
        src = s.inputs[key]
        (s.dir / "variant").mkdir(exist_ok=True)
        p = s.dir / "variant" / (name or src.name)
        p.write_bytes(fn(src.read_bytes()))
        return p

    return make


def _header_only(data: bytes) -> bytes:
    lines = [ln for ln in data.splitlines(keepends=True) if not ln.startswith(b"#")]
    return lines[0] if lines else b""


def _huge_cell(data: bytes) -> bytes:
    lines = data.splitlines(keepends=True)
    k = next((i for i, ln in enumerate(lines) if not ln.startswith(b"#")), 0)
    row = min(k + 1, len(lines) - 1)
    cells = lines[row].rstrip(b"\r\n").split(b",")
    cells[-1] = b"1" * 200_000
    lines[row] = b",".join(cells) + b"\n"
    return b"".join(lines)


@dataclass
class PathIn(Kind):
    """An input file read by the entry point; ``key`` names its valid version in
    :attr:`Scratch.inputs`; ``fmt`` is ``csv``, ``yaml``, ``urdf`` or ``py``."""

    key: str = ""
    fmt: str = "csv"
    optional: bool = False

    def _classes(self) -> dict[str, st.SearchStrategy]:
        def case(cls: str, label: str, make: Callable[[Scratch], Path], **kw: Any):
            return st.just(Case(cls, label, make, **kw))

        ext = f".{self.fmt}"
        out = {
            "missing": case("missing", "no such file", lambda s: s.dir / f"missing{ext}"),
            "directory": case("directory", "a directory", lambda s: s.dir),
            "device": st.sampled_from(["/dev/zero", "/dev/null"]).map(
                lambda d: Case("device", d, lambda s, d=d: Path(d))
            ),
            "link": case("link", "link to /dev/zero", _link("/dev/zero")),
            "empty": case(
                "empty", "an empty file", _file(f"empty{ext}", b""), refuse=self.fmt != "py"
            ),
            "binary": st.binary(min_size=16, max_size=64).map(
                lambda b: Case(
                    "binary", f"{len(b)} random bytes", _file(f"bin{ext}", b"\x00\xff" + b)
                )
            ),
            "non_utf8": case(
                "non_utf8",
                "Latin-1 text",
                _variant(self.key, lambda d: d.replace(b"\n", " \xe9\xe8\n".encode("latin-1"), 1)),
            ),
        }
        if _FIFO_OK:
            out["fifo"] = case("fifo", "a named pipe", _fifo)
        if self.fmt == "csv":
            out |= {
                "header_only": case(
                    "header_only", "header, no row", _variant(self.key, _header_only)
                ),
                "bom": case(
                    "bom",
                    "UTF-8 BOM",
                    _variant(self.key, lambda d: b"\xef\xbb\xbf" + d),
                    refuse=False,
                    same=True,
                ),
                "crlf": case(
                    "crlf",
                    "CRLF line ends",
                    _variant(self.key, lambda d: d.replace(b"\r\n", b"\n").replace(b"\n", b"\r\n")),
                    refuse=False,
                    same=True,
                ),
                "huge_cell": case("huge_cell", "a 200 kB cell", _variant(self.key, _huge_cell)),
            }
        return out

    def api(self) -> dict[str, st.SearchStrategy]:
        return self._classes() | {"wrong_type": _const("wrong_type", [3, ["a.csv"]] + self._none())}

    def cli(self) -> dict[str, st.SearchStrategy]:
        return {k: v.map(_as_tokens) for k, v in self._classes().items()}


def _as_tokens(case: Case) -> Case:
    return Case(
        case.cls, case.label, lambda s: [str(case.make(s))], case.refuse, case.same, case.usage_ok
    )


@dataclass
class PathOut(Kind):
    """An output file written by the entry point (``ext``: its extension; ``onto``: the
    input keys it must never overwrite)."""

    ext: str = ".csv"
    onto: tuple[str, ...] = ()
    optional: bool = False

    def _classes(self) -> dict[str, st.SearchStrategy]:
        def case(cls: str, label: str, make: Callable[[Scratch], Path]):
            return st.just(Case(cls, label, make))

        out = {
            "directory": case("directory", "a directory", lambda s: s.dir),
            "missing": case(
                "missing", "in a missing directory", lambda s: s.dir / "no" / f"x{self.ext}"
            ),
            "device": case("device", "/dev/null", lambda s: Path("/dev/null")),
            "link": case("link", "link to /dev/null", _link("/dev/null")),
            "trailing_slash": case(
                "trailing_slash",
                "NAME/ (a directory meant)",
                lambda s: f"{s.dir}/new{self.ext}/",  # (a str: pathlib would drop the slash)
            ),
        }
        if _FIFO_OK:
            out["fifo"] = case("fifo", "a named pipe", _fifo)
        if self.onto:
            out["onto_input"] = st.sampled_from(list(self.onto)).map(
                lambda k: Case("onto_input", f"onto input {k}", lambda s, k=k: s.inputs[k])
            )
        return out

    def api(self) -> dict[str, st.SearchStrategy]:
        return self._classes() | {"wrong_type": _const("wrong_type", [3, ["x.csv"]])}

    def cli(self) -> dict[str, st.SearchStrategy]:
        def tok(case: Case) -> Case:
            def make(s: Scratch) -> list[str]:
                p = case.make(s)
                return [str(p)]

            return Case(case.cls, case.label, make, case.refuse)

        # (onto an input: every combination is driven by test_contract_files.py, where the
        # command is given the input it would overwrite)
        return {k: v.map(tok) for k, v in self._classes().items() if k != "onto_input"}


@dataclass(frozen=True)
class Arg:
    """One argument of an entry point: its kind, its valid baseline value, the words a
    refusal may use to name it.

    Attributes:
        kind: The kind.
        baseline: A valid value, or a function of the scratch directory returning one
            (``None``-valued optional arguments are left at their default).
        names: Words one of which a refusal's message must contain (default: the argument's
            name, and for an option its name without dashes).
        skip: Classes not driven for this argument, with the reason (``{"huge": "..."}``).
        context: On the command line, tokens added when this option is driven, so that it
            matters (``--map xy`` for ``--grid``).

    """

    kind: Kind
    baseline: Any = None
    names: tuple[str, ...] = ()
    skip: dict[str, str] = field(default_factory=dict)
    context: tuple[str, ...] = ()

    def value(self, s: Scratch) -> Any:
        """The baseline value (built now when it is :class:`Lazy`)."""
        return self.baseline.fn(s) if isinstance(self.baseline, Lazy) else self.baseline


@dataclass(frozen=True)
class Lazy:
    """A baseline value built per example from the scratch directory (a configuration of the
    robot, a file...)."""

    fn: Callable[[Scratch], Any]
