"""Contact geometry and the slip/sign convention shared by every force law in this package.

Slip and sign convention
------------------------
All models take, per wheel (or track segment), in the wheel's heading frame (x forward along the
wheel's rolling direction, y to the left, z up):

* slip ratio ``s = (r_eff omega - v) / max(|r_eff omega|, |v|)``, in [-1, 1], where v is the
  longitudinal speed of the wheel centre over the ground and r_eff = radius x
  `Soil.rolling_radius_scale`. In drive (r omega > v >= 0) this is ``s = 1 - v/(r omega)``
  (Lindgren Eq. 1, Reina Eq. 3); in braking ``s = (r omega - v)/|v|``. s > 0 drives: a spinning
  wheel at v = 0 has s = 1, a locked wheel sliding forward s = -1. Reversing is the mirror
  image: r omega = -1, v = -0.9 gives s = -0.1 and a backward push. A wheel turning against
  the motion (r omega, v of opposite signs) is clipped to s = +-1.
* ``tan_beta``, v_lateral positive to the left, in the law's slip-angle convention
  (`models.slip_angle_convention`): ``v_lateral / |v_longitudinal|`` (Reina Eq. 4) for
  Reina's law; along the sliding velocity, ``v_lateral / max(|r_eff omega|, |v|)``, for the
  Janosi and linear laws, whose shear displacement is the sliding velocity times the time a
  rim point has been in contact (`slip_dynamics`; in drive ``(1 - s) v_lateral / v``).
* normal load W [N], >= 0 (0 when the wheel is off the ground).

and return ``(fx_n, fy_n)`` [N] in the same frame: fx > 0 pushes forward (sign(fx) = sign(s)),
fy opposes the lateral sliding (sign(fy) = -sign(tan_beta)); and a motion resistance >= 0 that
the simulation applies against the direction of travel. The simulation regularises zero speed
itself (relaxation-length slip states) and always passes finite s and tan_beta.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["ContactGeometry", "slip_ratio"]


def slip_ratio(rim_speed_mps: ArrayLike, ground_speed_mps: ArrayLike) -> np.ndarray:
    """Signed slip ratio s = (r omega - v)/max(|r omega|, |v|) [-]; 0 when both speeds are 0.

    When the wheel turns against the motion (r omega and v of opposite signs) the ratio would
    reach +-2; it is clipped to [-1, 1], full slip either way.

    Parameters
    ----------
    rim_speed_mps : array_like
        r_eff omega [m/s], the speed the wheel would travel at without slip.
    ground_speed_mps : array_like
        v [m/s], longitudinal speed of the wheel centre over the ground.
    """
    rim = np.asarray(rim_speed_mps, dtype=float)
    ground = np.asarray(ground_speed_mps, dtype=float)
    num = rim - ground
    den = np.maximum(np.abs(rim), np.abs(ground))
    s = np.divide(num, den, out=np.zeros(np.broadcast(num, den).shape), where=den > 0.0)
    return np.clip(s, -1.0, 1.0)


@dataclass(frozen=True)
class ContactGeometry:
    """Geometry of one wheel's (or one track segment's) contact with the ground.

    Parameters
    ----------
    radius_m : float
        Nominal wheel (or drive sprocket) radius r [m]; converts torque to force.
    width_m : float
        Contact width b [m] (tyre, rim or track width).
    contact_length_m : float
        Contact length L [m] of this contact. For a track modelled as several contacts, the
        length share of this one.
    track_length_m : float or None
        None for a wheel. For a track, its whole ground-contact length [m] (>= contact length):
        shear displacement builds up along the whole track (Janosi uses B = K/track_length) and
        the track cuts one rut, shared by its segments (compaction scaled by L/track_length).

    Raises
    ------
    ValueError
        Naming the field and value, if a length is not finite and > 0, or if the track length
        is shorter than the contact length.
    """

    radius_m: float
    width_m: float
    contact_length_m: float
    track_length_m: float | None = None

    def __post_init__(self) -> None:
        for key in ("radius_m", "width_m", "contact_length_m"):
            _check_length(key, getattr(self, key))
        if self.track_length_m is not None:
            _check_length("track_length_m", self.track_length_m)
            if self.track_length_m < self.contact_length_m:
                raise ValueError(f"ContactGeometry field track_length_m={self.track_length_m!r} "
                                 f"must be >= contact_length_m={self.contact_length_m!r}")

    @property
    def is_track(self) -> bool:
        """True for a track (segment)."""
        return self.track_length_m is not None

    @property
    def area_m2(self) -> float:
        """Contact area A = b L [m^2] of this contact."""
        return self.width_m * self.contact_length_m

    @property
    def shear_length_m(self) -> float:
        """Length over which shear displacement builds up [m]: L (wheel) or track length."""
        return self.contact_length_m if self.track_length_m is None else self.track_length_m

    @property
    def rut_share(self) -> float:
        """Fraction of the rut's compaction work carried by this contact [-]."""
        return 1.0 if self.track_length_m is None else self.contact_length_m / self.track_length_m


def _check_length(key: str, value: object) -> None:
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise ValueError(f"ContactGeometry field {key}={value!r} must be a real number")
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"ContactGeometry field {key}={value!r} must be finite and > 0")
