"""The command line under bad input: every registered command, every option, every bad-input
class of the option's kind (``contract.kinds``), a few values each drawn by hypothesis.

The contract (``contract.contract.check_cli``): exit 0, or exit 1 or 2 with exactly one
``pkdyn: error:`` line naming the culprit, no traceback, within the time limit; input files
never changed; a refused run leaves no file behind, an accepted one no temporary.
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings

from contract.contract import check_cli, file_changes, run_cli, same_result, snapshot, temporaries
from contract.drive import PENDING_SETTINGS, parser_of, resolve, scratch, without
from contract.registry import CLI, pending

settings.load_profile("contract")


def _cases() -> list:
    out = []
    for entry in CLI:
        for option, arg in entry.options.items():
            for cls in arg.kind.cli():
                if cls in arg.skip:
                    continue
                tid = f"{entry.name.replace(' ', '.')}|{option}|{cls}"
                marks = [pytest.mark.slow] if entry.slow else []
                reason = pending(tid)
                if reason:
                    marks.append(pytest.mark.xfail(strict=True, reason=reason))
                out.append(pytest.param(entry, option, cls, id=tid, marks=marks))
    return out


def argv_for(entry, option: str, tokens: list[str] | None, s) -> list[str]:
    """The entry's baseline with ``option`` given ``tokens`` (``None``: left out)."""
    parser = parser_of(entry.words)
    base = [resolve(t, s) for t in entry.baseline]
    action = next(a for a in parser._actions if option in a.option_strings or a.dest == option)
    if not action.option_strings:  # a positional: the first token of the baseline
        return [*entry.words, *(tokens or []), *base[1:]]
    argv = without(base, parser, option)
    context = entry.options[option].context  # what makes the option matter
    for tok in context:
        if tok.startswith("--"):
            argv = without(argv, parser, tok)
        elif tok.startswith("ROBOT="):  # another robot than the baseline's
            argv[0] = tok.partition("=")[2]
    argv += [resolve(t, s) for t in context if not t.startswith("ROBOT=")]
    if tokens is not None:
        argv += [option, *tokens]
    return [*entry.words, *argv]


@pytest.mark.parametrize("entry, option, cls", _cases())
def test_contract_cli(entry, option, cls):
    arg = entry.options[option]
    names = arg.names or (option, option.lstrip("-"), option.lstrip("-").replace("-", "_"))

    @PENDING_SETTINGS(pending(f"{entry.name.replace(' ', '.')}|{option}|{cls}"))
    @given(case=arg.kind.cli()[cls])
    def run(case):
        with scratch(entry.inputs, entry.robot) as s:
            tokens = case.make(s)
            argv = argv_for(entry, option, tokens, s)
            shown = tuple(t for t in (tokens or []) if t.strip())
            before = snapshot(s.dir)
            res = check_cli(
                argv,
                names + shown + tuple(p.rsplit("/", 1)[-1] for p in shown),
                case.refuse,
                case.usage_ok,
                entry.timeout,
            )
            changed, created, removed = file_changes(before, snapshot(s.dir))
            assert not changed and not removed, (
                f"input files changed {changed} or removed {removed}"
            )
            if res.code != 0:
                assert not created, f"a refused run left files: {created}"
            else:
                assert not temporaries(created), f"temporaries left: {temporaries(created)}"
                if case.same:  # the same command on the plain file
                    plain = [str(s.inputs[arg.kind.key])]
                    ref = run_cli(argv_for(entry, option, plain, s), entry.timeout).out
                    ref = ref.replace(str(s.dir), "<dir>")
                    got = res.out.replace(f"{s.dir}/variant/", f"{s.dir}/")
                    got = got.replace(str(s.dir), "<dir>")
                    assert same_result(got, ref), (
                        f"{case.label}: a different result\n{got[:600]}\n"
                        f"--- baseline ---\n{ref[:600]}"
                    )

    run()
