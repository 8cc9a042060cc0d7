"""No code from data: xacro expressions go through pkdyn's restricted, bounded evaluator.

The corpus holds real escapes (the first runs ``touch`` under the ``xacro`` package's own
evaluator, which the first test shows), attribute walks (dunder and not), lambdas,
comprehensions, huge numbers and strings, deep nesting and unlisted functions; each is refused
with one line naming the expression, and no marker file appears.
"""

from __future__ import annotations

import subprocess
import sys
import warnings
from pathlib import Path
from xml.sax.saxutils import escape

import pytest

import pkdyn
from pkdyn.exceptions import DescriptionError

pytest.importorskip("xacro")

PUBLIC = Path(__file__).parent / "data" / "public"

HEAD = '<?xml version="1.0"?>\n<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="arm">\n'
BODY = """  <link name="base"/>
  <link name="arm"><inertial><origin xyz="{x} 0 0"/><mass value="1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>
"""


def _file(tmp_path: Path, x: str, extra: str = "", name: str = "arm.urdf.xacro") -> Path:
    """A xacro file whose arm's centre of mass is at ``x`` (text of an XML attribute)."""
    path = tmp_path / name
    path.write_text(HEAD + extra + BODY.format(x=escape(x, {'"': "&quot;"})))
    return path


def _touch_through_subclasses(marker: Path) -> str:
    """Runs ``touch marker`` under Python's eval with xacro's symbols (no dunder name used)."""
    init = "python.vars(c)['__init__']"
    globals_ = f"python.vars(python.type({init}))['__globals__']"
    get = f"python.vars(python.type({globals_}))['__get__']"
    classes = "python.vars(python.type)['__subclasses__'](python.type(1).mro()[1])"
    return (
        f"[{get}({globals_}, {init})['system']('touch {marker}') for c in {classes} "
        "if 'os._wrap_close' in python.repr(c)][0]"
    )


def test_the_corpus_escape_is_real_under_xacros_own_evaluator(tmp_path):
    import xacro

    marker = tmp_path / "MARK"
    path = _file(tmp_path, "${" + _touch_through_subclasses(marker) + "}")
    xacro.process_file(str(path))  # the package alone: eval with its symbols
    assert marker.exists()


CORPUS = {
    "subclasses walk": "TOUCH",
    "dunder class": "().__class__",
    "dunder bases": "().__class__.__bases__[0].__subclasses__()",
    "method self": "[].copy.__self__",
    "non-dunder method": "[].copy",
    "xacro dict": "xacro.__dict__",
    "math os": "math.os",
    "math factorial": "math.factorial(100000)",
    "python vars": "python.vars(python.type)",
    "python type": "python.type(1)",
    "str method format": "'x'.format(1)",
    "str method replace": "('a'*90000).replace('a', 'a'*90000)",
    "type mro": "str.mro()",
    "import": "__import__('os').system('touch MARKER')",
    "lambda": "(lambda: 1)()",
    "list comprehension": "[x for x in range(3)]",
    "nested comprehension": "[[y for y in x] for x in ['ab']]",
    "generator": "sum(x for x in range(3))",
    "f-string": "f'abc'",
    "walrus": "(y := 1)",
    "huge power": "9**9**9",
    "big power": "2**5000",
    "huge string": "'a'*10**9",
    "huge list": "[0]*10**9",
    "long text of a list": "str(['a'*90000]*90000)",
    "shift": "1 << 100000",
    "round to far digits": "round(5, -10**9)",
    "sum of lists": "sum([[1]]*10, [])",
    "format width": "'%0999999999d' % 1",
    "unpacking": "[*range(10**9)]",
    "deep nesting": "-" * 200 + "1",
    "deep lists": "[" * 80 + "]" * 80,
    "getattr": "getattr(1, 'real')",
    "open": "open('/etc/passwd')",
    "eval": "eval('1')",
    "range too long": "list(range(10**9))",
}


@pytest.mark.parametrize("expr", list(CORPUS.values()), ids=list(CORPUS))
def test_escape_corpus_is_refused_in_one_line(tmp_path, expr):
    marker = tmp_path / "MARK"
    text = expr.replace("TOUCH", _touch_through_subclasses(marker)).replace("MARKER", str(marker))
    path = _file(tmp_path, "${" + text + "}")
    with pytest.raises(DescriptionError) as err:
        pkdyn.load(path)
    msg = str(err.value)
    assert "xacro expression" in msg and "not allowed" in msg and "\n" not in msg
    assert not marker.exists()


def test_the_cli_refuses_in_one_line_exit_1(tmp_path):
    marker = tmp_path / "MARK"
    path = _file(tmp_path, "${" + _touch_through_subclasses(marker) + "}")
    run = subprocess.run(
        [sys.executable, "-m", "pkdyn", "info", str(path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 1 and run.stdout == ""
    assert run.stderr.count("\n") == 1 and run.stderr.startswith("pkdyn: error: ")
    assert "xacro expression" in run.stderr and "not allowed" in run.stderr
    assert not marker.exists()


@pytest.mark.parametrize(
    "extension",
    [
        "$(eval __builtins__)",
        "$(eval [].__class__)",
        "$(eval [x for x in 'ab'])",
        "$(eval math.os)",
        "$(env HOME)",
    ],
    ids=["eval builtins", "eval dunder", "eval comprehension", "eval math os", "env"],
)
def test_substitutions_are_refused(tmp_path, extension):
    marker = tmp_path / "MARK"
    path = _file(tmp_path, extension.replace("MARKER", str(marker)))
    with pytest.raises(DescriptionError, match="not allowed") as err:
        pkdyn.load(path)
    assert "\n" not in str(err.value) and not marker.exists()


def test_the_xacro_module_is_restored_after_a_load(tmp_path):
    import xacro

    before = (xacro.safe_eval, xacro._global_symbols, xacro.eval_text, xacro.parse)
    with pytest.raises(DescriptionError):
        pkdyn.load(_file(tmp_path, "${().__class__}"))
    pkdyn.load(_file(tmp_path, "0.25", name="ok.urdf.xacro"))
    assert (xacro.safe_eval, xacro._global_symbols, xacro.eval_text, xacro.parse) == before


# ------------------------------------------------------------------ what real files use

SUBSET = """  <xacro:arg name="length" default="0.5"/>
  <xacro:property name="L" value="$(arg length)"/>
  <xacro:property name="cfg" value="${xacro.load_yaml('cfg.yaml')}"/>
  <xacro:property name="half" value="${L/2}"/>
  <xacro:property name="name" value="${'arm' + '_' + str(1)}"/>
  <xacro:property name="v" value="${[0.1, 0.2, 0.3]}"/>
"""

SUBSET_CHECKS = {
    "arithmetic": ("${half * 2 - L + 0.25}", 0.25),
    "power": ("${(2**2 + 0.5**2) / 17.0}", 0.25),
    "math": ("${math.sin(pi/6) / 2}", 0.25),
    "direct math": ("${sin(radians(30)) / 2}", 0.25),
    "degrees": ("${degrees(pi) / 720}", 0.25),
    "conditional": ("${0.25 if L > 0.1 and not L > 1 else 9}", 0.25),
    "comparison chain": ("${0.25 if 0 < L <= 0.5 != 3 else 9}", 0.25),
    "yaml dotted": ("${cfg.arm.com}", 0.25),
    "yaml indexed": ("${cfg['arm']['list'][1]}", 0.25),
    "yaml units": ("${cfg.arm.mm}", 0.25),
    "list index": ("${v[0] + v[2] - v[1] + 0.05}", 0.25),
    "string ops": (
        "${0.25 if name.upper() == 'ARM_1' and name.split('_')[0] == 'arm' else 9}",
        0.25,
    ),
    "builtins": ("${max(0.25, min(v)) + len(v) * 0 + abs(-0.0) + int('0')}", 0.25),
    "python ns": ("${python.round(0.2500001, 4)}", 0.25),
    "format percent": ("${float('%.2f' % 0.25)}", 0.25),
    "eval extension": ("$(eval 0.125 * 2)", 0.25),
    "optenv default": ("$(optenv PKDYN_NO_SUCH_VARIABLE 0.25)", 0.25),
}


@pytest.mark.parametrize("x, value", list(SUBSET_CHECKS.values()), ids=list(SUBSET_CHECKS))
def test_the_subset_real_files_use_is_evaluated(tmp_path, x, value):
    (tmp_path / "cfg.yaml").write_text(
        "arm:\n  com: 0.25\n  list: [0, 0.25, 1]\n  mm: !millimeters 250\n"
    )
    robot = pkdyn.load(_file(tmp_path, x, SUBSET))
    assert robot.model.inertias[1].lever[0] == pytest.approx(value, rel=1e-12)


def test_xacro_messages_are_warnings(tmp_path):
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        pkdyn.load(_file(tmp_path, "${xacro.warning('look') or 0.25}"))
    assert any("xacro warning: look" in str(w.message) for w in seen)


@pytest.mark.parametrize("target", ["/dev/zero", "fifo", "big"])
def test_load_yaml_reads_only_bounded_regular_files(tmp_path, target):
    import os

    if target == "fifo":
        os.mkfifo(tmp_path / "fifo")
        name = str(tmp_path / "fifo")
    elif target == "big":
        (tmp_path / "big.yaml").write_text("a: " + "1" * (5 * 2**20) + "\n")
        name = "big.yaml"
    else:
        name = target
    path = _file(tmp_path, f"${{xacro.load_yaml('{name}').a}}")
    with pytest.raises(DescriptionError) as err:
        pkdyn.load(path)
    assert "load_yaml" in str(err.value) and "\n" not in str(err.value)


def test_a_yaml_alias_bomb_is_refused(tmp_path):
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * 10) + "]" for k in range(1, 9)]
    (tmp_path / "bomb.yaml").write_text("\n".join(lines) + "\n")
    path = _file(tmp_path, "${len(str(xacro.load_yaml('bomb.yaml')))}")
    with pytest.raises(DescriptionError, match="not allowed"):
        pkdyn.load(path)


def test_a_macro_that_doubles_without_end_is_bounded(tmp_path, monkeypatch):
    from pkdyn.model.formats import xacro_files

    monkeypatch.setattr(xacro_files, "MAX_EVALUATIONS", 20_000)  # (the default: 500,000)
    levels = "".join(
        f'<xacro:macro name="m{k}"><xacro:m{k + 1}/><xacro:m{k + 1}/></xacro:macro>\n'
        for k in range(40)
    )
    extra = levels + '<xacro:macro name="m40"><link name="${1}"/></xacro:macro>\n<xacro:m0/>\n'
    with pytest.raises(DescriptionError, match="xacro expansion: .* more than 20,000"):
        pkdyn.load(_file(tmp_path, "0.25", extra))


def test_the_public_xacro_files_still_load():
    robot = pkdyn.load(PUBLIC / "drake_strandbeest" / "StrandbeestConstraints.urdf.xacro")
    assert len(robot.closures) == 36
