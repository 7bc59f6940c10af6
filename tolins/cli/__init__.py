"""The ``tolins`` command: wires arguments to library functions.

One module per command or command group, each adding its parser with ``add_parser`` and
running with the function it sets as ``run``: :mod:`.demo`, :mod:`.record` (``record``
and ``replay``), :mod:`.embed`, :mod:`.infer_study`, :mod:`.train`, :mod:`.bench`,
:mod:`.evaluate`, :mod:`.compare`, :mod:`.dataset` and :mod:`.export`. Where a config
dataclass exists, a command's options are generated from its fields (:mod:`.args`); every
option is checked before any work starts (:mod:`.checks`). The command modules import
the library on use, so the parser builds without torch.
"""

from __future__ import annotations

import argparse
import sys

from tolins.cli import checks


def build_parser() -> argparse.ArgumentParser:
    """The parser of every ``tolins`` command."""
    import tolins
    from tolins.cli import (
        bench,
        compare,
        dataset,
        demo,
        embed,
        evaluate,
        export,
        infer_study,
        record,
        train,
    )

    parser = checks.Parser(prog="tolins", description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--version",
        action="version",
        version=f"tolins {tolins.__version__}",
        help="print the installed version and exit",
    )
    commands = parser.add_subparsers(dest="command", required=True)
    listed = (demo, record, embed, infer_study, train, bench, evaluate, compare, dataset, export)
    for command in listed:  # in the order ``tolins --help`` lists them
        command.add_parser(commands)
    return parser


def _prog(args: argparse.Namespace) -> str:
    """``tolins COMMAND [ACTION]``: how the command that runs names itself in errors."""
    words = [args.command, getattr(args, "action", None), getattr(args, "method", None)]
    return " ".join(["tolins", *(word for word in words if word)])


def main(argv: list[str] | None = None) -> int:
    """Run the ``tolins`` command line ``argv`` (default: ``sys.argv[1:]``); the exit status."""
    try:
        args = build_parser().parse_args(argv)
    except checks.UsageError as error:
        return checks.fail(error.prog, error)
    try:
        return args.run(args)
    except checks.OptionError as error:
        return checks.fail(_prog(args), error)
    except KeyboardInterrupt:  # finished stages, checkpoints and written files stay
        print(f"{_prog(args)}: interrupted", file=sys.stderr)
        return 130
    except RuntimeError as error:
        from tolins.learning.agents.external import PolicyError

        if not isinstance(error, PolicyError):
            raise
        print(error.details, end="", file=sys.stderr)  # the user's policy's own traceback
        print(f"{_prog(args)}: {error} (its traceback above)", file=sys.stderr)
        return 1
