"""Read a rerun recording back as plain tables, for the recording tests."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import numpy as np
from rerun.chunk import RrdReader


def read_tables(path: Path) -> dict[str, dict[str, list]]:
    """``{entity#static|temporal: {column: values}}`` of every chunk, temporal rows sorted
    by step."""
    tables: dict[str, dict[str, list]] = defaultdict(lambda: defaultdict(list))
    for chunk in RrdReader(path).stream():
        kind = "static" if chunk.is_static else "temporal"
        for name, values in chunk.to_record_batch().to_pydict().items():
            tables[f"{chunk.entity_path}#{kind}"][name] += values
    for table in tables.values():
        if "step" in table:
            order = np.argsort(table["step"], kind="stable")
            for name in table:
                table[name] = [table[name][i] for i in order]
    return tables
