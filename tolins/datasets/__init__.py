"""Demonstrations as standard datasets: tolins episodes written as, and read from, Minari
datasets (``pip install "tolins[data]"``; docs/datasets.md).

Minari itself is imported on first use, so the rest of tolins works without it.
"""

import os

# HDF5's own file locks refused a dataset file opened while the bench's stages ran side by
# side in one process ("unable to lock file", errno 11). Each dataset is claimed by a lock
# of its own while it is written (tolins.datasets.target), so HDF5's are switched off
# unless the user chose otherwise; the library reads this when it opens a file.
os.environ.setdefault("HDF5_USE_FILE_LOCKING", "FALSE")

from tolins.datasets.envspec import dataset_env_spec, make_env
from tolins.datasets.reader import load_demonstrations, open_dataset, to_rollout
from tolins.datasets.sources import RECIPES, RandomPolicy, Source, make_source
from tolins.datasets.writer import STEP_INFO, UNITS, episode_seeds, write_dataset

__all__ = [
    "RECIPES",
    "STEP_INFO",
    "UNITS",
    "RandomPolicy",
    "Source",
    "dataset_env_spec",
    "episode_seeds",
    "load_demonstrations",
    "make_env",
    "make_source",
    "open_dataset",
    "to_rollout",
    "write_dataset",
]
