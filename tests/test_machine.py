"""The machine a bench records (:mod:`tolins.bench.machine`), and where a run records it:
``run.json`` and ``results.md``, with the stage-minutes."""

from __future__ import annotations

import json
import os

import pytest

from tolins.bench import machine
from tolins.bench.pipeline.config import BenchConfig
from tolins.bench.pipeline.runner import run_bench

# the first processor of /proc/cpuinfo on the 2-core VMs the figures were measured on
GENOA = """processor\t: 0
vendor_id\t: AuthenticAMD
cpu family\t: 25
model\t\t: 17
model name\t: AMD EPYC
stepping\t: 1

processor\t: 1
vendor_id\t: AuthenticAMD
cpu family\t: 25
model\t\t: 99
model name\t: not the first
"""


def test_cpuinfo_gives_the_first_processors_fields():
    fields = machine.parse_cpuinfo(GENOA)
    assert fields["model name"] == "AMD EPYC"
    assert (fields["vendor_id"], fields["cpu family"], fields["model"]) == (
        "AuthenticAMD",
        "25",
        "17",
    )


@pytest.mark.parametrize(
    ("vendor", "family", "model", "name"),
    [
        ("AuthenticAMD", 25, 0x01, "Zen 3"),  # Milan
        ("AuthenticAMD", 25, 0x11, "Zen 4"),  # Genoa: this VM
        ("AuthenticAMD", 25, 0xA0, "Zen 4"),  # Bergamo
        ("AuthenticAMD", 25, 0x21, "Zen 3"),  # Vermeer
        ("AuthenticAMD", 26, 0x02, "Zen 5"),  # Turin
        ("AuthenticAMD", 25, 0x30, None),  # no part known there
        ("AuthenticAMD", 24, 0x00, None),  # no AMD Zen family (24 is Hygon's)
        ("GenuineIntel", 6, 0x8F, None),  # Intel: its model name says more
        (None, None, None, None),
    ],
)
def test_a_microarchitecture_is_named_only_where_its_numbers_are_known(vendor, family, model, name):
    assert machine.microarchitecture(vendor, family, model) == name


def test_a_cpu_is_described_by_its_name_then_what_is_known_of_it():
    assert machine.describe("AMD EPYC", "Zen 4", 25, 17) == "AMD EPYC (Zen 4; family 25, model 17)"
    assert machine.describe("AMD EPYC", None, 25, 48) == "AMD EPYC (family 25, model 48)"
    assert machine.describe("x86_64", None, None, None) == "x86_64"


def test_this_machine_is_recorded_with_its_cores_and_torchs_simd_level():
    import torch

    facts = machine.machine()
    assert facts["cores"] == os.cpu_count() and 1 <= facts["usable_cores"] <= facts["cores"]
    assert facts["torch_simd"] == torch.backends.cpu.get_cpu_capability()
    cpu = facts["cpu"]
    assert cpu["description"].startswith(cpu["model_name"]) and cpu["model_name"]
    line = machine.describe_machine(facts)
    assert line.startswith(cpu["description"]) and f"torch SIMD {facts['torch_simd']}" in line
    fewer = {**facts, "cores": 8, "usable_cores": 2}
    assert ", 8 cores (2 usable), " in machine.describe_machine(fewer)


def test_run_json_and_results_md_name_the_machine_and_the_stage_minutes(tmp_path):
    config = BenchConfig(
        profile="tiny",
        backend="kinematic",
        rows="C2.1",
        out=str(tmp_path),
        study=False,
        robustness=False,
    )
    run = run_bench(config, progress=False, log=lambda _: None)
    record = json.loads((tmp_path / "run.json").read_text())
    assert record["machine"] == json.loads(json.dumps(machine.machine()))
    assert record["stage_minutes"] == pytest.approx(sum(run.stage_wall_s.values()) / 60)
    assert record["stage_minutes"] > 0
    markdown = (tmp_path / "results.md").read_text()
    assert f"min on {machine.describe_machine(record['machine'])} (" in markdown
    assert f"; {record['stage_minutes']:.1f} stage-minutes: " in markdown
