"""Kinematic test logs: a robot of any kind with hidden geometry, torque slip, soil regions
and correlated wheel-speed noise.

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

Vehicle kinds (``KINDS``): ``diff_drive`` (wheels left, right), ``skid_steer`` (four wheels,
two per side turning together, the true track width being the effective one of the turning
geometry) and ``rover4ws`` (four steered wheels at (±L/2, ±W/2), each pointing along its
contact velocity — Reina's double-Ackermann kinematics; the logged ``steer_<wheel>`` are the
true angles; the body's motion is the least-squares twist of the four wheels' ground travel,
``replay.rover_twist``, so wheel noise moves the rover too).

Torque and soil (optional): with ``torque_slip_per_nm`` and/or ``soil_regions`` the log gets
``torque_<wheel>`` columns — a drive torque T = T_0 (1 + 0.5 |turn ratio|) (1 + u) with u a
slow AR(1) load variation (rolling resistance of uneven ground), 20 % standard deviation,
4 s correlation — and each wheel slips s = c(x, y) T (Lindgren Eq. 24 with compliance
c = 1/k_s): c is ``torque_slip_per_nm`` everywhere plus, inside each region (a rectangle,
turned or not, or a disc), that region's compliance. A wheel then turns 1/(1 - s) times
more than its ground travel (the replay's convention g = d - s |d|).

Routes: ``"mixed"`` (random pieces of 3-10 s, turning both ways, with straights), ``"circle"``
(one way round, as OptiOdom's calibration circles) and ``"field"`` (a lawn-mower sweep of a
square of ``field_m``: long straights joined by half turns, so every part of the square is
visited — what a soil map needs).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slipenv.logs.log import Log
from slipenv.logs.meta import LogMeta
from slipenv.terramechanics.soil_map import Circle, Rectangle

ROUTES = ("mixed", "circle", "field")
KINDS = ("diff_drive", "skid_steer", "rover4ws")
WHEELS = {"diff_drive": ["left", "right"],
          "skid_steer": ["front_left", "rear_left", "front_right", "rear_right"],
          "rover4ws": ["front_left", "front_right", "rear_left", "rear_right"]}
TORQUE_NM = 5.0  # [N m] T_0, the typical drive torque of the generated robot


@dataclass(frozen=True)
class SoilRegion:
    """A rectangle [m] of softer soil with extra torque compliance [1/(N m)], turned by
    ``angle_rad`` (counter-clockwise) about its centre; axis-aligned at the default 0."""

    x0_m: float
    y0_m: float
    x1_m: float
    y1_m: float
    compliance_per_nm: float
    angle_rad: float = 0.0

    def __post_init__(self) -> None:
        for name in ("x0_m", "y0_m", "x1_m", "y1_m", "compliance_per_nm", "angle_rad"):
            if not np.isfinite(getattr(self, name)):
                raise ValueError(f"SoilRegion: {name} must be finite")
        if not (self.x1_m > self.x0_m and self.y1_m > self.y0_m):
            raise ValueError("SoilRegion: needs x1_m > x0_m and y1_m > y0_m")

    def contains(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        shape = Rectangle(self.x0_m, self.y0_m, self.x1_m, self.y1_m, self.angle_rad)
        return shape.signed_distance_m(x, y) < 0.0


@dataclass(frozen=True)
class SoilDisc:
    """A disc [m] of softer soil with extra torque compliance [1/(N m)]."""

    center_x_m: float
    center_y_m: float
    radius_m: float
    compliance_per_nm: float

    def __post_init__(self) -> None:
        for name in ("center_x_m", "center_y_m", "radius_m", "compliance_per_nm"):
            if not np.isfinite(getattr(self, name)):
                raise ValueError(f"SoilDisc: {name} must be finite")
        if self.radius_m <= 0:
            raise ValueError("SoilDisc: needs radius_m > 0")

    def contains(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        shape = Circle(self.center_x_m, self.center_y_m, self.radius_m)
        return shape.signed_distance_m(x, y) < 0.0


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


def _field_commands(t: np.ndarray, field_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Lawn-mower sweep: straights of ``field_m`` joined by half turns of radius
    ``field_m / 16``, alternately left and right, back and forth over the square."""
    speed, radius = 0.5, field_m / 16.0
    straight_s, turn_s = field_m / speed, np.pi * radius / speed
    v, w = np.full(t.shape, speed), np.zeros(t.shape)
    period = straight_s + turn_s
    k = np.floor(t / period).astype(int)
    phase = t - k * period
    turning = phase >= straight_s
    # 8 lanes out and back: the turns alternate left/right, and every 8th pair comes back
    sign = np.where(k % 2 == 0, 1.0, -1.0) * np.where((k // 8) % 2 == 0, 1.0, -1.0)
    w[turning] = sign[turning] * speed / radius
    return v, w


def _commands(rng: np.random.Generator, t: np.ndarray, route: str,
              field_m: float = 8.0) -> tuple:
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
    elif route == "field":
        v, w = _field_commands(t, field_m)
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
                  gt_sigma_m: float = 1e-3, gt_sigma_rad: float = 1e-3,
                  kind: str = "diff_drive", wheelbase_m: float = 0.6,
                  torque_slip_per_nm: float | None = None,
                  soil_regions: tuple[SoilRegion | SoilDisc, ...] = (), with_torque: bool = False,
                  field_m: float = 8.0) -> Log:
    """One log of the kinematic robot (seeded; nominal geometry ``radius_m``, ``track_m``).

    Parameters
    ----------
    seed : int
    truth : KinematicTruth, optional
        True geometry (left/right radii per side); the nominal one (a clean log) if None.
    duration_s, rate_hz : float
        Log length [s] and sample rate [Hz].
    route : str
        ``"mixed"``, ``"circle"`` or ``"field"``.
    radius_m, track_m, counts_per_rad : float
        Nominal geometry written to ``meta.json`` [m, m, counts/rad].
    slip_sigma, slip_tau_s : float
        Wheel-speed noise: standard deviation [-] and correlation time [s].
    gt_sigma_m, gt_sigma_rad : float
        Ground-truth noise [m, rad].
    kind : str
        ``diff_drive``, ``skid_steer`` or ``rover4ws`` (``KINDS``).
    wheelbase_m : float
        Front-rear axle distance of the rover [m] (true and nominal).
    torque_slip_per_nm : float, optional
        Torque compliance c = 1/k_s everywhere [1/(N m)] (hidden ``torque_slip``).
    soil_regions : tuple of SoilRegion or SoilDisc
        Regions of extra compliance (hidden soil map); they add where they overlap.
    with_torque : bool
        Log ``torque_<wheel>`` even without torque slip (a clean log with torque).
    field_m : float
        Side of the square the ``"field"`` route sweeps [m].
    """
    if not (duration_s > 0 and rate_hz > 0):
        raise ValueError(f"duration_s and rate_hz must be > 0, got {duration_s}, {rate_hz}")
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    truth = truth or KinematicTruth(radius_m, radius_m, track_m)
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s + 1e-9, 1.0 / rate_hz)
    n = t.size
    v, w = _commands(rng, t, route, field_m)
    wheels = WHEELS[kind]
    sides = np.array([0 if "left" in name else 1 for name in wheels])
    r_true = np.where(sides == 0, truth.radius_left_m, truth.radius_right_m)
    y_true = (0.5 - sides) * truth.track_width_m
    x_true = np.array([0.5 * wheelbase_m if "front" in name else -0.5 * wheelbase_m
                       for name in wheels]) if kind == "rover4ws" else np.zeros(len(wheels))
    # each wheel's contact speed and (rover) steering angle for the commanded twist
    cvx = v[:, None] - w[:, None] * y_true[None, :]
    cvy = w[:, None] * x_true[None, :]
    steer = np.arctan2(cvy, np.where(np.abs(cvx) < 1e-12, 1e-12, cvx))
    ground_rate = np.hypot(cvx, cvy) * np.sign(np.where(cvx == 0, 1.0, cvx))
    if kind != "rover4ws":
        steer[:] = 0.0
        ground_rate = cvx
    tau = slip_tau_s * rate_hz
    noise = np.column_stack([_ar1(rng, n, slip_sigma, tau) for _ in wheels])
    hidden_torque = torque_slip_per_nm is not None or bool(soil_regions)
    torque = None
    if hidden_torque or with_torque:
        turn_ratio = np.abs(w) * truth.track_width_m / np.maximum(np.abs(v), 0.05)
        load = np.clip(1.0 + _ar1(rng, n, 0.2, 4.0 * rate_hz), 0.3, None)
        torque = TORQUE_NM * (1.0 + 0.5 * np.minimum(turn_ratio, 2.0))[:, None] * \
            np.column_stack([load * (1.0 + 0.02 * rng.standard_normal(n)) for _ in wheels])
        torque *= np.sign(np.where(ground_rate == 0, 1.0, ground_rate))
    # the ground moves with the wheels' true rims: slip noise moves the robot too
    ground = ground_rate * (1.0 + noise)
    dt = np.diff(t)
    g = 0.5 * (ground[1:] + ground[:-1]) * dt[:, None]  # ground travel per interval [m]
    st = 0.5 * (steer[1:] + steer[:-1])
    if kind == "rover4ws":
        from slipenv.diagnose.replay import rover_twist

        ds, dlat, dth = rover_twist(g, st, x_true[None, :], y_true[None, :])
    else:
        gl, gr = g[:, sides == 0].mean(1), g[:, sides == 1].mean(1)
        ds, dlat, dth = 0.5 * (gl + gr), np.zeros(n - 1), (gr - gl) / truth.track_width_m
    yaw = np.concatenate([[0.0], np.cumsum(dth)])
    mid = yaw[:-1] + 0.5 * dth
    x = np.concatenate([[0.0], np.cumsum(ds * np.cos(mid) - dlat * np.sin(mid))])
    y = np.concatenate([[0.0], np.cumsum(ds * np.sin(mid) + dlat * np.cos(mid))])
    if route == "field":  # start in the square's corner, sweeping it
        x, y = x - 0.5 * field_m, y - 0.5 * field_m
    slip = np.zeros(g.shape)
    if hidden_torque:
        assert torque is not None  # drawn above whenever it hides a slip
        xm, ym = 0.5 * (x[1:] + x[:-1]), 0.5 * (y[1:] + y[:-1])
        c = np.full(n - 1, torque_slip_per_nm or 0.0)
        for region in soil_regions:
            c = c + np.where(region.contains(xm, ym), region.compliance_per_nm, 0.0)
        slip = c[:, None] * 0.5 * (torque[1:] + torque[:-1])
    rim = g / np.clip(1.0 - slip * np.sign(g), 0.05, None)  # g = d - s |d|
    phi = np.vstack([np.zeros(len(wheels)), np.cumsum(rim / r_true[None, :], axis=0)])
    vehicle: dict = {"wheel_radius_m": radius_m, "track_width_m": track_m,
                     "counts_per_rad": counts_per_rad}
    if kind == "rover4ws":
        vehicle["wheelbase_m"] = wheelbase_m
    meta = LogMeta.new(kind, wheels, **vehicle,
                       terrain_description="kinematic generator (slipenv.diagnose.kinematic)",
                       notes=f"kinematic test log, seed {seed}, route {route}",
                       kinematic={"seed": seed, "route": route, "kind": kind,
                                  "truth": {"radius_left_m": truth.radius_left_m,
                                            "radius_right_m": truth.radius_right_m,
                                            "track_width_m": truth.track_width_m},
                                  "torque_slip_per_nm": torque_slip_per_nm,
                                  "soil_regions": [vars(r) for r in soil_regions],
                                  "slip_sigma": slip_sigma, "slip_tau_s": slip_tau_s})
    wrap = (yaw + rng.normal(0.0, gt_sigma_rad, n) + np.pi) % (2 * np.pi) - np.pi
    cols: dict = {f"enc_{name}": np.round(phi[:, k] * counts_per_rad).astype(np.int64)
                  for k, name in enumerate(wheels)}
    if kind == "rover4ws":
        cols.update({f"steer_{name}": steer[:, k] for k, name in enumerate(wheels)})
    if torque is not None:
        cols.update({f"torque_{name}": torque[:, k] for k, name in enumerate(wheels)})
    return Log.from_arrays(
        meta, t=t, **cols,
        gt_x=x + rng.normal(0.0, gt_sigma_m, n), gt_y=y + rng.normal(0.0, gt_sigma_m, n),
        gt_yaw=wrap)
