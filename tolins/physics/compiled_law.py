"""The arm's operational-space law (:mod:`tolins.physics.arm`) compiled with numba.

:func:`law_torques` computes the law of :meth:`~tolins.physics.arm.Arm.batch_torques` for
one simulation from what MuJoCo gives (the grip site's Jacobian, the dense joint-space
inertia, the state and the bias forces) in a few microseconds, with the GIL released, so
that simulations on several threads update their laws at once. Its algebra is the numpy
law's (``tests/test_compiled_law.py`` holds them within 1e-9 of each other); the two
inverses are Cholesky solves here where numpy calls LAPACK's LU, so the last bits differ:
a Panda step is bit for bit the same in the single env, the vector env and dm_control, all
of which run this law, not between this law and the numpy one. Sums run left to right in
plain loops (no BLAS, no fast-math): the same bits on every CPU.

Importing this module imports numba (``tolins[robot]``; about a second), which
:class:`~tolins.physics.arm.Arm` does when a Panda is built
(:data:`~tolins.physics.arm.COMPILED`); without numba the arm runs the numpy law.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from tolins.physics import law_state

_compile = numba.njit(cache=True, nogil=True)

#: :func:`tolins.physics.law_state.advance_target`, compiled (the same operations, the
#: same bits).
advance_target = _compile(law_state.advance_target)


@_compile
def _cholesky_solve(matrix: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """``matrix⁻¹ rhs`` of a symmetric positive-definite ``matrix`` (Cholesky, in place
    of neither)."""
    n = matrix.shape[0]
    lower = np.zeros((n, n))
    for i in range(n):
        for j in range(i + 1):
            total = matrix[i, j]
            for k in range(j):
                total -= lower[i, k] * lower[j, k]
            if i == j:
                lower[i, i] = math.sqrt(total)
            else:
                lower[i, j] = total / lower[j, j]
    columns = rhs.shape[1]
    out = np.empty((n, columns))
    for c in range(columns):
        for i in range(n):  # forward: L y = b
            total = rhs[i, c]
            for k in range(i):
                total -= lower[i, k] * out[k, c]
            out[i, c] = total / lower[i, i]
        for i in range(n - 1, -1, -1):  # back: Lᵀ x = y
            total = out[i, c]
            for k in range(i + 1, n):
                total -= lower[k, i] * out[k, c]
            out[i, c] = total / lower[i, i]
    return out


@_compile
def _matmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a @ b`` summed left to right (no BLAS: the same bits on every CPU)."""
    out = np.zeros((a.shape[0], b.shape[1]))
    for i in range(a.shape[0]):
        for j in range(b.shape[1]):
            total = 0.0
            for k in range(a.shape[1]):
                total += a[i, k] * b[k, j]
            out[i, j] = total
    return out


@_compile
def _matvec(a: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``a @ x`` summed left to right."""
    out = np.zeros(a.shape[0])
    for i in range(a.shape[0]):
        total = 0.0
        for k in range(a.shape[1]):
            total += a[i, k] * x[k]
        out[i] = total
    return out


@_compile
def law_torques(
    jac_full: np.ndarray,
    mass_full: np.ndarray,
    qpos: np.ndarray,
    qvel: np.ndarray,
    site_xpos: np.ndarray,
    site_xmat: np.ndarray,
    bias_full: np.ndarray,
    ctrl: np.ndarray,
    index: np.ndarray,
    gains: np.ndarray,
    state: np.ndarray,
    limit: np.ndarray,
    advance: float,
    bounds: np.ndarray,
) -> None:
    """:func:`advance_target`, then the law's torques of one simulation into its ``ctrl``:
    ``jac_full`` ``(6, nv)`` the
    grip site's Jacobian, ``mass_full`` ``(nv, nv)`` the dense inertia, then the data's
    ``qpos``, ``qvel``, ``site_xpos``, ``site_xmat``, ``qfrc_bias`` and ``ctrl``; ``index``
    the grip site's id, then the arm's qpos addresses, dof addresses and motors (7 each);
    ``gains`` of :func:`~tolins.physics.law_state.pack_gains`; ``state`` the law state
    (:data:`~tolins.physics.law_state.STATE`);
    ``limit`` the motors' torque limits."""
    n = (index.shape[0] - 1) // 3
    site = index[0]
    qpos_index, dof, motors = index[1 : 1 + n], index[1 + n : 1 + 2 * n], index[1 + 2 * n :]
    twist = advance_target(state, advance, bounds)
    target, yaw, posture = state[0:3], state[3], state[10 : 10 + n]
    site_pos, site_mat = site_xpos[site], site_xmat[site]
    n = dof.shape[0]
    jac = np.empty((6, n))
    mass = np.empty((n, n))
    for j in range(n):
        for r in range(6):
            jac[r, j] = jac_full[r, dof[j]]
        for i in range(n):
            mass[i, j] = mass_full[dof[i], dof[j]]
    # the rotation error: the vee of the skew part of R* Rᵀ, R* the grip frame at yaw
    c, s = math.cos(yaw), math.sin(yaw)
    rot = np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]])
    turn = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            for k in range(3):
                turn[i, j] += rot[i, k] * site_mat[j * 3 + k]
    error = np.empty(6)
    for i in range(3):
        error[i] = target[i] - site_pos[i]
    error[3] = 0.5 * (turn[2, 1] - turn[1, 2])
    error[4] = 0.5 * (turn[0, 2] - turn[2, 0])
    error[5] = 0.5 * (turn[1, 0] - turn[0, 1])
    q = np.empty(n)
    qdot = np.empty(n)
    for j in range(n):
        q[j] = qpos[qpos_index[j]]
        qdot[j] = qvel[dof[j]]
    # X = M⁻¹ Jᵀ, Λ = (J X)⁻¹, J̄ = X Λ
    jac_t = jac.T.copy()
    solved = _cholesky_solve(mass, jac_t)
    inverse_task = _matmul(jac, solved)
    task = _cholesky_solve(inverse_task, np.eye(6))
    velocity = _matvec(jac, qdot)
    pull = np.empty(6)
    drive = np.empty(6)
    for r in range(6):
        pull[r] = gains[r] * error[r]
        drive[r] = gains[6 + r] * (twist[r] - velocity[r])
    for r in range(3):
        most = gains[12 + r] / task[r, r]
        pull[r] = min(max(pull[r], -most), most)
    wrench = _matvec(task, pull) + _matvec(task, drive)
    for r in range(3):
        wrench[r] += gains[16 + r]
    consistent = _matmul(solved, task)
    rate = gains[15]
    damping = 2.0 * math.sqrt(rate)
    posture_acc = np.empty(n)
    for j in range(n):
        posture_acc[j] = rate * (posture[j] - q[j]) - damping * qdot[j]
    hold = _matvec(mass, posture_acc)
    # N hold with N = I − Jᵀ J̄ᵀ
    projected = _matvec(consistent.T.copy(), hold)
    tau = _matvec(jac_t, wrench) + (hold - _matvec(jac_t, projected))
    for j in range(n):
        value = tau[j] + bias_full[dof[j]]
        ctrl[motors[j]] = min(max(value, -limit[j]), limit[j])
