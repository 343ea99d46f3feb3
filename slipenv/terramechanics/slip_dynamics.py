"""Slip as a state: relaxation length and step, soil dampers, and the rut (Coulomb) resistance.

Float functions of one wheel (convention of `contact`: s > 0 drives, tan_beta in the force law's
slip-angle convention (below), forces in the wheel's heading frame). Each law is written once, in C
(``slipenv/terramechanics/_laws.h``), the text the simulation's substep loop runs; the functions
here call it, and their docstrings give the sources and the equations.

Relaxation (Pacejka, Tyre and Vehicle Dynamics, 3rd ed., §7.2.1). The slip ratio and the slip
angle are states with a relaxation length sigma [m],

    sigma ds/dt + V s = r omega - v,      sigma db/dt + V_b b = v_lat,
    V = max(|r omega|, |v|, |v_lat|),

whose steady state is the kinematic slip (`contact.slip_ratio`). The lateral state's reference
speed V_b is the force law's slip-angle convention:

* the sliding velocity (Janosi, linear laws): V_b = V, so b -> v_lat/V. One reference speed for
  both components keeps (s, tan_beta) along the contact point's sliding velocity
  (r omega - v, v_lat) even at large slip, which the isotropic shear laws split the resultant
  by: the Janosi shear displacement at x along the patch is that velocity times the time
  x/(r omega) the rim point has been in contact (Lindgren Eq. 2; Wong, Theory of Ground
  Vehicles, Ch. 5, j = i x), so in drive tan_beta = v_lat/(r omega) = (1 - s) v_lat/v.
* Reina's (`relax_slip(..., forward_reference=True)`, `ReinaForceModel`):
  V_b = max(|v|, |v_lat|), so b -> v_lat/|v|, Reina's tan(beta) = V_y/V_x (Reina Eq. 4, the
  convention Table 3 was fitted in), up to 45 deg and +-1 beyond. This is Pacejka's own lateral
  relaxation (leak |V_cx|, steady tan(alpha) = V_sy/|V_cx|, §7.2.1) with |v_lat| added to the
  leak: with |V_cx| alone, at v -> 0 the state has no leak and a wheel sliding purely sideways
  would wind it up to the clip; with |v_lat| it settles smoothly at the same saturation as the
  sliding convention (tan_beta = +-1, where the clip also sits). The state is what the law
  reads: nothing divides by v, so v -> 0 is harmless (below).

At standstill V = V_b = 0 and the state integrates the slip displacement, so a parked vehicle
is held by a soil "spring" (the Janosi shear deformation) instead of creeping; a wheel spinning
at v = 0 reaches s = 1 with no division by zero (its lateral state, in Reina's convention, holds
whatever lateral deformation it had, a spring the side damper damps); pure sideways motion
drives tan_beta to +-1 against the motion. The soil spring is passive at any V_b >= 0: its
force opposes b and the leak V_b b only removes deformation. `relax_slip` takes one backward
Euler step, unconditionally stable for this linear ODE, which keeps a light wheel smooth even
when its spin time constant falls below the time step.

Damping (the sigma_1 term of the LuGre friction model, Canudas de Wit, Olsson, Astrom and
Lischinsky, IEEE TAC 40(3), 1995; faded with speed as in Canudas de Wit et al. 2003). Held still,
the relaxation state is an undamped spring of stiffness C/sigma [N/m] (C = dF/ds at s = 0);
`critical_damping_ns_per_m` sizes its damper, `lateral_soil_damping_n` and
`longitudinal_soil_damping_n` apply it. Both vanish in steady slip, so the force laws stay
exact there.

Relaxation length (`contact_relaxation_length_m`). In the brush model the relaxation length is
about the half length a of the contact patch (Pacejka §7.2.1, rigid carcass: sigma = a); for a
rigid wheel in soil the shear builds up along the front arc from the entry angle
theta_1 = acos(1 - z/r) to the bottom (Wong, Theory of Ground Vehicles, 4th ed., Ch. 5, the
shear displacement j(theta) of a rigid wheel), so sigma = r theta_1. The same follows from the
standstill stiffness: a patch of shear length L held still has stiffness F_max/K, the relaxation
state C/sigma with C = F_max L/(2K) (Lindgren Eq. 23), equal when sigma = L/2.

Motion resistance (`rut_resistance_n`, `rut_resistance_vector_n`). Compaction resistance is the
work of cutting a rut per unit distance (Bekker; Wong Ch. 5): it is rate-independent, a wheel
must cut its rut however slowly it moves, so it acts like Coulomb friction: full magnitude R
against the motion, and at rest whatever holds the wheel still, bounded by R. It is written as
a single-state elasto-plastic friction element (Dupont, Hayward, Armstrong and Altpeter,
"Single state elastoplastic friction models", IEEE TAC 47(5), 2002): the state is the
pre-sliding (elastic) displacement, bounded by a small stick length x_0; the force is
R x/x_0 plus a damper, capped at R; in sliding x sits at +-x_0 and the force is exactly R
against the motion at every speed. A vehicle held by less than R does not drift (the state
stays inside the band), so a stalled vehicle stalls instead of creeping, and the force never
exceeds R, so it cannot push a parked vehicle by more than the stick length.
"""

from __future__ import annotations

import math

import slipenv.terramechanics._laws as _laws

__all__ = [
    "contact_relaxation_length_m",
    "critical_damping_ns_per_m",
    "lateral_soil_damping_n",
    "longitudinal_soil_damping_n",
    "relax_slip",
    "resistance_along_travel_n",
    "rut_resistance_n",
    "rut_resistance_vector_n",
]


def relax_slip(slip: float, tan_beta: float, rim_speed_mps: float, long_speed_mps: float,
               lat_speed_mps: float, step_per_length: float, forward_reference: bool = False
               ) -> tuple[float, float, float, float]:
    """One backward-Euler step of the slip relaxation ODE (Pacejka §7.2.1; module docstring).

    With h = dt/sigma: s' = (s + h (r omega - v))/(1 + h V), b' = (b + h v_lat)/(1 + h V_b),
    each clipped to [-1, 1] (full slip either way, as `contact.slip_ratio`).

    Parameters
    ----------
    slip, tan_beta : float
        State at the start of the step: slip ratio s [-] and tan of the slip angle b [-].
    rim_speed_mps : float
        r_eff omega [m/s], the speed the wheel would travel at without slip.
    long_speed_mps, lat_speed_mps : float
        v, v_lat [m/s]: the contact point's velocity along the wheel's heading and to its left.
    step_per_length : float
        h = dt/sigma [s/m]: time step over relaxation length.
    forward_reference : bool
        False (Janosi, linear laws): V_b = V, tan_beta relaxes to v_lat/V, along the sliding
        velocity. True (Reina's law): V_b = max(|v|, |v_lat|), tan_beta relaxes to v_lat/|v|
        (Reina Eq. 4) up to 45 deg and to +-1 beyond.

    Returns
    -------
    slip, tan_beta : float
        The state at the end of the step.
    reference_speed_mps : float
        V = max(|r omega|, |v|, |v_lat|) [m/s], the speed the lengthwise damper fades with.
    lateral_reference_speed_mps : float
        V_b [m/s], the leak speed of tan_beta, the speed the side damper fades with.
    """
    return _laws.relax_slip(slip, tan_beta, rim_speed_mps, long_speed_mps, lat_speed_mps,
                            step_per_length, forward_reference)


def critical_damping_ns_per_m(slip_stiffness_n: float, relaxation_m: float, mass_kg: float,
                              damping_ratio: float, max_ns_per_m: float) -> float:
    """Damper c = min(2 zeta sqrt(k m), c_max) [N s/m] of the soil spring k = C/sigma.

    The relaxation state held still is a spring of stiffness k = C/sigma [N/m] carrying the
    mass m; c is `damping_ratio` zeta times its critical damping 2 sqrt(k m) (LuGre's sigma_1,
    Canudas de Wit et al. 1995), capped at `max_ns_per_m` (an explicit damper is stable below
    m/dt).

    Parameters
    ----------
    slip_stiffness_n : float
        C = dF/ds at s = 0 [N per unit slip], >= 0.
    relaxation_m : float
        Relaxation length sigma [m], > 0.
    mass_kg : float
        Mass the spring moves [kg].
    damping_ratio : float
        zeta [-], >= 0.
    max_ns_per_m : float
        Cap on c [N s/m].
    """
    return _laws.critical_damping_ns_per_m(slip_stiffness_n, relaxation_m, mass_kg,
                                           damping_ratio, max_ns_per_m)


def lateral_soil_damping_n(tan_beta_change: float, reference_speed_mps: float,
                           damping_n: float, fade_speed_mps: float) -> float:
    """Side damper on the lateral shear-deformation rate, faded with speed [N].

    F = -d delta(tan_beta)/(1 + (V_b/v_f)^4), with d = c sigma/dt [N per unit change of the state
    in one step] so that d delta(tan_beta) = c sigma d(tan_beta)/dt: LuGre's sigma_1 term on
    the deformation rate (Canudas de Wit et al. 1995). Zero in steady side slip (the state does
    not change), about full at crawling speed, where a turning tracked vehicle otherwise rocks at
    several Hz, and faded out (1/(1 + (V_b/v_f)^4)) where the relaxation leak V_b/sigma already
    damps the spring (Canudas de Wit et al. 2003 fade sigma_1 with speed too).

    Parameters
    ----------
    tan_beta_change : float
        Change of the tan_beta state over the step [-].
    reference_speed_mps : float
        V_b [m/s], the lateral state's leak speed (from `relax_slip`).
    damping_n : float
        d [N per unit tan_beta change per step], >= 0.
    fade_speed_mps : float
        v_f [m/s], > 0.
    """
    return _laws.lateral_soil_damping_n(tan_beta_change, reference_speed_mps, damping_n,
                                        fade_speed_mps)


def longitudinal_soil_damping_n(rim_speed_mps: float, long_speed_mps: float,
                                reference_speed_mps: float, damping_ns_per_m: float,
                                low_speed_mps: float) -> float:
    """Lengthwise damper on the sliding speed r omega - v, only near standstill [N].

    F = (1 - V/v_low) c (r omega - v) for V < v_low, else 0. The relaxation state alone is an
    undamped spring at standstill, and its speed-dependent leak ratchets an oscillating parked
    vehicle downhill (Pacejka §7.2); this damps it. Zero at and above v_low, so it never alters
    driving forces (when rolling, a damper at the patch would act on the wheel's small spin
    inertia and an explicit one would destabilise it), and zero when the wheel does not slide.

    Parameters
    ----------
    rim_speed_mps, long_speed_mps : float
        r omega and v [m/s].
    reference_speed_mps : float
        V [m/s] (from `relax_slip`).
    damping_ns_per_m : float
        c [N s/m] (`critical_damping_ns_per_m`).
    low_speed_mps : float
        v_low [m/s], > 0.
    """
    return _laws.longitudinal_soil_damping_n(rim_speed_mps, long_speed_mps, reference_speed_mps,
                                             damping_ns_per_m, low_speed_mps)


def resistance_along_travel_n(resistance_n: float, long_speed_mps: float,
                              ramp_speed_mps: float) -> float:
    """Signed motion resistance R clip(v/v_r, -1, 1) [N], to apply against the heading.

    Resistance opposes travel and vanishes at standstill (it is not static friction); the
    linear ramp below v_r keeps it continuous (and explicit-stable) through zero and exact
    above it.

    Parameters
    ----------
    resistance_n : float
        Magnitude R >= 0 [N] (compaction + rolling, from the force model).
    long_speed_mps : float
        v [m/s] along the wheel's heading.
    ramp_speed_mps : float
        v_r [m/s], > 0.
    """
    ramp = long_speed_mps / ramp_speed_mps
    return resistance_n * (1.0 if ramp > 1.0 else (-1.0 if ramp < -1.0 else ramp))


def contact_relaxation_length_m(radius_m: float, sinkage_m: float, min_length_m: float) -> float:
    """Relaxation length sigma = r acos(1 - z/r) of a rigid wheel sunk z [m], >= the floor.

    The front contact arc r theta_1, theta_1 = acos(1 - z/r) the entry angle (Wong, Theory of
    Ground Vehicles, Ch. 5), about half the contact patch: the brush model's sigma = a
    (Pacejka §7.2.1; module docstring). z is clipped to [0, r].

    Parameters
    ----------
    radius_m : float
        Wheel radius r [m], > 0.
    sinkage_m : float
        Sinkage z [m] (Bekker, `bekker.wheel_sinkage_m`).
    min_length_m : float
        Floor [m] (on rigid ground z -> 0 and the arc vanishes).
    """
    ratio = sinkage_m / radius_m
    ratio = 0.0 if ratio < 0.0 else (1.0 if ratio > 1.0 else ratio)
    arc = radius_m * math.acos(1.0 - ratio)
    return arc if arc > min_length_m else min_length_m


def rut_resistance_n(resistance_n: float, state: float, displacement_m: float,
                     speed_mps: float, stick_m: float,
                     damping_ns_per_m: float) -> tuple[float, float]:
    """Rate-independent motion resistance along one axis: an elasto-plastic Coulomb element.

    Dupont et al. 2002 (module docstring) with a linear pre-sliding branch: the state
    u = x/x_0 in [-1, 1] moves with the displacement, u' = clip(u + dx/x_0, -1, 1); the
    resistance is r = clip(R u' + c v, -R, R), to be applied against the axis (force -r).
    Sliding (|u'| = 1 and v of its sign): r = R sign(v) at any speed, the rate-independent
    compaction resistance. At rest under a push below R the state stays inside the band: the
    element holds, with |r| <= R, and the body does not creep.

    Parameters
    ----------
    resistance_n : float
        R >= 0 [N] (compaction + rolling, from the force model).
    state : float
        u at the start of the step [-].
    displacement_m : float
        dx = v dt [m] over the step along the axis.
    speed_mps : float
        v [m/s] along the axis (for the damper).
    stick_m : float
        x_0 [m], > 0: the pre-sliding displacement at which R is reached.
    damping_ns_per_m : float
        c [N s/m] of the pre-sliding damper (`critical_damping_ns_per_m` of k = R/x_0).

    Returns
    -------
    resistance_n : float
        r [N], signed along the axis (apply -r).
    state : float
        u' [-].
    """
    return _laws.rut_resistance_n(resistance_n, state, displacement_m, speed_mps, stick_m,
                                  damping_ns_per_m)


def rut_resistance_vector_n(resistance_n: float, state: tuple[float, float, float],
                            velocity_mps: tuple[float, float, float], dt_s: float,
                            stick_m: float, damping_ns_per_m: float
                            ) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """`rut_resistance_n` in the contact plane: the resistance of an ideal swivel castor.

    A castor swivels to its travel, so its rut runs along its contact velocity, whatever the
    chassis heading: the state u (a vector, |u| <= 1) follows the displacement v dt/x_0 and is
    renormalised to the unit disc, the resistance r = R u + c v is capped at |r| <= R. In
    sliding r = R v/|v|: the drag is along the castor's travel (physics-notes §1, defect 4).

    Parameters
    ----------
    resistance_n : float
        R >= 0 [N].
    state : tuple of 3 floats
        u at the start of the step (world frame) [-].
    velocity_mps : tuple of 3 floats
        Velocity of the contact point in the contact plane (world frame) [m/s].
    dt_s : float
        Step [s].
    stick_m, damping_ns_per_m : float
        x_0 [m] and c [N s/m] as in `rut_resistance_n`.

    Returns
    -------
    resistance_n : tuple of 3 floats
        r [N] (apply -r).
    state : tuple of 3 floats
        u'.
    """
    return _laws.rut_resistance_vector_n(resistance_n, state, velocity_mps, dt_s, stick_m,
                                         damping_ns_per_m)
