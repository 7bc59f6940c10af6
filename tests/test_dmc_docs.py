"""docs/dm_control.md names only what exists: every ``env.task.X`` (or ``task.X``) it
writes resolves on a loaded env's task after a reset and a step, and it lists every task
keyword."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tolins import dmc

DOC = Path(__file__).resolve().parents[1] / "docs" / "dm_control.md"
#: ``env.task.a.b`` or ``task.a()`` inside backticks, not ``tolins.envs.tasks...``.
_CHAIN = re.compile(r"(?<![\w.])(?:env\.)?task((?:\.[A-Za-z_]\w*)+)(\(\))?")
#: The sentence form that once hid five missing names: "`env.task` exposes `a`, `b`".
_LIST = re.compile(r"`(?:env\.)?task` (?:exposes|has|holds) ([^.;]*)")


def documented(text: str) -> list[tuple[tuple[str, ...], bool]]:
    """Each attribute path the doc names on the task, and whether it is called ``()``."""
    names = []
    blocks = re.findall(r"```.*?```", text, flags=re.DOTALL)  # code examples count too
    prose = re.sub(r"```.*?```", "", text, flags=re.DOTALL)
    for code in blocks + re.findall(r"`([^`]+)`", prose):
        names += [(tuple(m[1].split(".")[1:]), bool(m[2])) for m in _CHAIN.finditer(code)]
    for listed in _LIST.findall(text):
        names += [((name,), False) for name in re.findall(r"`(\w+)`", listed)]
    return sorted(set(names))


def test_the_parser_sees_both_forms():
    text = "`env.task.score.steps`, `task.last_score.reward_info()`; `env.task` exposes `a`, `b`."
    assert documented(text) == [
        (("a",), False),
        (("b",), False),
        (("last_score", "reward_info"), True),
        (("score", "steps"), False),
    ]
    assert documented("`tolins.envs.tasks.TASKS`, `dmc.Insert`") == []
    assert documented("```python\nenv.task.goal\n```\n`task.error`") == [
        (("error",), False),
        (("goal",), False),
    ]


def _resolve(task: object, path: tuple[str, ...], call: bool) -> object:
    value = task
    for name in path:
        assert hasattr(value, name), f"task.{'.'.join(path)}: {type(value).__name__} has no {name}"
        value = getattr(value, name)
    return value() if call else value


@pytest.mark.parametrize("domain", ["circle2x2", "circle2x1_defective"])
def test_every_task_attribute_the_doc_names_exists(domain):
    names = documented(DOC.read_text())
    assert len(names) >= 10  # the doc's table is there
    env = dmc.load(domain, "insert", task_kwargs={"random": 0})
    env.reset()
    timestep = env.step([0.0, 0.0, 0.0, -2.5])
    for path, call in names:
        _resolve(env.task, path, call)
    # and they mean what the doc says
    assert env.task.score.steps == 1
    assert env.task.last_score.reward == timestep.reward
    assert sum(env.task.last_score.reward_info().values()) == pytest.approx(timestep.reward)
    assert env.task.error is None


def test_the_doc_lists_every_task_keyword():
    text = DOC.read_text()
    section = text[text.index("**task_kwargs**") :]
    missing = [name for name in dmc.TASK_KWARGS if f"`{name}`" not in section]
    assert not missing, f"docs/dm_control.md does not list task_kwargs {missing}"
