"""Rotating laser scanner that measures bearings to surveyed retro-reflective beacons.

Lindgren §2.4: a scanner on the vehicle turns at 3.6 scans/s and reports the bearing, relative
to the body x axis, of each of 15 surveyed beacons it sweeps past ("not all simultaneously
visible", about 30 bearings per second in total), with variance 1e-4 rad². Bearings are not
identified: which beacon produced a bearing is for the estimator to decide (Lindgren Eq. 17 and
its nearest-innovation association).

Model. The scanner head points at body angle ``ψ(t) = ψ0 + 2π f t``. A beacon at body bearing
``φ(t)`` is hit when ``ψ(t) - φ(t)`` passes a multiple of 2π; the hit is reported if the beacon
is within ``max_range_m`` and inside the field of view ``|φ| <= fov_rad / 2`` (the rear sector
is hidden by the vehicle). Between two calls the vehicle pose is interpolated linearly, so each
bearing is computed from the pose at its own time stamp. Optional clutter adds spurious
bearings (Poisson, uniform over the field of view) to exercise the estimator's gating.

The default layout (:func:`default_beacons_xy`) is an assumption: the paper gives the number of
beacons, not where they stood. Fifteen beacons 8 m apart around the edge of a 30 m × 30 m field
centred on the origin; with a 25 m range and a 240° field of view, a vehicle within 8 m of the
centre sees 6-12 of them, about 34 bearings per second on average.
"""

from __future__ import annotations

import math

import numpy as np

from slipenv.contracts.angles import TWO_PI, wrap_angle, wrap_angles

FIELD_HALF_SIZE_M = 15.0  # half the side of the default square field [m] (assumed)


def _wrap_in_place(angles: np.ndarray) -> None:
    """:func:`wrap_angles` of a float array, written into it (the same operations)."""
    np.subtract(np.pi, angles, out=angles)
    np.mod(angles, TWO_PI, out=angles)
    np.subtract(np.pi, angles, out=angles)


def default_beacons_xy() -> np.ndarray:
    """The default 15-beacon layout: 8 m apart along the edge of a 30 m square field.

    Returns
    -------
    np.ndarray, shape (15, 2)
        Beacon positions [m], starting 2 m from the south-west corner, counter-clockwise.
    """
    side = 2.0 * FIELD_HALF_SIZE_M
    perimeter = 4.0 * side
    h = FIELD_HALF_SIZE_M
    out = []
    for s in np.arange(15) * perimeter / 15.0 + 2.0:
        k, u = divmod(float(s) % perimeter, side)
        out.append([(-h + u, -h), (h, -h + u), (h - u, h), (-h, h - u)][int(k)])
    return np.array(out)


MAX_BEACONS = 1000  # every scan costs O(beacons)
MAX_BEACON_COORD_M = 1e4  # [m] a survey of a field, not of a continent
MAX_SCAN_RATE_HZ = 100.0  # [1/s] head revolutions; Lindgren's is 3.6
MAX_CLUTTER_RATE_HZ = 1000.0  # [1/s]


def _is_number(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def as_beacons_xy(value, name: str = "beacons") -> np.ndarray:
    """Surveyed beacon positions as a float (m, 2) array [m], checked.

    Parameters
    ----------
    value : array_like, shape (m, 2)
        Positions [m]: 1 <= m <= 1000, every coordinate finite and within 10 km of the origin.
    name : str
        Option named in errors.

    Raises
    ------
    ValueError
        Naming ``name`` if ``value`` is not numeric, not (m, 2), empty, or out of range.
    """
    if isinstance(value, (str, bytes, dict)):
        raise ValueError(f"{name} must be an (n, 2) array of beacon positions [m], "
                         f"got {type(value).__name__} {value!r}")
    try:
        b = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an (n, 2) array of beacon positions [m] (numbers), "
                         f"got {value!r}") from None
    if b.ndim != 2 or b.shape[1] != 2 or not 1 <= b.shape[0] <= MAX_BEACONS:
        raise ValueError(f"{name} must be an (n, 2) array of beacon positions [m] with "
                         f"1 <= n <= {MAX_BEACONS}, got shape {b.shape}")
    if not np.all(np.isfinite(b)) or np.max(np.abs(b)) > MAX_BEACON_COORD_M:
        raise ValueError(f"{name} positions must be finite and within {MAX_BEACON_COORD_M:g} m "
                         "of the origin")
    return b


class BeaconScanner:
    """Rotating bearing-only beacon scanner (Lindgren §2.4).

    Parameters
    ----------
    beacons_xy : np.ndarray, shape (m, 2), optional
        Surveyed beacon positions [m]; :func:`default_beacons_xy` when None.
    scan_rate_hz : float
        Head revolutions per second [1/s] (Lindgren: 3.6).
    bearing_var_rad2 : float
        Bearing noise variance [rad²] (Lindgren: 1e-4).
    max_range_m : float
        Beacons farther than this are not seen [m] (assumed 25 m).
    fov_rad : float
        Field of view centred on body x [rad] (assumed 240°: the rear 120° is hidden).
    clutter_rate_hz : float
        Mean rate of spurious bearings [1/s] (0: none).
    head_phase_rad : float
        Head angle ψ0 at t = 0 [rad].

    Notes
    -----
    Every random draw comes from the ``rng`` passed to :meth:`scan`.
    """

    def __init__(
        self,
        beacons_xy: np.ndarray | None = None,
        scan_rate_hz: float = 3.6,
        bearing_var_rad2: float = 1e-4,
        max_range_m: float = 25.0,
        fov_rad: float = math.radians(240.0),
        clutter_rate_hz: float = 0.0,
        head_phase_rad: float = 0.0,
    ) -> None:
        b = default_beacons_xy() if beacons_xy is None else as_beacons_xy(beacons_xy, "beacons_xy")
        for name, value in (("scan_rate_hz", scan_rate_hz), ("max_range_m", max_range_m),
                            ("fov_rad", fov_rad)):
            if not (_is_number(value) and math.isfinite(value) and value > 0.0):
                raise ValueError(f"BeaconScanner.{name} must be finite and > 0, got {value!r}")
        for name, value in (("bearing_var_rad2", bearing_var_rad2),
                            ("clutter_rate_hz", clutter_rate_hz),
                            ("head_phase_rad", head_phase_rad)):
            if not (_is_number(value) and math.isfinite(value)):
                raise ValueError(f"BeaconScanner.{name} must be a finite number, got {value!r}")
        if not (bearing_var_rad2 >= 0.0 and clutter_rate_hz >= 0.0):
            raise ValueError("bearing_var_rad2 and clutter_rate_hz must be >= 0")
        if scan_rate_hz > MAX_SCAN_RATE_HZ or clutter_rate_hz > MAX_CLUTTER_RATE_HZ:
            raise ValueError(f"BeaconScanner.scan_rate_hz must be <= {MAX_SCAN_RATE_HZ:g} and "
                             f"clutter_rate_hz <= {MAX_CLUTTER_RATE_HZ:g} [1/s]")
        self.beacons_xy = b
        self.scan_rate_hz = float(scan_rate_hz)
        self.bearing_var_rad2 = float(bearing_var_rad2)
        self.max_range_m = float(max_range_m)
        self.fov_rad = float(min(fov_rad, 2.0 * math.pi))
        self.clutter_rate_hz = float(clutter_rate_hz)
        self.head_phase_rad = float(head_phase_rad)
        self._last: tuple[float, float, float, float] | None = None  # (t, x, y, yaw)
        # (x, y, beacons, world bearing of each beacon from there) at the last pose: the next
        # scan starts from that pose, so its bearings need not be computed twice
        self._last_bearings: tuple[float, float, np.ndarray, np.ndarray] | None = None

    def reset(self, t_s: float | None = None, x_m: float = 0.0, y_m: float = 0.0,
              yaw_rad: float = 0.0) -> None:
        """Start a new episode at time ``t_s`` and pose (x, y, yaw); no bearings before it.

        Without ``t_s`` the scanner forgets its last sweep and the next ``scan`` starts it.
        """
        if t_s is None:
            self._last = None
            return
        self._last = (float(t_s), float(x_m), float(y_m), float(yaw_rad))

    def _body_bearings(self, x: float, y: float, yaw: float) -> np.ndarray:
        """Unwrapped bearing of each beacon from pose (x, y, yaw) [rad], shape (m,)."""
        return self._world_bearings(x, y) - yaw

    def _world_bearings(self, x: float, y: float) -> np.ndarray:
        """Bearing of each beacon from (x, y), counter-clockwise from world x [rad], shape (m,);
        reuses the last pose's (the same floats give the same bearings)."""
        last = self._last_bearings
        if last is not None and last[0] == x and last[1] == y and last[2] is self.beacons_xy:
            return last[3]
        bearings = np.arctan2(self.beacons_xy[:, 1] - y, self.beacons_xy[:, 0] - x)
        self._last_bearings = (x, y, self.beacons_xy, bearings)
        return bearings

    def scan(
        self, t_s: float, x_m: float, y_m: float, yaw_rad: float, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray]:
        """Bearings the head swept past in (t_prev, t_s], with the vehicle now at (x, y, yaw).

        Parameters
        ----------
        t_s : float
            Current time [s]; must be after the previous call's.
        x_m, y_m, yaw_rad : float
            True vehicle pose now [m, m, rad]; the pose in between is interpolated from the
            previous call.
        rng : np.random.Generator
            Source of all noise.

        Returns
        -------
        bearings_rad : np.ndarray, shape (k,)
            Noisy bearings relative to body x, wrapped to [-π, π) [rad], unidentified.
        times_s : np.ndarray, shape (k,)
            Time stamp of each bearing [s], increasing, in (t_prev, t_s].
        """
        if self._last is None:  # the first call starts the scanner
            self.reset(t_s, x_m, y_m, yaw_rad)
            return np.zeros(0), np.zeros(0)
        t0, x0, y0, yaw0 = self._last
        t1 = float(t_s)
        if not t1 > t0:
            raise ValueError(f"BeaconScanner.scan: t = {t1!r} s is not after {t0!r} s")
        dyaw = wrap_angle(yaw_rad - yaw0)
        self._last = (t1, float(x_m), float(y_m), float(yaw_rad))
        dt = t1 - t0
        # g(t) = ψ(t) - φ(t), taken linear over the interval; hits where g = 2π m.
        # This runs at every control step on every beacon: the arrays are updated in place
        # (each expression keeps its operands and their order, so the values are the same).
        phi0 = self._body_bearings(x0, y0, yaw0)
        phi1 = self._body_bearings(float(x_m), float(y_m), yaw0 + dyaw)
        dphi = np.subtract(phi1, phi0, out=phi1)
        _wrap_in_place(dphi)
        g0 = np.subtract(self.head_phase_rad + 2.0 * math.pi * self.scan_rate_hz * t0, phi0,
                         out=phi0)
        dg = np.subtract(2.0 * math.pi * self.scan_rate_hz * dt, dphi, out=dphi)
        m_lo = np.floor(g0 / (2.0 * np.pi))
        m_lo += 1.0
        m_hi = np.add(g0, dg)
        m_hi /= 2.0 * np.pi
        np.floor(m_hi, out=m_hi)
        # a beacon is swept past m_hi - m_lo + 1 times (whole numbers) if that is > 0 and dg > 0
        hit = m_hi >= m_lo
        hit &= dg > 0.0
        if self.clutter_rate_hz == 0.0 and not hit.any():
            return np.zeros(0), np.zeros(0)  # the head swept past no beacon: nothing to draw
        idx = hit.nonzero()[0]
        m = m_lo[idx]
        if not (m == m_hi[idx]).all():  # a beacon swept past more than once
            n_hits = np.maximum(m_hi - m_lo + 1.0, 0.0).astype(int) * (dg > 0.0)
            idx = np.repeat(np.arange(len(self.beacons_xy)), n_hits)
            m = m_lo[idx] + (np.arange(len(idx)) - np.repeat(np.cumsum(n_hits) - n_hits, n_hits))
        frac = np.minimum(np.maximum((2.0 * np.pi * m - g0[idx]) / dg[idx], 0.0), 1.0)
        # time and pose at each hit, a + frac (b - a) per column: (t, x, y, yaw)
        at_hit = np.array((t0, x0, y0, yaw0)) + frac[:, None] * np.array((dt, x_m - x0,
                                                                           y_m - y0, dyaw))
        times = np.maximum(at_hit[:, 0], math.nextafter(t0, math.inf))  # inside (t0, t1]
        yaws = at_hit[:, 3]
        d = self.beacons_xy[idx] - at_hit[:, 1:3]
        dx, dy = d[:, 0], d[:, 1]
        bearing = wrap_angles(np.arctan2(dy, dx) - yaws)
        seen = (np.hypot(dx, dy) <= self.max_range_m) & (np.abs(bearing) <= 0.5 * self.fov_rad)
        bearing, times = bearing[seen], times[seen]
        bearing = bearing + rng.normal(0.0, math.sqrt(self.bearing_var_rad2), bearing.shape)
        if self.clutter_rate_hz > 0.0:
            k = rng.poisson(self.clutter_rate_hz * dt)
            bearing = np.concatenate([bearing, rng.uniform(-0.5, 0.5, k) * self.fov_rad])
            times = np.concatenate([times, t0 + dt * (1.0 - rng.uniform(0.0, 1.0, k))])
        if len(times) > 1:
            order = np.argsort(times, kind="stable")
            bearing, times = bearing[order], times[order]
        return wrap_angles(bearing), times
