"""Synthetic skid-steer tracked-vehicle runs generated from Yamauchi Eq. 1-9 (test helper).

The "true" vehicle: constant input track speeds per run; the true yaw rate is a fraction
``efficiency`` of the commanded one; the track slips follow Endo's relation (Eq. 8) with
``N_TRUE`` exactly; the slip angle follows Eq. 9 with ``BETA_COEF``; the run lies on a plane tilted
by ``slope_rad`` with the uphill direction along world +y. Sensors: quantised encoders, gyro and
inclinometer with seeded Gaussian noise. Used by test_identification and test_yamauchi.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slipenv.contracts.frame import SensorFrame
from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.skid_steer.endo import endo_slip_velocities
from slipenv.estimators.skid_steer.identification import SlipRun, true_slips
from slipenv.estimators.skid_steer.yamauchi import rotation_radius_m

TREAD_M = 0.41  # [m] Yamauchi Table 1
SPROCKET_RADIUS_M = 0.06  # [m] assumed (slipenv Patako preset)
COUNTS_PER_RAD = 2000.0  # [counts/rad] assumed
N_TRUE = 0.824  # [-] Yamauchi Table 1
BETA_COEF = (0.03, -0.5, 0.04, -0.2)  # a1 [rad], a2 [-], a3 [-], a4 [rad/m]
MAX_RADIUS_M = 1.0  # [m] rotation-radius clip, as in SlipCompensatedOdometry's default
GEOMETRY = OdometryGeometry(SPROCKET_RADIUS_M, TREAD_M, COUNTS_PER_RAD)


def slope_attitude(yaw: np.ndarray, slope_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """Roll and pitch [rad] of a vehicle heading ``yaw`` on a plane rising along world +y."""
    s = np.sin(slope_rad)
    return np.arcsin(s * np.cos(yaw)), -np.arcsin(s * np.sin(yaw))


def beta_law(roll, angular_displacement, radius):
    """The true Eq. 9 slip angle [rad]."""
    a1, a2, a3, a4 = BETA_COEF
    return a1 + a2 * roll + a3 * angular_displacement + a4 * radius


@dataclass
class Run:
    """Truth and sensor frames of one synthetic run (arrays at the frame times)."""

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    yaw: np.ndarray
    beta: np.ndarray
    roll: np.ndarray
    angular_displacement: np.ndarray
    radius: float
    v_l: float
    v_r: float
    v_x: float
    omega: float
    frames: list[SensorFrame]

    @property
    def features(self) -> np.ndarray:
        """True regressors (roll, angular displacement, rotation radius), shape (k, 3)."""
        radius = np.full(self.t.size, self.radius)
        return np.column_stack([self.roll, self.angular_displacement, radius])


def simulate_run(
    speed_mps: float,
    yaw_rate_cmd: float,
    efficiency: float,
    slope_rad: float,
    yaw0: float,
    duration_s: float,
    rng: np.random.Generator,
    *,
    dt: float = 0.1,
    substeps: int = 20,
    gyro_std: float = 0.003,
    roll_std: float = 0.003,
) -> Run:
    """Simulate one constant-command run; truth integrated on a grid ``substeps`` × finer."""
    half = 0.5 * TREAD_M
    v_l, v_r = speed_mps - half * yaw_rate_cmd, speed_mps + half * yaw_rate_cmd
    omega = efficiency * yaw_rate_cmd
    s_l, s_r = endo_slip_velocities(v_l, v_r, omega, TREAD_M, N_TRUE, 0.0)
    v_x = float(0.5 * (v_l + v_r) - 0.5 * (s_l + s_r))  # Eq. 1
    radius = float(rotation_radius_m(v_x, omega, MAX_RADIUS_M))
    steps = int(round(duration_s / dt))
    tf = np.linspace(0.0, steps * dt, steps * substeps + 1)
    yaw = yaw0 + omega * tf
    roll, pitch = slope_attitude(yaw, slope_rad)
    beta = beta_law(roll, omega * tf, radius)
    speed = v_x / np.cos(beta)
    vx_w, vy_w = speed * np.cos(yaw + beta), speed * np.sin(yaw + beta)
    h = tf[1] - tf[0]
    x = np.concatenate([[0.0], np.cumsum(0.5 * h * (vx_w[1:] + vx_w[:-1]))])
    y = np.concatenate([[0.0], np.cumsum(0.5 * h * (vy_w[1:] + vy_w[:-1]))])
    k = slice(None, None, substeps)
    t = tf[k]
    frames = []
    for i, ti in enumerate(t):
        counts = np.rint(np.array([v_l, v_r]) / SPROCKET_RADIUS_M * ti * COUNTS_PER_RAD)
        frames.append(
            SensorFrame(
                t_s=float(ti),
                enc_counts=counts.astype(np.int64),
                wheel_torque_nm=np.full(2, np.nan),
                gyro_z_rad_s=float(omega + gyro_std * rng.standard_normal()),
                roll_rad=float(roll[k][i] + roll_std * rng.standard_normal()),
                pitch_rad=float(pitch[k][i] + roll_std * rng.standard_normal()),
            )
        )
    return Run(
        t=t, x=x[k], y=y[k], yaw=yaw[k], beta=beta[k], roll=roll[k],
        angular_displacement=omega * t, radius=radius, v_l=float(v_l), v_r=float(v_r),
        v_x=v_x, omega=float(omega), frames=frames,
    )


def rotation_runs(rng: np.random.Generator) -> list[Run]:
    """Yamauchi §2.3 in simulation: 0/8/15° slopes, 5 cm/s, 10/20/30 °/s, both directions, two
    start headings; each run turns about 90° from rest."""
    runs = []
    for slope_deg in (0.0, 8.0, 15.0):
        for rate_deg in (10.0, 20.0, 30.0):
            for direction in (1.0, -1.0):
                for yaw0 in (0.0, 0.5 * np.pi):
                    eff = rng.uniform(0.6, 0.9)
                    rate = direction * np.radians(rate_deg)
                    duration = 0.5 * np.pi / (eff * abs(rate))
                    slope = np.radians(slope_deg)
                    runs.append(simulate_run(0.05, rate, eff, slope, yaw0, duration, rng))
    return runs


def constant_frames(v_l, v_r, gyro, *, n=100, dt=0.05, geometry=GEOMETRY) -> list[SensorFrame]:
    """Frames of constant track speeds [m/s] and a constant gyro reading [rad/s] on level ground."""
    frames = []
    for k in range(n + 1):
        t = k * dt
        angles = np.array([v_l, v_r]) / geometry.wheel_radius_m * t
        counts = np.rint(angles * geometry.counts_per_rad).astype(np.int64)
        frames.append(SensorFrame(t, counts, np.full(2, np.nan), gyro_z_rad_s=gyro, roll_rad=0.0))
    return frames


def feed(estimator, frames, pose=(0.0, 0.0, 0.0)) -> list:
    """Reset on the first frame, update on the rest; return the updates' estimates."""
    estimator.reset(*pose, frames[0])
    return [estimator.update(f) for f in frames[1:]]


def noisy_endo_samples(runs, rng, v_std=5e-4, omega_std=2e-3) -> dict[str, np.ndarray]:
    """Track speeds and true slips from noisy ground-truth velocities (motion-capture derivatives),
    as keyword arguments of ``fit_endo_n``."""
    cols: dict[str, list] = {"v_l": [], "v_r": [], "alpha_l": [], "alpha_r": []}
    r = SPROCKET_RADIUS_M
    for run in runs:
        k = run.t.size
        v_x = run.v_x + v_std * rng.standard_normal(k)
        omega = run.omega + omega_std * rng.standard_normal(k)
        a_l, a_r, _ = true_slips(
            np.full(k, run.v_l / r), np.full(k, run.v_r / r), r, v_x, omega, np.zeros(k), TREAD_M
        )
        values = (np.full(k, run.v_l), np.full(k, run.v_r), a_l, a_r)
        for key, value in zip(cols, values, strict=True):
            cols[key].append(value)
    return {key: np.concatenate(v) for key, v in cols.items()}


def slip_runs(runs, rng, beta_std) -> list[SlipRun]:
    """Regression data of the runs: true features, slip angle with motion-capture noise [rad]."""
    return [
        SlipRun(f"run{i:02d}", run.features, run.beta + beta_std * rng.standard_normal(run.t.size))
        for i, run in enumerate(runs)
    ]


def run_estimator(estimator, run: Run) -> tuple[np.ndarray, list]:
    """Feed a run's frames; return the estimated positions (k, 2) and the estimates."""
    estimates = [estimator.reset(0.0, 0.0, float(run.yaw[0]), run.frames[0])]
    estimates += [estimator.update(f) for f in run.frames[1:]]
    return np.array([[e.x_m, e.y_m] for e in estimates]), estimates


def position_rmse(xy: np.ndarray, run: Run) -> float:
    """Position RMSE against the run's truth [m]."""
    return float(np.sqrt(np.mean((xy[:, 0] - run.x) ** 2 + (xy[:, 1] - run.y) ** 2)))
