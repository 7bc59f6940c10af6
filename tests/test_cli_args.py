"""Options generated from config dataclasses (``tolins.cli.args``): field docstrings and
``Attributes:`` entries as help, what a command adds through ``Option``, and the
``tolins bench`` and ``tolins infer-study`` parsers that come out of it."""

from __future__ import annotations

import argparse
import dataclasses
from dataclasses import dataclass

import pytest

from tolins.bench.pipeline.config import BenchConfig
from tolins.cli import build_parser
from tolins.cli.args import Option, add_config_arguments, config_from_args, field_docs, plain
from tolins.cli.checks import positive_int
from tolins.inference.study import StudyConfig


@dataclass(frozen=True)
class _Example:
    """An example.

    Attributes:
        count: How many, counted
            over two lines.
        name: Which one (``a`` or ``b``).

    Returns nothing.
    """

    count: int = 3
    name: str = "a"
    label: str | None = None
    """A label under its field, which wins."""


def test_docs_come_from_the_attributes_section_and_field_docstrings():
    assert field_docs(_Example) == {
        "count": "How many, counted over two lines.",
        "name": "Which one (``a`` or ``b``).",
        "label": "A label under its field, which wins.",
    }
    assert plain("see :mod:`tolins.bench`, :func:`~a.b.run` and ``x``") == (
        "see tolins.bench, run and x"
    )


def test_an_option_adds_what_the_field_cannot_say():
    parser = argparse.ArgumentParser()
    options = {"count": Option(type=positive_int), "name": Option(choices=("a", "b"))}
    add_config_arguments(parser, _Example, options, skip=("label",))
    assert config_from_args(_Example, parser.parse_args(["--count", "5"])) == _Example(count=5)
    assert config_from_args(_Example, parser.parse_args([]), name="b") == _Example(name="b")
    for bad in (["--count", "0"], ["--name", "c"], ["--label", "x"]):
        with pytest.raises(SystemExit):
            parser.parse_args(bad)
    assert "How many, counted over two lines. (default: 3)" in parser.format_help()
    with pytest.raises(ValueError, match="no fields"):
        add_config_arguments(argparse.ArgumentParser(), _Example, {"nope": Option()})


def _subcommand(name: str) -> argparse.ArgumentParser:
    commands = next(
        action
        for action in build_parser()._actions
        if isinstance(action, argparse._SubParsersAction)
    )
    return commands.choices[name]


@pytest.mark.parametrize(
    ("command", "config"), [("bench", BenchConfig), ("infer-study", StudyConfig)]
)
def test_every_option_of_a_config_command_is_a_field_with_its_doc(command, config):
    parser = _subcommand(command)
    dests = {action.dest for action in parser._actions}
    fields = {field.name for field in dataclasses.fields(config)}
    docs = field_docs(config)
    for action in parser._actions:
        if action.dest in fields and action.dest not in ("rows", "seeds", "out", "methods"):
            assert plain(docs[action.dest]).replace("%", "%%") in action.help, action.dest
    if config is BenchConfig:
        assert fields <= dests  # every field of the bench is an option


def test_the_bench_options_keep_their_names_and_defaults():
    parser = build_parser()
    args = parser.parse_args(["bench"])
    default = config_from_args(BenchConfig, args, out="results/quick")
    assert default == BenchConfig(out="results/quick")
    argv = ["bench", "--profile", "tiny", "--rows", "C1.1", "--rows", "C2.1", "--seeds", "2"]
    argv += ["--no-study", "--no-robustness", "--workers", "3", "--backend", "kinematic"]
    args = parser.parse_args([*argv, "--executor", "ray", "--address", "auto", "--out", "o"])
    assert config_from_args(BenchConfig, args) == BenchConfig(
        profile="tiny",
        rows="C1.1,C2.1",
        backend="kinematic",
        seeds=2,
        out="o",
        study=False,
        robustness=False,
        workers=3,
        executor="ray",
        address="auto",
    )
