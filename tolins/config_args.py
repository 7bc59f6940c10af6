"""Command-line options generated from a config dataclass (one option per field).

Each field becomes ``--field-name`` with the field's default, its type (``int``,
``float``, ``str``, ``bool`` as ``--x/--no-x``, ``Literal[...]`` as choices, ``X | None``)
and, as help, the docstring written under the field. A field named ``seed`` takes
:func:`tolins.cli_checks.seed` (0 … 2**32 - 1), like every seed option of ``tolins``::

    @dataclass(frozen=True)
    class TrainConfig:
        epochs: int = 40
        \"\"\"Passes over the data.\"\"\"

    add_config_arguments(parser, TrainConfig)
    config = config_from_args(TrainConfig, parser.parse_args())
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import inspect
import itertools
import textwrap
import types
import typing
from typing import Any, TypeVar

from tolins.cli_checks import seed

Config = TypeVar("Config")


def field_docs(cls: type) -> dict[str, str]:
    """The docstring under each field of the dataclass ``cls`` (read from its source)."""
    tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    body = tree.body[0].body  # type: ignore[attr-defined]
    docs = {}
    for node, after in itertools.pairwise(body):
        if (
            isinstance(node, ast.AnnAssign)
            and isinstance(node.target, ast.Name)
            and isinstance(after, ast.Expr)
            and isinstance(after.value, ast.Constant)
            and isinstance(after.value.value, str)
        ):
            docs[node.target.id] = " ".join(after.value.value.split())
    return docs


def add_config_arguments(parser: argparse.ArgumentParser, cls: type) -> None:
    """Add one ``--option`` per field of the dataclass ``cls``."""
    docs = field_docs(cls)
    hints = typing.get_type_hints(cls)
    for field in dataclasses.fields(cls):
        if field.default is dataclasses.MISSING:
            raise ValueError(f"{cls.__name__}.{field.name} needs a default to become an option")
        option = "--" + field.name.replace("_", "-")
        help_text = f"{docs.get(field.name, '')} (default: {field.default})".strip()
        help_text = help_text.replace("%", "%%")  # argparse %-formats help strings
        kind, optional = _unwrap_optional(hints[field.name])
        kwargs: dict[str, Any] = {"default": field.default, "help": help_text, "dest": field.name}
        if kind is bool:
            kwargs["action"] = argparse.BooleanOptionalAction
        elif typing.get_origin(kind) is typing.Literal:
            choices = typing.get_args(kind)
            kwargs.update(choices=choices, type=type(choices[0]))
        elif field.name == "seed" and kind is int and not optional:
            kwargs["type"] = seed
        elif kind in (int, float, str):
            kwargs["type"] = _none_or(kind) if optional else kind
        else:
            raise ValueError(f"{cls.__name__}.{field.name}: type {kind!r} has no option form")
        parser.add_argument(option, **kwargs)


def config_from_args(cls: type[Config], args: argparse.Namespace) -> Config:
    """An instance of ``cls`` from parsed options (``ValueError`` from its checks stays)."""
    names = [field.name for field in dataclasses.fields(cls)]  # type: ignore[arg-type]
    return cls(**{name: getattr(args, name) for name in names})


def _unwrap_optional(hint: Any) -> tuple[Any, bool]:
    if typing.get_origin(hint) in (typing.Union, types.UnionType):
        rest = [arg for arg in typing.get_args(hint) if arg is not type(None)]
        if len(rest) == 1:
            return rest[0], True
    return hint, False


def _none_or(kind: type) -> Any:
    def parse(text: str) -> Any:
        return None if text.lower() == "none" else kind(text)

    parse.__name__ = kind.__name__
    return parse
