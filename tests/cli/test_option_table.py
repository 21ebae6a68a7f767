"""Each option of a study's command line is defined once (`jswim.studies.flags.FLAGS`, or a
study's own `Study.flags`), and every view read from that definition agrees with the parsers and
with `StudyOptions`: the fields the options set, the refusals' reasons, a bench suite's keys and
a models file's keys."""

from __future__ import annotations

import argparse
import dataclasses
from collections import Counter

import pytest

from jswim.bench.models_file import MODEL_KEYS
from jswim.bench.suites import SIZE_OPTIONS, part_options
from jswim.cli.options import study_parser
from jswim.studies import StudyOptions, get, names
from jswim.studies.flags import FLAGS
from jswim.studies.specs import IGNORED

FIELDS = {f.name for f in dataclasses.fields(StudyOptions)}


def _subparsers(p: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    return next(a for a in p._actions if isinstance(a, argparse._SubParsersAction)).choices


def parsers() -> dict[str, argparse.ArgumentParser]:
    """Every study's parser, by study name (``swim``: ``jswim swim``)."""
    commands = _subparsers(study_parser())
    nested = _subparsers(commands["study"])
    return {n: commands["swim"] if get(n).command == "swim" else nested[n] for n in names()}


def accepted(parser: argparse.ArgumentParser) -> dict[str, str]:
    """Each flag ``parser`` takes -> its argparse dest."""
    return {s: a.dest for a in parser._actions for s in a.option_strings}


def duplicates(items) -> list:
    return [k for k, n in Counter(items).items() if n > 1]


def own_flags() -> dict[str, list[dict]]:
    """Each study's own flag -> its argparse keywords in each study that takes it."""
    out: dict[str, list[dict]] = {}
    for n in names():
        for flag, kw in get(n).flags:
            out.setdefault(flag, []).append(kw)
    return out


def test_each_option_is_defined_once():
    assert not duplicates([*(s for f in FLAGS for s in f.names), *own_flags()])
    assert not duplicates(
        [*(f.dest for f in FLAGS), *(f.lstrip("-").replace("-", "_") for f in own_flags())]
    )
    # an option several studies take (--separations) is one declaration: the same parsing
    # (the same type object), only the help each study's own
    for flag, kws in own_flags().items():
        bare = [{k: v for k, v in kw.items() if k != "help"} for kw in kws]
        assert all(b.keys() == bare[0].keys() for b in bare), flag
        assert all(b[k] is bare[0][k] or b[k] == bare[0][k] for b in bare for k in b), flag


def test_each_field_is_a_study_option_set_by_one_option():
    own = [f.lstrip("-").replace("-", "_") for f in own_flags()]
    fields = [*(f.field for f in FLAGS if f.field), *own]
    assert not duplicates(fields)
    assert set(fields) <= FIELDS, set(fields) - FIELDS


def test_every_field_a_study_ignores_has_its_reason():
    for n in names():
        assert set(get(n).ignores) <= set(IGNORED), n


def test_each_flag_is_in_the_parsers_under_its_dest():
    for n, parser in parsers().items():
        taken = accepted(parser)
        for f in FLAGS:
            if f.study_only and get(n).command != "study":
                assert f.names[0] not in taken, (n, f.names[0])
                continue
            assert all(taken.get(s) == f.dest for s in f.names), (n, f.names)
        for field, (flag, _) in zip(get(n).own_options, get(n).flags):
            assert taken[flag] == field, (n, flag)


def test_every_suite_key_is_a_flag_of_a_study_parser_under_that_name():
    by_study = {n: accepted(p) for n, p in parsers().items()}
    for key, flag in part_options().items():
        takers = [n for n, taken in by_study.items() if taken.get(flag) == key]
        assert takers, f"suite key {key!r}: no study parser takes {flag} as {key}"
    # the keys users write today (docs/bench.md), kept
    assert part_options()["noise"] == "--noise" and part_options()["swimmer"] == "--swimmer"
    assert set(SIZE_OPTIONS) <= set(part_options())


def test_every_models_file_key_is_a_flag_of_the_study_parser():
    taken = accepted(parsers()["curves"])
    for key, flag in MODEL_KEYS.items():
        assert flag is None or flag in taken, (key, flag)
    for f in FLAGS:
        if f.llm:
            assert f.names[0] in taken and f.field is None


@pytest.mark.parametrize("study", [n for n in names() if get(n).command == "study"])
def test_an_ignored_field_s_flag_is_refused_in_one_line(study, capsys):
    from jswim import cli

    for f in FLAGS:
        if f.field in get(study).ignores:
            value = {"--direction": "-x", "--init": "paper"}.get(f.names[0], "1")
            assert cli.main(["study", study, f"{f.names[0]}={value}", "--dry-run"]) == 2
            err = capsys.readouterr().err.strip()
            assert f"has no use for {f.names[0]} (" in err and "\n" not in err, err
