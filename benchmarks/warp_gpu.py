"""Speed and memory of the MuJoCo Warp backend for 1k, 4k and 16k worlds (a GPU run).

Usage::

    python benchmarks/warp_gpu.py --device cuda:0 --json warp_gpu.json   # the GPU run
    python benchmarks/warp_gpu.py --device cpu --worlds 2 4 --steps 1    # its smoke test

For each socket (2*2, 2*8) and world count, one ``WarpBatch`` is stepped in two regimes:

* **contact**: every workpiece 0.25 mm off its holes, pushed down onto the board at
  2.5 mm/s (blocked: the pins press on the board with the 5 N servo limit);
* **free**: every workpiece 2 mm above the board, moved sideways at ±2.5 mm/s (no contact).

One control step (0.25 s, 250 physics steps, 5 force reads) warms up (kernel loading and
graph capture), then ``--steps`` control steps are timed. Reported per row: control steps/s
of the batch, world-steps/s (× worlds), physics steps/s per world summed, contacts per world,
and memory: the device's memory-pool high-water mark on CUDA (bytes Warp allocated), the
process's peak resident set on the CPU device. Nothing is estimated: a row is what ran.
"""

from __future__ import annotations

import argparse
import json
import platform
import resource
import time
from pathlib import Path

import numpy as np

from tolins import CircularSocket

SOCKETS = {"2*2": CircularSocket(2, 2), "2*8": CircularSocket(2, 8)}
SPEED = 2.5


def regime(name: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Start poses ``(n, 4)`` and first velocities ``(n, 4)`` of regime ``name``."""
    if name == "contact":
        return np.tile([0.25, 0.0, 0.0, 0.05], (n, 1)), np.tile([0.0, 0.0, 0.0, -SPEED], (n, 1))
    return np.tile([0.0, 0.0, 0.0, 2.0], (n, 1)), np.tile([SPEED, 0.0, 0.0, 0.0], (n, 1))


def memory_bytes(wp, device) -> int:
    """Warp's memory-pool high-water mark (CUDA) or this process's peak RSS (CPU)."""
    if device.is_cuda:
        return int(wp.get_mempool_used_mem_high(device))
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def measure(socket_name: str, n: int, mode: str, steps: int, device: str) -> dict:
    """One row: ``n`` worlds of ``socket_name`` in regime ``mode``."""
    import warp as wp

    from tolins.physics.warp import WarpBatch

    build = time.perf_counter()
    batch = WarpBatch(SOCKETS[socket_name], n, 0.25, device=device)
    ids = np.arange(n)
    poses, velocities = regime(mode, n)
    batch.reset(ids, poses)
    batch.step(ids, velocities)  # warm-up: kernels loaded, graphs captured
    wp.synchronize_device(batch.device)
    warm = time.perf_counter() - build
    start = time.perf_counter()
    for k in range(steps):
        sign = -1.0 if (mode == "free" and k % 2 == 0) else 1.0
        state = batch.step(ids, velocities * sign)
    wp.synchronize_device(batch.device)
    seconds = time.perf_counter() - start
    contacts = float(batch.d.nacon.numpy()[0]) / n
    faults = sum(e is not None for e in state.errors)
    row = {
        "socket": socket_name,
        "worlds": n,
        "regime": mode,
        "control_steps": steps,
        "seconds": round(seconds, 4),
        "batch_control_steps_per_s": round(steps / seconds, 3),
        "world_control_steps_per_s": round(n * steps / seconds, 1),
        "world_physics_steps_per_s": round(n * steps * batch.substeps / seconds, 0),
        "contacts_per_world": round(contacts, 2),
        "faults": faults,
        "memory_bytes": memory_bytes(wp, batch.device),
        "build_and_warm_s": round(warm, 2),
        "nconmax": batch.nconmax,
        "njmax": batch.njmax,
    }
    batch.close()
    return row


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--device", default="cuda:0")
    parser.add_argument("--worlds", type=int, nargs="+", default=[1024, 4096, 16384])
    parser.add_argument("--sockets", nargs="+", default=list(SOCKETS), choices=list(SOCKETS))
    parser.add_argument("--regimes", nargs="+", default=["contact", "free"])
    parser.add_argument("--steps", type=int, default=4, help="timed control steps per row")
    parser.add_argument("--json", type=Path, help="write the rows here too")
    args = parser.parse_args(argv)
    import warp as wp

    wp.config.log_level = wp.LOG_WARNING  # no banner, no per-module load lines
    wp.init()
    device = (
        wp.get_device(args.device) if args.device in {d.alias for d in wp.get_devices()} else None
    )
    report = {
        "device": args.device,
        "device_name": getattr(device, "name", "unavailable"),
        "host": platform.node(),
        "warp": wp.__version__,
        "rows": [],
    }
    print(json.dumps({k: v for k, v in report.items() if k != "rows"}), flush=True)
    for socket_name in args.sockets:
        for n in args.worlds:
            for mode in args.regimes:
                row = measure(socket_name, n, mode, args.steps, args.device)
                report["rows"].append(row)
                print(json.dumps(row), flush=True)
                if args.json:
                    args.json.write_text(json.dumps(report, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
