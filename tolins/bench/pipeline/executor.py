"""Where the bench's stages run: :class:`LocalExecutor` (this process, the default) or
:class:`RayExecutor` (Ray tasks on a cluster, ``pip install 'tolins[ray]'``).

A :class:`Job` is one stage: a module-level function, its arguments, and the jobs whose
results it takes as its last arguments. Both executors call the same functions with the
same arguments and return the results by job name in the jobs' order; they differ only
in where and when each job runs:

Both start a job once its dependencies are done and a worker is free, the ready job with
the costliest chain of work behind it first (:class:`Schedule`, :func:`critical_paths`).

- local: on a pool of ``workers`` threads, torch on one thread; RS-GAIL's candidates on
  each training's own thread pool. A job that holds the GIL most of its time
  (``own_process``: SB3's Python loop) runs in a process of its own, so that two of them
  do not take turns on one core.
- Ray: as a task (1 CPU) when one of the cluster's CPUs is free; torch on one thread in
  ``side_by_side`` tasks and on as many threads as the driver's elsewhere (as locally:
  torch's results can depend on its thread count); RS-GAIL's candidates on one
  :class:`~tolins.rollouts.ray_pool.RolloutWorker` actor per CPU of the cluster.

Results are identical (tested): every stage's seeds are fixed by its config, not by
where it runs. Stage folders need a filesystem every node shares (``DIR`` is checked on
the node before each task); each stage is submitted once and writes its files
atomically, the marker last (:mod:`tolins.bench.store.cache`).

A job that raises stops the run: no more start, and locally the running ones stop at
their next control step (:mod:`tolins.stopping`; a process of their own is ended with
SIGTERM, on which a deep-RL training first writes its checkpoint), as on Ctrl-C; the
exception is raised with the stage's name attached (:func:`failed_stage`, and a note in
its traceback).
"""

from __future__ import annotations

import heapq
import multiprocessing
import multiprocessing.pool
import os
import re
import socket
import sys
import threading
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tolins.stopping import clear_stop, request_stop, wait_unless_stopped

EXECUTORS = ("local", "ray")
#: Seconds the main thread sleeps at most while it waits for jobs. The kernel may deliver a
#: Ctrl-C to any thread of the process (to another one while the main thread has signals
#: blocked, as glibc's ``pthread_create`` does for an instant each time a thread starts);
#: Python runs the handler in the main thread only, the next time that thread wakes, so a
#: wait without a timeout takes the interruption only when the next job ends.
WAKE_S = 0.25
INSTALL_RAY = "pip install 'tolins[ray]'"
#: Seconds the check of ``--address`` waits to connect, and then for the head's answer.
PROBE_S = 2.0
#: HTTP/2's client connection preface and an empty SETTINGS frame (RFC 9113, 3.4); the
#: frame type of SETTINGS.
_HTTP2_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])
_SETTINGS = 4


@dataclass(frozen=True)
class Job:
    """One stage: ``fn(*args, *[result of each of deps])``.

    Attributes:
        name: Unique name (the stage's name).
        fn: A module-level function (Ray pickles it by reference).
        args: Its first arguments (picklable).
        deps: Names of earlier jobs whose results are its last arguments.
        side_by_side: An evaluation: on Ray, its task runs torch on one thread (a
            training's on the driver's count); locally every job runs torch on one thread.
        own_process: Its work holds the GIL most of the time (a Python loop of small
            torch calls): locally it runs in a process of the executor's own (Ray's tasks
            are processes anyway). Its arguments and result must pickle, as on Ray.
    """

    name: str
    fn: Callable[..., Any]
    args: tuple[Any, ...] = ()
    deps: tuple[str, ...] = ()
    side_by_side: bool = False
    own_process: bool = False


Callback = Callable[[Job], None] | None
DoneCallback = Callable[[Job, Any], None] | None


def failed_stage(error: BaseException) -> str | None:
    """The name of the stage whose job raised ``error`` (``None``: not raised by a job)."""
    return getattr(error, "tolins_stage", None)


def _mark_failed(error: BaseException, name: str) -> BaseException:
    """``error`` named as the failure of stage ``name`` (:func:`failed_stage`)."""
    error.tolins_stage = name  # type: ignore[attr-defined]
    error.add_note(f"(raised by the bench's stage {name})")
    return error


class LocalExecutor:
    """Jobs on ``workers`` threads of this process, each as soon as its dependencies are done,
    the ready job with the longest chain of work behind it first; an ``own_process`` job's
    thread hands it to one of ``workers`` spawned processes and waits for it.

    ``costs`` (seconds, by job name; :func:`~tolins.bench.pipeline.progress.expected_cost`)
    order the ready jobs: a job's priority is its own cost plus that of the costliest chain
    of jobs that need it (critical path first), ties in list order. Torch runs on one thread
    throughout (every training and evaluation asks for that, and one setting for the whole
    run keeps it so while jobs overlap), so results do not depend on the order.
    """

    name = "local"

    def __init__(self, workers: int = 2) -> None:
        self.workers = workers
        self.placement: dict[str, dict[str, Any]] = {}
        self._processes: multiprocessing.pool.Pool | None = None
        self._processes_made = threading.Lock()

    def _process_pool(self) -> multiprocessing.pool.Pool:
        """The processes of ``own_process`` jobs (spawned on first use: forking a process
        with threads running is unsafe), ``workers`` of them, kept until :meth:`close`."""
        with self._processes_made:
            if self._processes is None:
                self._processes = multiprocessing.get_context("spawn").Pool(self.workers)
            return self._processes

    def candidate_pool(self) -> None:
        """``None``: each RS-GAIL run makes its own thread pool."""
        return None

    def run(
        self,
        jobs: Sequence[Job],
        *,
        on_start: Callback = None,
        on_done: DoneCallback = None,
        costs: Mapping[str, float] | None = None,
    ) -> dict[str, Any]:
        """Run ``jobs``; their results by name. If one raises or the run is interrupted,
        no more start and the running ones stop at their next control step
        (:mod:`tolins.stopping`; an ``own_process`` job's process is ended by
        :meth:`close`), then the error is raised."""
        from tolins.learning.artefacts import single_threaded_torch

        results: dict[str, Any] = {}
        schedule = Schedule(jobs, costs or {})
        by_name = {job.name: job for job in jobs}

        def call(job: Job) -> Any:
            if on_start:
                on_start(job)
            args = (*job.args, *[results[d] for d in job.deps])
            if job.own_process:
                pending = self._process_pool().apply_async(_call_here, (job.fn, args))
                value, where = wait_unless_stopped(pending.get)
            else:
                value, where = job.fn(*args), _where()
            self.placement[job.name] = where
            if on_done:
                on_done(job, value)
            return value

        try:
            with single_threaded_torch(), ThreadPoolExecutor(self.workers) as pool:
                running: dict[Future, str] = {}
                try:
                    while schedule.ready or running:
                        while schedule.ready and len(running) < self.workers:
                            name = schedule.next()
                            running[pool.submit(call, by_name[name])] = name
                        done, _ = wait(running, timeout=WAKE_S, return_when=FIRST_COMPLETED)
                        for future in done:
                            name = running.pop(future)
                            error = future.exception()
                            if error is not None:
                                raise _mark_failed(error, name)
                            results[name] = future.result()
                            schedule.finished(name)
                except BaseException:
                    request_stop()  # leaving the pool waits for the running jobs: now brief
                    raise
        finally:
            clear_stop()
        return {job.name: results[job.name] for job in jobs}

    def close(self) -> None:
        """End the processes of ``own_process`` jobs, if any ran (a job still running in
        one, after a failure or an interruption, is ended with it)."""
        if self._processes is not None:
            self._processes.terminate()
            self._processes.join()
            self._processes = None


class Schedule:
    """Which job starts next: of those whose dependencies are done, the one with the
    costliest chain of work behind it (:func:`critical_paths`; ties in list order).

    Args:
        jobs: The jobs (a job's dependencies before it; names outside ``jobs`` are done).
        costs: Seconds by job name (a job missing from it costs 1).
    """

    def __init__(self, jobs: Sequence[Job], costs: Mapping[str, float]) -> None:
        self._priority = critical_paths(jobs, costs)
        self._order = {job.name: i for i, job in enumerate(jobs)}
        self._waiting = {job.name: set(job.deps) & set(self._order) for job in jobs}
        self._needed_by: dict[str, list[str]] = {job.name: [] for job in jobs}
        for job in jobs:
            for dep in self._waiting[job.name]:
                self._needed_by[dep].append(job.name)
        self._ready = [self._entry(n) for n, deps in self._waiting.items() if not deps]
        heapq.heapify(self._ready)

    @property
    def ready(self) -> bool:
        """Whether a job can start now."""
        return bool(self._ready)

    def next(self) -> str:
        """The name of the job to start now (taken off the ready ones)."""
        return heapq.heappop(self._ready)[2]

    def finished(self, name: str) -> None:
        """Job ``name`` is done: the jobs that waited only for it become ready."""
        for later in self._needed_by[name]:
            self._waiting[later].discard(name)
            if not self._waiting[later]:
                heapq.heappush(self._ready, self._entry(later))

    def _entry(self, name: str) -> tuple[float, int, str]:
        return -self._priority[name], self._order[name], name


def critical_paths(jobs: Sequence[Job], costs: Mapping[str, float]) -> dict[str, float]:
    """Each job's cost plus the costliest chain of jobs that need it (a job missing from
    ``costs`` costs 1)."""
    return chain_costs({job.name: job.deps for job in jobs}, costs)


def chain_costs(needs: Mapping[str, Sequence[str]], costs: Mapping[str, float]) -> dict[str, float]:
    """:func:`critical_paths` of the jobs ``needs`` names (job -> the jobs it needs, a job
    after those it needs; names outside ``needs`` are done)."""
    needed_by: dict[str, list[str]] = {name: [] for name in needs}
    for name, deps in needs.items():
        for dep in deps:
            if dep in needed_by:
                needed_by[dep].append(name)
    path: dict[str, float] = {}
    for name in reversed(list(needs)):
        after = max((path[n] for n in needed_by[name]), default=0.0)
        path[name] = costs.get(name, 1.0) + after
    return path


def check_address(address: str | None) -> None:
    """Raise ``ValueError`` unless ``address`` is ``None``, ``auto`` or ``HOST:PORT``."""
    if address is None or address == "auto":
        return
    match = re.fullmatch(r"([A-Za-z0-9._-]+|\[[0-9A-Fa-f:]+\]):(\d{1,5})", address)
    if match is None or not 1 <= int(match[2]) <= 65535:
        raise ValueError(
            f"address={address!r}; allowed: auto (the cluster `ray start` started on this "
            "machine) or HOST:PORT of a Ray head node, e.g. 127.0.0.1:6379"
        )


class RayExecutor:
    """Jobs as Ray tasks following their dependencies.

    Args:
        address: ``None`` starts a Ray instance on this machine, or uses the one this
            process already initialised (``ray.init(...)`` by the caller); ``auto`` or
            ``HOST:PORT`` connects to a running cluster.
        shared: A folder every task checks it can see (the bench's output folder).
    """

    name = "ray"

    def __init__(self, address: str | None = None, *, shared: str | Path | None = None) -> None:
        check_address(address)
        try:
            import ray
        except ImportError:
            raise ValueError(
                f"--executor ray needs Ray, which is not installed: {INSTALL_RAY}"
            ) from None
        import torch

        self._ray = ray
        _probe(address)
        self._owned = not ray.is_initialized()
        if self._owned:
            _connect(ray, address)
        elif address is not None:
            raise ValueError(
                f"address={address!r}, but Ray is already initialised in this process: "
                "pass no address to use that instance, or call ray.shutdown() first"
            )
        self.shared = None if shared is None else str(Path(shared).resolve())
        self.torch_threads = torch.get_num_threads()
        self.placement: dict[str, dict[str, Any]] = {}
        self._pool = None
        self._started = None

    @property
    def workers(self) -> int:
        """How many tasks run at once: the cluster's CPUs."""
        return max(1, int(self._ray.cluster_resources().get("CPU", 1)))

    def candidate_pool(self):
        """The :class:`~tolins.rollouts.ray_pool.RayPool` all trainings share (started once)."""
        if self._pool is None:
            from tolins.rollouts.ray_pool import RayPool

            self._pool = RayPool.start()
        return self._pool

    def run(
        self,
        jobs: Sequence[Job],
        *,
        on_start: Callback = None,
        on_done: DoneCallback = None,
        costs: Mapping[str, float] | None = None,
    ) -> dict[str, Any]:
        """As :meth:`LocalExecutor.run`: a task is submitted when its dependencies are done
        and one of the cluster's CPUs is free, the ready job with the costliest chain of work
        behind it first (:class:`Schedule`), so that Ray runs the jobs in that order.

        ``on_start`` is called when a task begins on its worker (each task puts its name on
        a :class:`ray.util.queue.Queue` first, which this loop reads every ``WAKE_S``)."""
        ray = self._ray
        task = ray.remote(num_cpus=1, num_returns=2)(_ray_task)
        started = self._start_queue() if on_start else None
        schedule = Schedule(jobs, costs or {})
        slots = self.workers
        by_name = {job.name: job for job in jobs}
        values: dict[str, Any] = {}
        running: dict[Any, Job] = {}  # the "where" reference of each task -> its job
        try:
            while schedule.ready or running:
                while schedule.ready and len(running) < slots:
                    job = by_name[schedule.next()]
                    threads = 1 if job.side_by_side else self.torch_threads
                    deps = [values[d] for d in job.deps]
                    values[job.name], where = task.options(name=job.name).remote(
                        job.fn, job.args, threads, self.shared, (started, job.name), *deps
                    )
                    running[where] = job
                done, _ = ray.wait(list(running), num_returns=1, timeout=WAKE_S)
                if started is not None:  # made only with an on_start
                    for name in started.get_nowait_batch(started.qsize()):
                        on_start(by_name[name])
                for ref in done:
                    job = running.pop(ref)
                    try:
                        self.placement[job.name] = ray.get(ref)
                        value = ray.get(values[job.name])
                    except Exception as error:
                        damaged = _stage_file_error(error)
                        if damaged is not None:  # its one line, not Ray's remote traceback
                            raise _mark_failed(damaged, job.name) from None
                        _mark_failed(error, job.name)
                        raise
                    if on_done:
                        on_done(job, value)
                    schedule.finished(job.name)
        finally:
            if started is not None:  # what a failed run's tasks put there
                started.get_nowait_batch(started.qsize())
        return {job.name: ray.get(values[job.name]) for job in jobs}

    def _start_queue(self) -> Any:
        """The queue Ray tasks put their names on as they start: an actor holding no CPU,
        made by the first run that reports starts and kept until :meth:`close` (an actor
        made anew for each run could take a worker that a task of that run then waits to
        see started)."""
        if self._started is None:
            from ray.util.queue import Queue

            self._started = Queue(actor_options={"num_cpus": 0})
        return self._started

    def close(self) -> None:
        """End the rollout actors and the start queue; disconnect from (or stop) the Ray
        instance started here."""
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None
        if self._started is not None:
            self._started.shutdown()
            self._started = None
        if self._owned and self._ray.is_initialized():
            self._ray.shutdown()


def make_executor(
    name: str, *, workers: int = 2, address: str | None = None, shared: str | Path | None = None
) -> LocalExecutor | RayExecutor:
    """The executor called ``name`` (:data:`EXECUTORS`)."""
    if name == "local":
        if address is not None:
            raise ValueError(f"address={address!r} needs executor='ray' (--executor ray)")
        return LocalExecutor(workers)
    if name == "ray":
        return RayExecutor(address, shared=shared)
    raise ValueError(f"executor={name!r}; allowed: {', '.join(EXECUTORS)}")


def _probe(address: str | None) -> None:
    """Fail fast, in one line with what to do, when no Ray head answers at ``HOST:PORT``:
    nothing listens there, or what does is no gRPC server (a Ray head's GCS is one), each
    found within :data:`PROBE_S` seconds. Else ``ray.init`` would retry for minutes,
    printing Ray's warnings."""
    if address is None or address == "auto":
        return
    host, port = address.rsplit(":", 1)
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=PROBE_S) as peer:
            problem = None if _tls() else _grpc_problem(peer)
    except OSError as error:
        problem = str(error)
    if problem is not None:
        raise ValueError(
            f"address={address!r}: no Ray head answers there ({problem}); start one with "
            "`ray start --head --port=PORT` or pass --address auto"
        )


def _grpc_problem(peer: socket.socket) -> str | None:
    """Why ``peer`` is no gRPC server (``None``: it is one): an HTTP/2 server sends a
    SETTINGS frame first, to the client's preface."""
    try:
        peer.sendall(_HTTP2_PREFACE)
        header = b""
        while len(header) < 9:
            chunk = peer.recv(9 - len(header))
            if not chunk:
                return "it closed the connection: not a gRPC server"
            header += chunk
    except TimeoutError:
        return f"no answer within {PROBE_S:g} s: not a gRPC server"
    return None if header[3] == _SETTINGS else "it answers, but not as a gRPC server"


def _tls() -> bool:
    """Whether Ray speaks TLS here (``RAY_USE_TLS``): then no plain preface is answered."""
    return os.environ.get("RAY_USE_TLS", "0").lower() in ("1", "true")


def _connect(ray: Any, address: str | None) -> None:
    if address is None:
        ray.init(include_dashboard=False, configure_logging=False)
        return
    try:
        ray.init(address=address, configure_logging=False)
    except ConnectionError as error:
        raise ValueError(
            f"address={address!r}: could not connect to a Ray cluster ({error}); start "
            "one with `ray start --head`"
        ) from None


def _stage_file_error(error: Exception) -> Exception | None:
    """The :class:`~tolins.bench.store.integrity.StageFileError` a Ray task raised, which
    Ray's ``error`` wraps (``None`` for any other error)."""
    from tolins.bench.store.integrity import StageFileError

    cause = getattr(error, "cause", None)
    return cause if isinstance(cause, StageFileError) else None


def _call_here(fn: Callable[..., Any], args: tuple[Any, ...]) -> tuple[Any, dict[str, Any]]:
    """``fn(*args)`` with torch on one thread, and where it ran (an ``own_process`` job)."""
    from tolins.learning.artefacts import single_threaded_torch

    with single_threaded_torch():
        return fn(*args), _where()


def _where() -> dict[str, Any]:
    """Where this call runs: Ray node id (``None`` outside Ray), host, process, thread."""
    ray = sys.modules.get("ray")  # never imported by the local executor
    node = ray.get_runtime_context().get_node_id() if ray and ray.is_initialized() else None
    return {
        "node": node,
        "host": socket.gethostname(),
        "pid": os.getpid(),
        "thread": threading.current_thread().name,
    }


def _ray_task(
    fn: Callable[..., Any],
    args: tuple,
    threads: int,
    shared: str | None,
    start: tuple[Any, str],
    *deps: Any,
) -> tuple[Any, dict[str, Any]]:
    import torch

    started, name = start
    if started is not None:
        started.put(name)

    if shared is not None and not Path(shared).is_dir():
        raise FileNotFoundError(
            f"{shared} is not visible on {socket.gethostname()}: with --executor ray the "
            "output folder must be on a filesystem every Ray node shares (NFS, a volume)"
        )
    torch.set_num_threads(threads)
    return fn(*args, *deps), _where()
