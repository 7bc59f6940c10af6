"""The dm_control suite of tolins, built from the same task table as the gymnasium ids.

```python
from tolins import dmc

env = dmc.load("circle2x2", "insert", task_kwargs={"random": 0})
timestep = env.reset()
timestep = env.step([0.0, 0.0, 0.0, -2.5])
```
"""

from tolins.dmc.physics import InsertionPhysics, PandaInsertionPhysics
from tolins.dmc.suite import (
    ALL_TASKS,
    CIRCLE,
    DEFECTIVE,
    DELICATE,
    GRADE,
    PAPER,
    POLYGON,
    ROBOT,
    SUITES,
    TASK_KWARGS,
    TASKS_BY_DOMAIN,
    get_tasks,
    load,
    make_environment,
)
from tolins.dmc.task import Insert

__all__ = [
    "ALL_TASKS",
    "CIRCLE",
    "DEFECTIVE",
    "DELICATE",
    "GRADE",
    "PAPER",
    "POLYGON",
    "ROBOT",
    "SUITES",
    "TASKS_BY_DOMAIN",
    "TASK_KWARGS",
    "Insert",
    "InsertionPhysics",
    "PandaInsertionPhysics",
    "get_tasks",
    "load",
    "make_environment",
]
