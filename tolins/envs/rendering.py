"""Offscreen renderers that are closed before the interpreter tears OpenGL down, each in its
own OpenGL context (:func:`close_renderer`).

A ``mujoco.Renderer`` left open (an env that rendered and was never closed) is freed by
its ``__del__`` at interpreter exit, after MuJoCo's own exit handler has terminated the
EGL display: every such renderer then prints ``EGLError`` tracebacks. Renderers made by
:func:`open_renderer` are closed by an exit handler that runs before that one.
"""

from __future__ import annotations

import atexit
import weakref

import mujoco
import numpy as np

#: Height and width (pixels) of the env's ``rgb_array`` frames.
FRAME_SIZE = (480, 640)
#: The MJCF camera the frames are drawn from.
CAMERA = "overview"

#: The renderers :func:`open_renderer` made that are still alive (closing twice is harmless).
_OPEN: weakref.WeakSet[mujoco.Renderer] = weakref.WeakSet()


def close_renderer(renderer: mujoco.Renderer) -> None:
    """Close ``renderer`` with its own OpenGL context current. ``Renderer.close`` frees its
    textures and buffers in whichever context is current: with another renderer's current
    it deletes that renderer's objects of the same ids, whose later frames come out wrong."""
    context = getattr(renderer, "_gl_context", None)
    if context is not None:
        context.make_current()
    renderer.close()


def _close_open_renderers() -> None:
    """Close every renderer :func:`open_renderer` made that is still alive."""
    for renderer in list(_OPEN):
        close_renderer(renderer)


def open_renderer(model: mujoco.MjModel, height: int, width: int) -> mujoco.Renderer:
    """A ``mujoco.Renderer(model, height, width)`` that is closed at interpreter exit if its
    owner has not closed it (it is also closed, as any, when garbage collected).

    Exit handlers run last registered first, and the EGL display's handler is registered
    when the first OpenGL context is made; this one is registered again after every new
    renderer, so it always runs first.
    """
    renderer = mujoco.Renderer(model, height, width)
    _OPEN.add(renderer)
    atexit.unregister(_close_open_renderers)
    atexit.register(_close_open_renderers)
    return renderer


def draw_frame(renderer: mujoco.Renderer, data: mujoco.MjData) -> np.ndarray:
    """The ``rgb_array`` frame ``(height, width, 3)`` uint8 of ``data`` (a state of the
    renderer's model) seen from :data:`CAMERA`."""
    renderer.update_scene(data, camera=CAMERA)
    return renderer.render()
