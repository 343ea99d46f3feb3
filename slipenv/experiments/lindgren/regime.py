"""Where the simulated field's operating point sits on the paper's torque/slip curve.

Lindgren §3.3 fitted Okello's curve T = T_max [1 - (B/s)(1 - e^{-s/B})] (Eq. 20-21) to the
vehicle's straight driving and found the data "near linear": "only the part of the torque/slip
relationship close to the origin is observed" (Fig. 2), "for our low draught force
application, the slip experienced remains small enough that the relationship can be
adequately modeled as linear" (§6). The torque sensors were matched at 100 N m (§2.2).

On that curve, with x = s/B, the torque is T = T_max g(x), g(x) = 1 - (1 - e^{-x})/x, and its
secant T/s over the slope at zero slip k_s = T_max/(2B) (Eq. 24) is 2 h(x), h(x) = g(x)/x
(:func:`slipenv.terramechanics.janosi.okello_secant`): 1 at the origin, falling as the curve
bends. :func:`operating_point` reads x from the calibration drive's measured secant over the
law's slope at zero slip, and gives the share of T_max used, the slip the linear law would
predict at that torque, and the motion resistance the driven wheels overcome.
"""

from __future__ import annotations

import math

import gymnasium as gym
from scipy.optimize import brentq

from slipenv.terramechanics.janosi import okello_secant
from slipenv.terramechanics.presets import soil_by_name
from slipenv.vehicles.presets import vehicle_by_name

from .settings import ENV_ID

G_MPS2 = 9.80665  # [m/s²] standard gravity


def okello_bracket(x: float) -> float:
    """g(x) = 1 - (1 - e^{-x})/x = T/T_max at x = s/B (Lindgren Eq. 21), x >= 0."""
    return float(x * okello_secant(x))


def curve_position(secant_over_tangent: float) -> float:
    """x = s/B at which Okello's curve's secant T/s is ``secant_over_tangent`` times its slope
    at zero slip: the root of 2 h(x) = ratio (h falls from 1/2 at x = 0 to 0); 0 for a ratio
    >= 1 (a linear law), inf for a ratio <= 0."""
    if not secant_over_tangent < 1.0:
        return 0.0
    if not secant_over_tangent > 0.0:
        return math.inf
    return float(brentq(lambda x: 2.0 * float(okello_secant(x)) - secant_over_tangent,
                        0.0, 1e6, xtol=1e-12))


def field_preset() -> dict:
    """The env's vehicle weight [N], driven wheel radius [m] and, from its soil and contact
    length, Okello's B = K/L (the shear deformation modulus over the shear length)."""
    config = gym.spec(ENV_ID).kwargs["config"]
    spec = vehicle_by_name(config.vehicle)
    soil = soil_by_name(config.soil)
    driven = [w for w in spec.wheels if w.channel is not None]
    contact = sum(w.contact_length_m for w in driven) / len(driven)
    return {"vehicle": spec.name, "soil": soil.name, "weight_n": spec.mass_kg * G_MPS2,
            "wheel_radius_m": driven[0].radius_m, "shear_modulus_m": soil.shear_modulus_m,
            "contact_length_m": contact, "shape_b": soil.shear_modulus_m / contact}


def operating_point(calibration: dict, k_s_tangent_nm: float, preset: dict) -> dict:
    """The calibration drive's point on Okello's curve, and its motion resistance.

    Parameters
    ----------
    calibration : dict
        :func:`~.calibration.radius_from_recording` of a straight drive at constant speed.
    k_s_tangent_nm : float
        The world's torque/slip slope at zero slip (the oracle's k_s, mean of the sides) [N m].
    preset : dict
        :func:`field_preset`.

    Returns
    -------
    dict
        ``torque_nm`` (per driven wheel), ``slip`` (true, mean of the sides), ``secant_nm``,
        ``secant_over_tangent``, ``x`` = s/B read from that ratio, ``b_measured`` = s/x,
        ``b_preset`` (K/L), ``torque_share`` = T/T_max = g(x), ``linear_slip`` = T/k_s (what
        the linear law through the law's zero-slip slope predicts), ``motion_resistance_n``
        (the driven wheels' thrust on the straight at constant speed, Σ T / r) and
        ``resistance_share`` of the weight.
    """
    torque = float(sum(calibration["mean_torque_nm"]) / len(calibration["mean_torque_nm"]))
    slip = float(calibration["slip_vs_true_radius"])
    secant = torque / slip if slip > 0.0 else math.nan
    ratio = secant / k_s_tangent_nm
    x = curve_position(ratio)
    resistance = sum(calibration["mean_torque_nm"]) / preset["wheel_radius_m"]
    return {"torque_nm": torque, "slip": slip, "secant_nm": secant,
            "tangent_nm": k_s_tangent_nm, "secant_over_tangent": ratio, "x": x,
            "b_measured": slip / x if x > 0.0 else math.nan, "b_preset": preset["shape_b"],
            "torque_share": okello_bracket(x) if math.isfinite(x) else 1.0,
            "linear_slip": torque / k_s_tangent_nm,
            "motion_resistance_n": resistance,
            "resistance_share": resistance / preset["weight_n"], "weight_n": preset["weight_n"]}
