"""MuJoCo models compiled from sockets, kept by identity of the spec.

A simulation whose workpiece changes (a bent-pin or other defect draw) runs on the model
that workpiece's MJCF compiles to (:func:`compile_model`). A :class:`SocketCache` keeps what
was built from a socket (a model, or a model with a data to draw it) so that a workpiece
that comes back is not compiled again: that of the owner's own socket always, and the
``size`` others built last besides. Every MuJoCo simulator compiles through these.
"""

from __future__ import annotations

import copy
import functools
from collections.abc import Callable
from typing import Any, Generic, TypeVar

import mujoco

from tolins.geometry.delicate import ElasticPins
from tolins.geometry.specs import SocketSpec
from tolins.mjcf import make_mjcf
from tolins.physics.versions import PhysicsVersion
from tolins.physics.versions import physics_version as physics_version_of

T = TypeVar("T")


def compile_model(
    socket: SocketSpec,
    physics_version: int | PhysicsVersion = 1,
    pins: ElasticPins | None = None,
) -> mujoco.MjModel:
    """The MuJoCo model of ``socket``'s board and workpiece (:func:`tolins.make_mjcf`) for a
    physics version (:mod:`tolins.physics.versions`: its number or the version itself);
    ``pins``: elastic-plastic pins (``None``: rigid)."""
    version = physics_version_of(physics_version)
    xml = make_mjcf(socket, board_body=not version.board_in_world, elastic=pins)
    return mujoco.MjModel.from_xml_string(xml)


def model_builder(
    physics_version: int | PhysicsVersion, pins: ElasticPins | None = None
) -> Callable[[SocketSpec], mujoco.MjModel]:
    """:func:`compile_model` of one physics version (and pins), looked up here once, as a
    picklable one-argument function (for a :class:`SocketCache`)."""
    return functools.partial(
        compile_model, physics_version=physics_version_of(physics_version), pins=pins
    )


def simulation_model(model: mujoco.MjModel, elastic: bool) -> mujoco.MjModel:
    """``model`` for one simulation of a batch: with elastic-plastic pins a copy (its
    ``eq_data`` holds that simulation's plastic set), else the shared model itself."""
    return copy.copy(model) if elastic else model


class SocketCache(Generic[T]):
    """What ``build`` makes of a socket, by identity of the spec (see the module docstring).

    Args:
        build: Makes the value of a socket (a module-level function, so the cache pickles).
        socket: The owner's own socket, whose value is kept for good.
        size: How many values of other sockets are kept besides, the oldest dropped first.
        own: The value of ``socket`` if the owner has built it already; else it is built
            on first use.
    """

    def __init__(
        self,
        build: Callable[[SocketSpec], T],
        socket: SocketSpec,
        size: int,
        own: T | None = None,
    ) -> None:
        self.build = build
        self.socket = socket
        self.size = size
        self._own = own
        # By id of the spec; each entry holds its spec, so the id is not reused meanwhile.
        self._others: dict[int, tuple[SocketSpec, T]] = {}

    def get(self, socket: SocketSpec) -> T:
        """The value of ``socket``: kept, or built now (and kept)."""
        if socket is self.socket:
            if self._own is None:
                self._own = self.build(socket)
            return self._own
        entry = self._others.get(id(socket))
        if entry is not None and entry[0] is socket:
            return entry[1]
        value = self.build(socket)
        if len(self._others) >= self.size:
            self._others.pop(next(iter(self._others)))
        self._others[id(socket)] = (socket, value)
        return value

    def clear(self) -> None:
        """Drop the values of the other sockets (the own socket's stays)."""
        self._others.clear()

    def __getstate__(self) -> dict[str, Any]:
        # The keys are ids of this process's objects: a copy keys its own specs anew.
        return {**self.__dict__, "_others": list(self._others.values())}

    def __setstate__(self, state: dict[str, Any]) -> None:
        others = state.pop("_others")
        self.__dict__.update(state)
        self._others = {id(socket): (socket, value) for socket, value in others}
