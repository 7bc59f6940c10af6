"""The insertion environment, its backends and the task table."""

from tolins.envs.initial_pose import InitialPoseDistribution
from tolins.envs.insertion_env import BACKENDS, InsertionEnv
from tolins.envs.tasks import GENERIC_ID, TASKS, Task, make_vec, register_envs

__all__ = [
    "BACKENDS",
    "GENERIC_ID",
    "TASKS",
    "InitialPoseDistribution",
    "InsertionEnv",
    "Task",
    "make_vec",
    "register_envs",
]
