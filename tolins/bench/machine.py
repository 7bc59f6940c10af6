"""The machine a bench ran on: its CPU, how many cores it has and may use, and the SIMD
level torch picks its kernels by, so that a wall time can be read (and scaled) with it.

The CPU is described by ``/proc/cpuinfo`` (``model name``, plus the raw ``cpu family`` and
``model`` numbers, since a VM often says just ``AMD EPYC``), with a microarchitecture name
only where those numbers identify one for certain (:data:`MICROARCHITECTURES`), and
:func:`platform.processor` where there is no ``/proc/cpuinfo``.
"""

from __future__ import annotations

import functools
import os
import platform
from pathlib import Path
from typing import Any

CPUINFO = Path("/proc/cpuinfo")

#: (vendor id, cpu family, first model, last model) -> microarchitecture: AMD's Zen
#: generations by the family and model numbers AMD published for them.
MICROARCHITECTURES: dict[tuple[str, int, int, int], str] = {
    ("AuthenticAMD", 23, 0x30, 0x3F): "Zen 2",  # Rome
    ("AuthenticAMD", 23, 0x70, 0x7F): "Zen 2",  # Matisse
    ("AuthenticAMD", 25, 0x00, 0x0F): "Zen 3",  # Milan
    ("AuthenticAMD", 25, 0x10, 0x1F): "Zen 4",  # Genoa
    ("AuthenticAMD", 25, 0x20, 0x2F): "Zen 3",  # Vermeer
    ("AuthenticAMD", 25, 0x40, 0x5F): "Zen 3",  # Rembrandt, Cezanne
    ("AuthenticAMD", 25, 0x60, 0x7F): "Zen 4",  # Raphael, Phoenix
    ("AuthenticAMD", 25, 0xA0, 0xAF): "Zen 4",  # Bergamo, Siena
    ("AuthenticAMD", 26, 0x00, 0xFF): "Zen 5",
}


def microarchitecture(vendor: str | None, family: int | None, model: int | None) -> str | None:
    """The microarchitecture of a CPU by its vendor id and family and model numbers, where
    :data:`MICROARCHITECTURES` knows it; else ``None``."""
    for (known, fam, first, last), name in MICROARCHITECTURES.items():
        if vendor == known and family == fam and model is not None and first <= model <= last:
            return name
    return None


def parse_cpuinfo(text: str) -> dict[str, str]:
    """The fields of the first processor in ``/proc/cpuinfo``'s ``text``."""
    fields: dict[str, str] = {}
    for line in text.splitlines():
        if not line.strip():
            if fields:
                break
            continue
        key, _, value = line.partition(":")
        fields.setdefault(key.strip(), value.strip())
    return fields


@functools.cache
def cpu() -> dict[str, Any]:
    """This machine's CPU: ``model_name``, ``vendor``, ``family``, ``model`` (numbers, or
    ``None`` where not known), ``microarchitecture`` (or ``None``) and ``description``
    (all of them in a line, e.g. ``AMD EPYC (Zen 4; family 25, model 17)``)."""
    try:
        fields = parse_cpuinfo(CPUINFO.read_text())
    except OSError:
        fields = {}
    name = fields.get("model name") or platform.processor() or platform.machine() or "unknown"
    vendor = fields.get("vendor_id")
    family, model = _number(fields.get("cpu family")), _number(fields.get("model"))
    arch = microarchitecture(vendor, family, model)
    return {
        "model_name": name,
        "vendor": vendor,
        "family": family,
        "model": model,
        "microarchitecture": arch,
        "description": describe(name, arch, family, model),
    }


def describe(name: str, arch: str | None, family: int | None, model: int | None) -> str:
    """A CPU in a line: its model name, then its microarchitecture and numbers if known."""
    numbers = [] if family is None else [f"family {family}"]
    numbers += [] if model is None else [f"model {model}"]
    inside = "; ".join(part for part in (arch, ", ".join(numbers)) if part)
    return f"{name} ({inside})" if inside else name


def machine() -> dict[str, Any]:
    """What a bench's figures depend on of this machine: ``cpu`` (:func:`cpu`), ``cores``
    (``os.cpu_count()``), ``usable_cores`` (those this process may run on), ``torch_simd``
    (``torch.backends.cpu.get_cpu_capability()``: ``AVX512``, ``AVX2``, ``DEFAULT``, ...)
    and ``platform``."""
    import torch

    return {
        "cpu": cpu(),
        "cores": os.cpu_count(),
        "usable_cores": len(os.sched_getaffinity(0))
        if hasattr(os, "sched_getaffinity")
        else os.cpu_count(),
        "torch_simd": torch.backends.cpu.get_cpu_capability(),
        "platform": platform.platform(),
    }


def describe_machine(facts: dict[str, Any]) -> str:
    """:func:`machine`'s ``facts`` in a line, e.g. ``AMD EPYC (Zen 4; family 25, model
    17), 2 cores (2 usable), torch SIMD AVX512``."""
    cores = f"{facts['cores']} cores"
    if facts.get("usable_cores") not in (None, facts["cores"]):
        cores += f" ({facts['usable_cores']} usable)"
    return f"{facts['cpu']['description']}, {cores}, torch SIMD {facts['torch_simd']}"


def _number(text: str | None) -> int | None:
    return int(text) if text is not None and text.isdigit() else None
