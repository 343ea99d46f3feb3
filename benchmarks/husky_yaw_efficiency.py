"""The simulated Husky's skid-steer yaw efficiency against BorealTC's sandy loam.

BorealTC (docs/real_data.md, `slipenv diagnose` proprioceptive analysis) measures the yaw
efficiency eta = (gyro yaw rate) / ((v_R - v_L)/B), with v = r omega from the wheel encoders and
the nominal track B = 0.555 m: eta = 0.567 +- 0.007 pooled over 14 runs on sandy loam. This
script drives the simulated Husky (Janosi force law) on flat ground at a set of commanded
(v, omega), measures eta the same way (true yaw rate against the wheels' true spin rates, nominal
radius, B = 0.555 m) and pools it as the real data were: the least-squares slope through the
origin of yaw rate against (v_R - v_L)/B over all steady samples.

Soils: ``field_loam`` is Wong's sandy loam (the soil BorealTC's terrain is named after);
``loose_sand`` is the soil of HuskySand-v0. Run from the repository root::

    python benchmarks/husky_yaw_efficiency.py [--soils field_loam loose_sand]
        [--lateral-stiffness-ratio 1.0] [--json PATH]
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from slipenv.envs.factory import make_force_model, make_soil_map, make_vehicle
from slipenv.sim.simulator import Simulator
from slipenv.terrain.terrain import TerrainSpec
from slipenv.terramechanics.models import JanosiForceModel
from slipenv.vehicles.kinematics import twist_to_commands

BOREALTC_TRACK_M = 0.555  # nominal Husky track used by the BorealTC analysis (docs/real_data.md)
BOREALTC_SANDY_LOAM_ETA = 0.567  # pooled, 14 runs (docs/real_data.md)
# (v [m/s], commanded omega [rad/s]): BorealTC's Husky drives at 0.2-1 m/s with turns of
# every radius; the set spans nominal differentials (v_R - v_L)/B of 0.2-1.0 rad/s.
COMMANDS = ((0.5, 0.2), (0.5, 0.5), (0.3, 0.8), (0.8, 0.4), (0.2, 1.0))


def measure(soil: str, commands=COMMANDS, seconds: float = 6.0, settle_s: float = 2.0,
            lateral_stiffness_ratio: float = 1.0) -> dict:
    """eta per command and pooled for the Husky on ``soil`` (flat, Janosi law with the given
    lateral anisotropy, `JanosiForceModel`)."""
    spec = make_vehicle("husky")
    model = make_force_model(
        lambda g: JanosiForceModel(g, lateral_stiffness_ratio=lateral_stiffness_ratio), spec)
    sim = Simulator(spec, TerrainSpec(), model, make_soil_map(soil, None))
    r = spec.wheel_radius_nominal_m
    left = [i for i, c in enumerate(spec.channels) if c in ("left",)]
    right = [i for i, c in enumerate(spec.channels) if c in ("right",)]
    rows, xs, ys = [], [], []
    try:
        for v, omega in commands:
            sim.reset(0.0, 0.0, 0.0)
            speeds, steer = twist_to_commands(spec, v, omega)
            n = int(round(seconds / sim.control_dt_s))
            n0 = int(round(settle_s / sim.control_dt_s))
            truths = [sim.step(speeds, steer) for _ in range(n)][n0:]
            angles = np.array([t.channel_angle_rad for t in truths])
            t = np.array([tr.t_s for tr in truths])
            rates = np.gradient(angles, t, axis=0)
            v_l = r * rates[:, left].mean(axis=1)
            v_r = r * rates[:, right].mean(axis=1)
            nominal = (v_r - v_l) / BOREALTC_TRACK_M
            yaw = np.array([tr.yaw_rate_rad_s for tr in truths])
            rows.append({"v_mps": v, "omega_cmd_rad_s": omega,
                         "nominal_rad_s": float(nominal.mean()),
                         "yaw_rate_rad_s": float(yaw.mean()),
                         "eta": float(yaw.mean() / nominal.mean())})
            xs.append(nominal)
            ys.append(yaw)
    finally:
        sim.close()
    x, y = np.concatenate(xs), np.concatenate(ys)
    return {"soil": soil, "runs": rows, "eta_pooled": float(x @ y / (x @ x))}


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--soils", nargs="+", default=["field_loam", "loose_sand"])
    parser.add_argument("--lateral-stiffness-ratio", type=float, default=1.0,
                        help="kappa of the Janosi law's lateral anisotropy (Reina: 3.6)")
    parser.add_argument("--json", default=None, help="write the figures to this JSON file")
    args = parser.parse_args(argv)
    kappa = args.lateral_stiffness_ratio
    out = {"borealtc_sandy_loam_eta": BOREALTC_SANDY_LOAM_ETA, "track_m": BOREALTC_TRACK_M,
           "lateral_stiffness_ratio": kappa,
           "soils": [measure(s, lateral_stiffness_ratio=kappa) for s in args.soils]}
    print(f"BorealTC sandy loam (real): eta = {BOREALTC_SANDY_LOAM_ETA:.3f}")
    print(f"{'soil':<12} {'v':>5} {'w_cmd':>6} {'(vR-vL)/B':>10} {'yaw rate':>9} {'eta':>6}")
    for res in out["soils"]:
        for row in res["runs"]:
            print(f"{res['soil']:<12} {row['v_mps']:5.2f} {row['omega_cmd_rad_s']:6.2f} "
                  f"{row['nominal_rad_s']:10.3f} {row['yaw_rate_rad_s']:9.3f} "
                  f"{row['eta']:6.3f}")
        print(f"{res['soil']:<12} pooled eta = {res['eta_pooled']:.3f} "
              f"(real sandy loam {BOREALTC_SANDY_LOAM_ETA:.3f})")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(out, fh, indent=2)
    return out


if __name__ == "__main__":
    main()
