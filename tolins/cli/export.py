"""``tolins export``: a workpiece as a mesh (STL, GLB) or its MJCF model (``.xml``)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from tolins.cli import checks
from tolins.envs import tasks

if TYPE_CHECKING:
    from tolins.geometry.specs import SocketSpec


def add_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``export`` to the ``tolins`` parser."""
    export = commands.add_parser(
        "export", help="write a workpiece as a mesh (STL, GLB) or its MJCF model (.xml)"
    )
    which = export.add_mutually_exclusive_group(required=True)
    which.add_argument(
        "--env",
        type=checks.env_ids(
            tasks.env_ids(generic=False),
            reasons=dict.fromkeys(
                tasks.GENERIC_IDS.values(), "its workpiece is given with --socket"
            ),
        ),
        help="a preset env id: its nominal workpiece, e.g. tolins/Circle2x2-v1",
    )
    which.add_argument(
        "--socket",
        metavar="JSON",
        help='a spec\'s fields as a JSON object, defects included (e.g. {"rows": 2, "cols": '
        '1, "pin_offsets": [[0.1, 0], [0, -0.05]]}; a recording\'s spec), or a file holding one',
    )
    export.add_argument(
        "--out",
        required=True,
        help="PART.stl (mm), PART.glb (glTF: metres, y up) or MODEL.xml (the MJCF model); "
        "replaced if present",
    )
    export.add_argument(
        "--part",
        default="all",
        help="all (the workpiece 2 mm over the board), board or workpiece; meshes only",
    )
    export.set_defaults(run=run)


def _spec(args: argparse.Namespace) -> SocketSpec:
    """The workpiece of ``--env`` or ``--socket`` (``ValueError``, ``OSError`` for a bad
    one): ``--socket`` is inline JSON when it starts with ``{`` or ``[``, else a file."""
    from tolins.geometry.spec_json import ALLOWED, spec_from_json
    from tolins.json_input import shorten

    if args.env is not None:
        return tasks.task_of(args.env).socket
    text = args.socket
    if text.lstrip().startswith(("{", "[")):
        return spec_from_json(text, f"--socket {shorten(text)} (inline JSON)")
    path = Path(text)
    if not _is_file(path):
        raise ValueError(
            f"--socket {shorten(text)}: no such file, nor inline JSON (starting with {{ or [); "
            f"allowed: {ALLOWED}, or a file holding one"
        )
    return spec_from_json(path.read_bytes(), f"--socket {path} (a file)")


def _is_file(path: Path) -> bool:
    """Whether ``path`` is a file (``False`` for a name the system refuses, e.g. too long)."""
    try:
        return path.is_file()
    except OSError:
        return False


def run(args: argparse.Namespace) -> int:
    """Write the mesh or model to ``--out``, replacing it atomically."""
    from tolins.mjcf.export import EXPORT_SUFFIXES

    out = checks.output_file("--out", args.out, suffixes=EXPORT_SUFFIXES)
    from tolins import atomic
    from tolins.mjcf.export import export_bytes

    try:
        data = export_bytes(_spec(args), out.suffix, args.part)
    except (ValueError, OSError) as error:  # UnicodeDecodeError is a ValueError
        return checks.fail("tolins export", error)
    atomic.atomic_write(out, lambda file: file.write(data))
    print(f"wrote {out} ({len(data) / 1e3:.0f} kB)")
    return 0
