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
    """The workpiece of ``--env`` or ``--socket`` (``ValueError``, ``OSError`` for a bad one)."""
    from tolins.geometry.spec_json import spec_from_json

    if args.env is not None:
        return tasks.task_of(args.env).socket
    if args.socket.lstrip().startswith("{"):
        return spec_from_json(args.socket)
    if Path(args.socket).is_file():
        return spec_from_json(Path(args.socket).read_text(encoding="utf-8"))
    raise ValueError(
        f"--socket {args.socket}: no such file, nor a JSON object; allowed: a JSON "
        'object of a spec\'s fields (e.g. {"rows": 2, "cols": 2}) or a file holding one'
    )


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
