"""The observation and action layout shared by the environments and the controllers.

The environment builds the observation from its *estimated* pose (never ground truth) and the
path projection with :func:`build_observation`, the one place that does so; the controllers read
it by the indices defined here, so the two sides cannot drift apart.

Observation, float32, shape (12,):

=====  =====================  =======  ==================================================
index  constant               unit     meaning
=====  =====================  =======  ==================================================
0      ``OBS_X``              m        estimated x position, world frame
1      ``OBS_Y``              m        estimated y position, world frame
2      ``OBS_COS_YAW``        --       cos of estimated yaw
3      ``OBS_SIN_YAW``        --       sin of estimated yaw
4      ``OBS_SPEED``          m/s      estimated forward speed
5      ``OBS_YAW_RATE``       rad/s    estimated yaw rate, counter-clockwise positive
6      ``OBS_SLIP_ANGLE``     rad      slip angle estimate β̂, body x to velocity
                                       (0 until an estimator provides one)
7      ``OBS_CROSS_TRACK``    m        signed cross-track error, > 0 LEFT of the path
8      ``OBS_HEADING_ERROR``  rad      yaw - path heading, wrapped to (-pi, pi]
9      ``OBS_CURVATURE``      1/m      path curvature at the projection, > 0 turning left
10     ``OBS_REF_SPEED``      m/s      reference speed at the projection
11     ``OBS_PROGRESS``       --       fraction of the path done, 0..1
=====  =====================  =======  ==================================================

Action, float32 in [-1, 1]^2: ``[v / v_max, omega / omega_max]``, a body twist (forward speed,
yaw rate) that the env turns into wheel or track speeds through each vehicle's kinematics.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np

from slipenv.contracts.angles import wrap_angle

OBS_X = 0
OBS_Y = 1
OBS_COS_YAW = 2
OBS_SIN_YAW = 3
OBS_SPEED = 4
OBS_YAW_RATE = 5
OBS_SLIP_ANGLE = 6
OBS_CROSS_TRACK = 7
OBS_HEADING_ERROR = 8
OBS_CURVATURE = 9
OBS_REF_SPEED = 10
OBS_PROGRESS = 11
OBS_DIM = 12

OBS_NAMES = ("x_m", "y_m", "cos_yaw", "sin_yaw", "speed_mps", "yaw_rate_rps",
             "slip_angle_est_rad", "cross_track_m", "heading_error_rad", "path_curvature_1pm",
             "ref_speed_mps", "progress")

# Physical bounds of each entry; the env clips to them and declares them as its Box.
OBS_LOW = np.array([-1e4, -1e4, -1, -1, -50, -20, -math.pi, -1e4, -math.pi, -1e3, 0, 0],
                   dtype=np.float32)
OBS_HIGH = np.array([1e4, 1e4, 1, 1, 50, 20, math.pi, 1e4, math.pi, 1e3, 50, 1],
                    dtype=np.float32)

ACT_SPEED = 0
ACT_YAW_RATE = 1
ACT_DIM = 2


class ProjectionLike(Protocol):
    """What :func:`build_observation` needs of a path projection
    (:class:`slipenv.paths.PathProjection` satisfies it)."""

    @property
    def s(self) -> float: ...
    @property
    def cross_track_m(self) -> float: ...
    @property
    def heading_rad(self) -> float: ...
    @property
    def curvature_1pm(self) -> float: ...
    @property
    def speed_mps(self) -> float: ...
    @property
    def remaining_m(self) -> float: ...


def build_observation(x_m: float, y_m: float, yaw_rad: float, speed_mps: float,
                      yaw_rate_rps: float, projection: ProjectionLike,
                      slip_angle_est_rad: float = 0.0) -> np.ndarray:
    """Assemble the observation vector from an estimated state and a path projection.

    Parameters
    ----------
    x_m, y_m, yaw_rad, speed_mps, yaw_rate_rps : float
        Estimated pose [m, m, rad], forward speed [m/s] and yaw rate [rad/s].
    projection : ProjectionLike
        Projection of ``(x_m, y_m)`` on the path (``Path.project``).
    slip_angle_est_rad : float
        Estimated slip angle β̂ [rad]; 0 when no estimator provides one.

    Returns
    -------
    np.ndarray, shape (12,), float32
        Clipped to ``[OBS_LOW, OBS_HIGH]``.

    Raises
    ------
    FloatingPointError
        If an entry is NaN or infinite (a diverged estimator must not reach a policy).
    """
    if not math.isfinite(yaw_rad):  # math.cos would raise ValueError on ±inf
        raise FloatingPointError(f"non-finite observation: yaw_rad = {yaw_rad!r}")
    total = projection.s + projection.remaining_m
    obs = (x_m, y_m, math.cos(yaw_rad), math.sin(yaw_rad), speed_mps, yaw_rate_rps,
           slip_angle_est_rad, projection.cross_track_m,
           wrap_angle(yaw_rad - projection.heading_rad), projection.curvature_1pm,
           projection.speed_mps, projection.s / total if total > 0.0 else 1.0)
    out = np.asarray(obs, dtype=np.float32)
    if not np.all(np.isfinite(out)):
        raise FloatingPointError(f"non-finite observation: {out.tolist()}")
    return np.clip(out, OBS_LOW, OBS_HIGH)
