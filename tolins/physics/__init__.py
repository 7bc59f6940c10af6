"""The simulators behind the envs, one folder: MuJoCo, the paper's kinematic model, MuJoCo Warp.

========================  ====================================================================
module                    what it holds
========================  ====================================================================
``protocol``              what every simulator returns (``BackendState``, ``BatchState``) and
                          offers (``Backend``, ``BatchPhysics``), and the capability flags
``schedule``              the control period: allowed values, physics steps, contact reads
``servo``                 the MuJoCo control step (``ServoStepper``), shared by every MuJoCo
                          stepper and by dm_control
``free_flight``           where nothing can touch: the longer physics step of ``-v2``
``versions``              the physics versions of the ``-v1`` and ``-v2`` ids
``compiled``              models compiled from sockets, cached by spec (``SocketCache``)
``mujoco``                ``MujocoBackend`` (single env) and ``MujocoBatch`` (``mujoco.batch``)
``kinematic``             the paper's simulator: ``KinematicBatch`` and its batch of one
``warp``                  ``WarpBatch`` on MuJoCo Warp (``pip install 'tolins[warp]'``)
``randomization``         randomised physics drawn per episode and applied to a model
``arm``                   the Panda's grasp, forward kinematics, wrist sensing and
                          operational-space law
``panda``                 ``PandaBatch`` and ``PandaBackend``: a Franka Panda holding the
                          workpiece (``robot="panda"``)
``registry``              the simulators by name and robot (``SIMULATORS``, ``ROBOTS``,
                          ``make_backend``, ``make_batch``)
========================  ====================================================================

The layer imports mjcf, geometry and the base modules only.
"""

from tolins.physics.protocol import Backend, BackendState, BatchPhysics, BatchState, Capabilities
from tolins.physics.registry import (
    BACKENDS,
    BATCH_BACKENDS,
    ROBOTS,
    SIMULATORS,
    Simulator,
    make_backend,
    make_batch,
    simulator,
)

__all__ = [
    "BACKENDS",
    "BATCH_BACKENDS",
    "ROBOTS",
    "SIMULATORS",
    "Backend",
    "BackendState",
    "BatchPhysics",
    "BatchState",
    "Capabilities",
    "Simulator",
    "make_backend",
    "make_batch",
    "simulator",
]
