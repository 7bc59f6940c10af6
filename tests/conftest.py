"""Shared test set-up."""

# tolins chooses headless OpenGL (MUJOCO_GL=egl) when mujoco is first imported; import it
# before any test module imports mujoco itself, so render tests run instead of skipping.
import tolins  # noqa: F401
