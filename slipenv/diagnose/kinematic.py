"""Kinematic test logs: a differential-drive robot with hidden geometry and correlated slip.

The second generator of the diagnosis tests, beside the PyBullet one of ``synth.py``, so the
tests do not rest on one simulator. The robot follows a commanded forward speed v and yaw
rate ω; its true geometry (rolling radii r_L, r_R and track width W, ``KinematicTruth``) sets
the wheel ground speeds v_L,R = v ∓ ω W/2 and the wheel rotations φ̇ = v_side / r_side (1 + s),
where s is a longitudinal wheel-speed noise, AR(1) in time per wheel (standard deviation
``slip_sigma``, correlation time ``slip_tau_s``): what a real floor does to odometry, and
why errors along a run are correlated. The ground truth integrates v, ω exactly (midpoint
rule), plus white OptiTrack-like noise; encoders are quantised. The log's ``meta.json``
holds the *nominal* geometry, so any difference is a hidden ``rolling_radius`` /
``track_width`` effect.

Routes: ``"mixed"`` (random pieces of 3-10 s, turning both ways, with straights) and
``"circle"`` (one way round, as OptiOdom's calibration circles).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slipenv.logs.log import Log
from slipenv.logs.meta import LogMeta

ROUTES = ("mixed", "circle")


@dataclass(frozen=True)
class KinematicTruth:
    """True geometry of the generated robot.

    Attributes
    ----------
    radius_left_m, radius_right_m : float
        Effective rolling radii [m].
    track_width_m : float
        Effective track width [m].
    """

    radius_left_m: float
    radius_right_m: float
    track_width_m: float

    def __post_init__(self) -> None:
        for name in ("radius_left_m", "radius_right_m", "track_width_m"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"KinematicTruth: {name} must be a finite number > 0 m, "
                                 f"got {value!r}")


def _commands(rng: np.random.Generator, t: np.ndarray, route: str) -> tuple:
    """Forward speed v [m/s] and yaw rate ω [rad/s] at every sample."""
    if route == "circle":
        v = np.full(t.shape, 0.5)
        w = np.full(t.shape, 0.5)
    elif route == "mixed":
        v, w = np.zeros(t.shape), np.zeros(t.shape)
        start = 0.0
        while start < t[-1] + 1e-9:
            stop = start + float(rng.uniform(3.0, 10.0))
            piece = (t >= start) & (t < stop)
            v[piece] = rng.uniform(0.3, 1.0)
            w[piece] = 0.0 if rng.random() < 0.3 else rng.uniform(0.2, 0.7) * rng.choice(
                [-1.0, 1.0])
            start = stop
    else:
        raise ValueError(f"route must be one of {ROUTES}, got {route!r}")
    ramp = np.clip(t / 1.0, 0.0, 1.0)  # 1 s start-up
    return v * ramp, w * ramp


def _ar1(rng: np.random.Generator, n: int, sigma: float, tau_steps: float) -> np.ndarray:
    """AR(1) series of stationary standard deviation ``sigma`` and correlation time
    ``tau_steps`` samples."""
    a = float(np.exp(-1.0 / max(tau_steps, 1e-9)))
    e = rng.normal(0.0, sigma * np.sqrt(1.0 - a * a), size=n)
    out = np.empty(n)
    out[0] = rng.normal(0.0, sigma)
    for k in range(1, n):
        out[k] = a * out[k - 1] + e[k]
    return out


def kinematic_log(seed: int, truth: KinematicTruth | None = None, *, duration_s: float = 120.0,
                  rate_hz: float = 20.0, route: str = "mixed", radius_m: float = 0.1,
                  track_m: float = 0.5, counts_per_rad: float = 2000.0,
                  slip_sigma: float = 0.01, slip_tau_s: float = 1.0,
                  gt_sigma_m: float = 1e-3, gt_sigma_rad: float = 1e-3) -> Log:
    """One log of the kinematic robot (seeded; nominal geometry ``radius_m``, ``track_m``).

    Parameters
    ----------
    seed : int
    truth : KinematicTruth, optional
        True geometry; the nominal one (a clean log) if None.
    duration_s, rate_hz : float
        Log length [s] and sample rate [Hz].
    route : str
        ``"mixed"`` or ``"circle"``.
    radius_m, track_m, counts_per_rad : float
        Nominal geometry written to ``meta.json`` [m, m, counts/rad].
    slip_sigma, slip_tau_s : float
        Wheel-speed noise: standard deviation [-] and correlation time [s].
    gt_sigma_m, gt_sigma_rad : float
        Ground-truth noise [m, rad].
    """
    if not (duration_s > 0 and rate_hz > 0):
        raise ValueError(f"duration_s and rate_hz must be > 0, got {duration_s}, {rate_hz}")
    truth = truth or KinematicTruth(radius_m, radius_m, track_m)
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s + 1e-9, 1.0 / rate_hz)
    n = t.size
    v, w = _commands(rng, t, route)
    vl, vr = v - 0.5 * w * truth.track_width_m, v + 0.5 * w * truth.track_width_m
    tau = slip_tau_s * rate_hz
    rate_l = vl / truth.radius_left_m * (1.0 + _ar1(rng, n, slip_sigma, tau))
    rate_r = vr / truth.radius_right_m * (1.0 + _ar1(rng, n, slip_sigma, tau))
    dt = np.diff(t)
    phi_l = np.concatenate([[0.0], np.cumsum(0.5 * (rate_l[1:] + rate_l[:-1]) * dt)])
    phi_r = np.concatenate([[0.0], np.cumsum(0.5 * (rate_r[1:] + rate_r[:-1]) * dt)])
    # the ground moves with the wheels' true rims: slip noise moves the robot too
    dl = np.diff(phi_l) * truth.radius_left_m
    dr = np.diff(phi_r) * truth.radius_right_m
    ds, dth = 0.5 * (dl + dr), (dr - dl) / truth.track_width_m
    yaw = np.concatenate([[0.0], np.cumsum(dth)])
    mid = yaw[:-1] + 0.5 * dth
    x = np.concatenate([[0.0], np.cumsum(ds * np.cos(mid))])
    y = np.concatenate([[0.0], np.cumsum(ds * np.sin(mid))])
    meta = LogMeta.new("diff_drive", ["left", "right"], wheel_radius_m=radius_m,
                       track_width_m=track_m, counts_per_rad=counts_per_rad,
                       terrain_description="kinematic generator (slipenv.diagnose.kinematic)",
                       notes=f"kinematic test log, seed {seed}, route {route}",
                       kinematic={"seed": seed, "route": route,
                                  "truth": {"radius_left_m": truth.radius_left_m,
                                            "radius_right_m": truth.radius_right_m,
                                            "track_width_m": truth.track_width_m},
                                  "slip_sigma": slip_sigma, "slip_tau_s": slip_tau_s})
    wrap = (yaw + rng.normal(0.0, gt_sigma_rad, n) + np.pi) % (2 * np.pi) - np.pi
    return Log.from_arrays(
        meta, t=t,
        enc_left=np.round(phi_l * counts_per_rad).astype(np.int64),
        enc_right=np.round(phi_r * counts_per_rad).astype(np.int64),
        gt_x=x + rng.normal(0.0, gt_sigma_m, n), gt_y=y + rng.normal(0.0, gt_sigma_m, n),
        gt_yaw=wrap)
