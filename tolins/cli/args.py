"""Command-line options generated from a config dataclass (one option per field).

Each field becomes ``--field-name`` with the field's default, its type (``int``,
``float``, ``str``, ``bool`` as ``--x/--no-x``, ``Literal[...]`` as choices, ``X | None``)
and, as help, the field's documentation: the docstring written under the field, or else
its entry in the class docstring's ``Attributes:`` section. A field named ``seed`` takes
:func:`tolins.cli.checks.seed` (0 … 2**32 - 1), like every seed option of ``tolins``.

What a field's type cannot say (the names a registry allows, a count's lower bound, a
default the command works out) a command adds as an :class:`Option` of that field::

    @dataclass(frozen=True)
    class TrainConfig:
        epochs: int = 40
        \"\"\"Passes over the data.\"\"\"

    add_config_arguments(parser, TrainConfig, {"epochs": Option(type=positive_int)})
    config = config_from_args(TrainConfig, parser.parse_args())
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import inspect
import itertools
import re
import textwrap
import types
import typing
from collections.abc import Callable, Collection, Mapping
from typing import Any, TypeVar

from tolins.cli.checks import seed

Config = TypeVar("Config")

#: The default of :attr:`Option.default`: the option's default is the field's.
_FIELDS_OWN: Any = object()


@dataclasses.dataclass(frozen=True)
class Option:
    """What a command says about one field's option beyond the field itself."""

    type: Callable[[str], Any] | None = None
    """Parses and checks the option's text, in place of the type the annotation gives."""
    choices: Collection[Any] | None = None
    """The values allowed, where the field is a plain ``str`` (a registry's names)."""
    action: type[argparse.Action] | None = None
    """How the option stores what it is given (e.g. :class:`tolins.cli.checks.JoinedList`)."""
    default: Any = _FIELDS_OWN
    """The option's default where the command's differs from the field's."""
    help: str | None = None
    """The whole help text, in place of the field's documentation and its default."""


def field_docs(cls: type) -> dict[str, str]:
    """The documentation of each field of the dataclass ``cls``: the docstring under the
    field (read from its source), else its entry under ``Attributes:`` in the class
    docstring. Whitespace is joined to single spaces; fields without either are left out."""
    docs = _attribute_docs(cls.__doc__ or "")
    tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    body = tree.body[0].body  # type: ignore[attr-defined]
    for node, after in itertools.pairwise(body):
        if (
            isinstance(node, ast.AnnAssign)
            and isinstance(node.target, ast.Name)
            and isinstance(after, ast.Expr)
            and isinstance(after.value, ast.Constant)
            and isinstance(after.value.value, str)
        ):
            docs[node.target.id] = " ".join(after.value.value.split())
    names = {field.name for field in dataclasses.fields(cls)}
    return {name: text for name, text in docs.items() if name in names}


def add_config_arguments(
    parser: argparse.ArgumentParser,
    cls: type,
    options: Mapping[str, Option] | None = None,
    *,
    skip: Collection[str] = (),
) -> None:
    """Add one ``--option`` per field of the dataclass ``cls``, but those named in ``skip``
    (they keep the field's default); ``options`` adds what the field cannot say."""
    options = options or {}
    unknown = (set(options) | set(skip)) - {field.name for field in dataclasses.fields(cls)}
    if unknown:
        raise ValueError(f"{cls.__name__} has no fields {sorted(unknown)}")
    docs = field_docs(cls)
    hints = typing.get_type_hints(cls)
    for field in dataclasses.fields(cls):
        if field.name in skip:
            continue
        if field.default is dataclasses.MISSING:
            raise ValueError(f"{cls.__name__}.{field.name} needs a default to become an option")
        option = options.get(field.name, Option())
        kwargs = _parsing(cls, field.name, hints[field.name], option)
        default = field.default if option.default is _FIELDS_OWN else option.default
        kwargs.update(default=default, dest=field.name)
        kwargs["help"] = _help(docs.get(field.name, ""), default, option)
        parser.add_argument("--" + field.name.replace("_", "-"), **kwargs)


def config_from_args(cls: type[Config], args: argparse.Namespace, **values: Any) -> Config:
    """An instance of ``cls`` from parsed options: each field the parser has an option for,
    unless ``values`` gives it (a value the command works out); the rest keep their
    defaults. ``ValueError`` from the config's checks stays."""
    names = [field.name for field in dataclasses.fields(cls)]  # type: ignore[arg-type]
    given = {name: getattr(args, name) for name in names if hasattr(args, name)}
    return cls(**{**given, **values})


def _parsing(cls: type, name: str, hint: Any, option: Option) -> dict[str, Any]:
    """The ``add_argument`` arguments that parse the field ``name`` of type ``hint``."""
    kind, optional = _unwrap_optional(hint)
    kwargs: dict[str, Any] = {}
    if option.action is not None:
        kwargs["action"] = option.action
    elif kind is bool:
        kwargs["action"] = argparse.BooleanOptionalAction
    elif typing.get_origin(kind) is typing.Literal:
        choices = typing.get_args(kind)
        kwargs.update(choices=choices, type=type(choices[0]))
    elif name == "seed" and kind is int and not optional:
        kwargs["type"] = seed
    elif kind in (int, float, str):
        kwargs["type"] = _none_or(kind) if optional else kind
    elif option.type is None:
        raise ValueError(f"{cls.__name__}.{name}: type {kind!r} has no option form")
    if option.type is not None:
        kwargs["type"] = option.type
    if option.choices is not None:
        kwargs["choices"] = list(option.choices)
    return kwargs


def _help(doc: str, default: Any, option: Option) -> str:
    """The help text: the field's documentation as plain text, and its default."""
    text = option.help if option.help is not None else f"{plain(doc)} (default: {default})"
    return text.strip().replace("%", "%%")  # argparse %-formats help strings


def plain(doc: str) -> str:
    """Documentation as the terminal shows it: ````x```` and ``:role:`x``` as ``x``
    (a dotted name as its last part where it starts with ``~`` or ``.``)."""
    doc = re.sub(r":\w+:`([^`]+)`", _role, doc)
    return re.sub(r"``([^`]+)``", r"\1", doc)


def _role(match: re.Match[str]) -> str:
    target = match.group(1)
    return target.rpartition(".")[2] if target.startswith(("~", ".")) else target


def _attribute_docs(docstring: str) -> dict[str, str]:
    """The entries of the ``Attributes:`` section of a Google-style docstring, by name."""
    lines = inspect.cleandoc(docstring).splitlines()
    if "Attributes:" not in lines:
        return {}
    body = lines[lines.index("Attributes:") + 1 :]
    indent = len(body[0]) - len(body[0].lstrip()) if body else 0
    docs: dict[str, str] = {}
    name = ""
    for line in body:
        depth = len(line) - len(line.lstrip())
        if not line.strip() or depth < indent or indent == 0:
            break  # the section ends at a blank line or a line less indented
        if depth == indent:
            name, _, text = line.strip().partition(":")
            docs[name] = text.strip()
        else:
            docs[name] += " " + line.strip()
    return docs


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
