"""Give rows of a shipped reference more training seeds, from a run of just those rows.

A claim that a reference leaves inconclusive names the training seeds that would decide it
(``seeds_to_decide``). This script takes a run of the rows the claim needs on the
reference's profile, with that many seeds (e.g. ``tolins bench --profile paper --rows
P2.1,P2.2 --seeds 6 --no-study --no-robustness --no-robot --out DIR``), and writes into the
reference:

- those rows' entries from the run, every seed of them (one machine's trainings; the run's
  first seeds repeat the reference's, on this machine's CPU, and ``tolins compare`` of the
  two tells whether they are consistent);
- every claim recomputed from the rows (:func:`~tolins.bench.table.claims.check_claims`),
  into ``results.json`` and ``run.json``;
- in ``run.json``, under ``extended_rows``: which rows come from which run (its date,
  machine, versions, seeds and stage times);
- in ``curves.json``: the run's learning curves of those rows' trainings.

Usage (from the repository root)::

    python benchmarks/extend_reference.py DIR --reference paper --rows P2.1,P2.2
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from tolins.atomic import atomic_json
from tolins.bench.pipeline.profiles import PROFILES
from tolins.bench.reference import reference_path
from tolins.bench.table.claims import check_claims
from tolins.bench.table.rows import select_rows


def extend(reference: Path, run: Path, row_ids: list[str]) -> dict[str, str]:
    """Write ``run``'s rows ``row_ids`` into the reference folder ``reference``; the claims'
    verdicts after."""
    results = _read(reference / "results.json")
    record = _read(reference / "run.json")
    new_results, new_record = _read(run / "results.json"), _read(run / "run.json")
    if new_record["profile"] != record["profile"]:
        raise SystemExit(f"{run}: not a run of the reference's profile {record['profile']}")
    for row_id in row_ids:
        results["rows"][row_id] = new_results["rows"][row_id]
    profile = PROFILES[record["profile"]["name"]]
    checks = check_claims(
        results["rows"], budgets=(profile.deep_rl_env_steps, profile.rs_gail_env_steps)
    )
    results["claims"] = record["claims"] = {c.claim.name: c.to_json() for c in checks}
    trainings = {t.name for row in select_rows(",".join(row_ids)) for t in row.trainings}
    stages = {
        name: wall
        for name, wall in new_record["stage_wall_s"].items()
        if name.rsplit("-seed", 1)[0] in trainings or name.split("-seed")[0][5:] in row_ids
    }
    extended = record.setdefault("extended_rows", {})
    for row_id in row_ids:
        extended[row_id] = {
            key: new_record.get(key) for key in ("date", "seeds", "machine", "versions", "config")
        } | {"stage_wall_s": stages}
    curves = _read(reference / "curves.json")
    curves |= {
        name: curve
        for name, curve in _read(run / "curves.json").items()
        if name.rsplit("-seed", 1)[0] in trainings
    }
    atomic_json(reference / "results.json", results)
    atomic_json(reference / "run.json", record)
    atomic_json(reference / "curves.json", curves)
    return {c.claim.name: c.verdict for c in checks}


def _read(path: Path) -> dict[str, Any]:
    return json.loads(path.read_text())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run", type=Path, help="the run's folder (its results.json, run.json)")
    parser.add_argument("--reference", default="paper", help="the reference's name")
    parser.add_argument("--rows", required=True, help="comma-separated row ids")
    args = parser.parse_args()
    folder = reference_path(args.reference).parent
    for claim, verdict in extend(folder, args.run, args.rows.split(",")).items():
        print(f"{claim}: {verdict}")


if __name__ == "__main__":
    main()
