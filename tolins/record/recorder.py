"""Record insertion episodes to a rerun ``.rrd`` file, headless (no viewer needed)."""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any

import gymnasium as gym
import rerun as rr
import rerun.blueprint as rrb

from tolins.envs.insertion_env import InsertionEnv
from tolins.mjcf.model import scene_extent
from tolins.record.arm import ArmDrawing, arm_drawing
from tolins.record.episode import EpisodeBuffer, send_episode
from tolins.record.layout import default_blueprint
from tolins.record.metadata import spec_to_dict
from tolins.record.scene import log_board
from tolins.record.stale import remove_dead_temporaries
from tolins.rollouts.episodes import Episode, Policy, run_episode

APPLICATION_ID = "tolins"


def check_output_path(path: str | os.PathLike[str]) -> Path:
    """``path`` as a ``Path`` if it can take a new recording: ``*.rrd``, not a folder. Its
    folder is created if missing."""
    path = Path(path)
    if path.suffix != ".rrd":
        raise ValueError(f"{path}: not a .rrd path; allowed: a path ending in .rrd")
    if path.is_dir():
        raise ValueError(f"{path}: is a folder; allowed: a file path ending in .rrd")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise ValueError(f"{path}: cannot create folder {path.parent}: {error.strerror}") from error
    return path


class RrdFile:
    """A recording stream saved to ``path`` atomically.

    Everything is streamed to a hidden temporary file beside ``path``; :meth:`commit`
    completes it and renames it onto ``path`` (``os.replace``), :meth:`abort` deletes it.
    """

    def __init__(
        self, path: str | os.PathLike[str], blueprint: rrb.Blueprint | None = None
    ) -> None:
        self.path = check_output_path(path)
        remove_dead_temporaries(self.path)
        self._tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.tmp")
        self.stream = rr.RecordingStream(APPLICATION_ID)
        self.stream.save(self._tmp, default_blueprint=blueprint or default_blueprint())
        self._open = True

    def commit(self) -> None:
        """Flush, close and move the file into place (idempotent)."""
        if self._open:
            self._open = False
            self.stream.flush()
            self.stream.disconnect()
            os.replace(self._tmp, self.path)

    def abort(self) -> None:
        """Close and delete the temporary file; ``path`` is left as it was."""
        if self._open:
            self._open = False
            self.stream.disconnect()
            self._tmp.unlink(missing_ok=True)


class RerunRecorder(gym.Wrapper):
    """Log every episode of an insertion env to rerun.

    Per control step it only buffers ``info`` (pose, wrench, collision, success) and the
    reward (and, when a robot holds the part, its links' poses and the wrist's wrench:
    :mod:`tolins.record.arm`); at the episode's end it sends each quantity as one column (see
    :mod:`tolins.record.layout` for the entity paths) from a worker thread, which runs
    while the next episode's MuJoCo steps release the GIL. The board is logged once, at
    the first reset. Call :meth:`close` (or :meth:`finish`) to complete the file; errors
    of the worker are raised there.

    Args:
        env: An :class:`InsertionEnv`, possibly wrapped (e.g. by ``gymnasium.make``).
        target: A path ending in ``.rrd`` (written atomically on :meth:`finish` or
            :meth:`close`) or a ``rerun.RecordingStream`` the caller owns.
        policy_name: Stored with each episode's metadata.
        env_id: Stored in the metadata; defaults to ``env.spec.id``.
    """

    def __init__(
        self,
        env: gym.Env,
        target: str | os.PathLike[str] | rr.RecordingStream,
        *,
        policy_name: str | None = None,
        env_id: str | None = None,
    ) -> None:
        super().__init__(env)
        if not isinstance(env.unwrapped, InsertionEnv):
            raise ValueError(f"env={env!r} is not an InsertionEnv; allowed: tolins envs")
        self.env_id = env_id or (env.spec.id if env.spec is not None else "unregistered")
        self.policy_name = policy_name
        if isinstance(target, rr.RecordingStream):
            self._file, self.stream = None, target
        else:
            extent = scene_extent(env.unwrapped.nominal_socket)
            robot = env.unwrapped.settings.robot != "free"
            self._file = RrdFile(target, default_blueprint(extent, robot=robot))
            self.stream = self._file.stream
        self._episode: EpisodeBuffer | None = None
        self._arm: tuple[Any, ArmDrawing | None] | None = None
        self._sender = ThreadPoolExecutor(max_workers=1, thread_name_prefix="tolins-record")
        self._sent: list[Future[None]] = []
        self.episodes_recorded = 0

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Any, dict[str, Any]]:
        self._send_pending()
        observation, info = self.env.reset(seed=seed, options=options)
        base: InsertionEnv = self.env.unwrapped
        if self.episodes_recorded == 0:
            self._log_header(base)
        metadata = {
            "env_id": self.env_id,
            "policy": self.policy_name,
            "seed": seed,
            "backend": base.backend_name,
            "spec": base.socket,
        }
        self._episode = EpisodeBuffer(
            self.episodes_recorded, base.control_dt, metadata, base.collision_force
        )
        self._episode.on_reset(observation, info)
        if base.settings.robot != "free":
            self._episode.arm = self._arm_drawing(base)
            self._episode.add_arm(base.backend.data)
        self.episodes_recorded += 1
        return observation, info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        observation, reward, terminated, truncated, info = self.env.step(action)
        if self._episode is not None:
            self._episode.on_step(observation, action, reward, terminated, truncated, info)
            if self._episode.arm is not None:
                self._episode.add_arm(self.env.unwrapped.backend.data)
            if terminated or truncated:
                self._send_pending()
        return observation, reward, terminated, truncated, info

    def finish(self) -> None:
        """Send an unfinished episode and complete the file; the env stays open."""
        self._send_pending()
        self._wait_for_sends()
        if self._file is not None:
            self._file.commit()
            self._sender.shutdown()  # the file is complete: nothing more to send
        else:
            self.stream.flush()

    def abort(self) -> None:
        """Drop the file being written (a path target only)."""
        self._episode = None
        try:
            self._wait_for_sends()
        finally:
            if self._file is not None:
                self._file.abort()
                self._sender.shutdown()

    def close(self) -> None:
        try:
            self.finish()
        finally:
            self._sender.shutdown()
            super().close()

    def _arm_drawing(self, base: InsertionEnv) -> ArmDrawing | None:
        """The drawing of the robot of ``base``'s model now, kept per model."""
        model = base.backend.model
        if self._arm is None or self._arm[0] is not model:
            self._arm = (model, arm_drawing(model))
        return self._arm[1]

    def _send_pending(self) -> None:
        if self._episode is not None:
            episode, self._episode = self._episode, None
            done = [future for future in self._sent if future.done()]
            self._sent = [future for future in self._sent if future not in done]
            for future in done:
                future.result()  # a failed send raises here, early
            self._sent.append(self._sender.submit(send_episode, self.stream, episode))

    def _wait_for_sends(self) -> None:
        sent, self._sent = self._sent, []
        for future in sent:
            future.result()

    def _log_header(self, base: InsertionEnv) -> None:
        self.stream.send_recording_name(f"{self.env_id} ({self.policy_name or 'unnamed policy'})")
        self.stream.send_property(
            "tolins",
            rr.AnyValues(
                env_id=self.env_id,
                policy=self.policy_name or "",
                spec=json.dumps(spec_to_dict(base.nominal_socket)),
                backend=base.backend_name,
                robot=base.settings.robot,
                control_dt=base.control_dt,
            ),
        )
        log_board(self.stream, base.nominal_socket)


def policy_label(policy: Policy) -> str:
    """A policy's ``name`` attribute, else its type's name."""
    return str(getattr(policy, "name", None) or type(policy).__name__)


def record_episodes(
    env: gym.Env,
    policy: Policy,
    episodes: int,
    path: str | os.PathLike[str],
    *,
    seed: int | None = 0,
    policy_name: str | None = None,
    env_id: str | None = None,
    on_episode: Callable[[Episode], None] | None = None,
) -> list[Episode]:
    """Run ``episodes`` episodes of ``policy`` (seeds ``seed``, ``seed + 1``, ...) into
    ``path``. The file appears only once every episode is written; ``env`` stays open."""
    if not isinstance(episodes, int) or episodes < 1:
        raise ValueError(f"episodes={episodes!r}; allowed: an integer ≥ 1")
    recorder = RerunRecorder(
        env, path, policy_name=policy_name or policy_label(policy), env_id=env_id
    )
    results = []
    try:
        for i in range(episodes):
            result = run_episode(recorder, policy, seed=None if seed is None else seed + i)
            results.append(result)
            if on_episode is not None:
                on_episode(result)
        recorder.finish()
    except BaseException:
        recorder.abort()
        raise
    return results
