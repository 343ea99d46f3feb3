"""The numbers Reina, Ishigami, Nagatani and Yoshida report ("Odometry correction using visual
slip angle estimation for planetary exploration rovers", Advanced Robotics 24, 2010), each with
its table. :data:`PAPER` has the layout of the experiment's JSON ``"metrics"``.
"""

from __future__ import annotations

SLIP_ANGLE_RMS_DEG = {"sideways": 1.4, "mounds": 1.6}
"""E_β, r.m.s. error of FTrace's slip angle against ground truth [deg] (Table 5)."""

SLIP_RATIO_RMS = {"sideways": 0.06, "mounds": 0.10}
"""E_sx, r.m.s. error of the slip ratio s_x(β̂) of Eq. 12 against ground truth (Table 5)."""

FINAL_ERROR_M = {
    "sideways": {"plain": 2.84, "compass": 2.50, "scomp": 0.14},
    "mounds": {"plain": 2.90, "compass": 1.98, "scomp": 0.41},
}
"""Eq. 18 final position errors [m] of plain, compass-enhanced and sComp odometry (Table 5),
over about 7 m (sideways climb) and 13 m (mounds)."""

DISTANCE_M = {"sideways": 7.0, "mounds": 13.0}
"""Travel distances [m] (§4.3.1, §4.3.2)."""

FTRACE = {"frames": 15016, "false_positive": 0.003, "false_negative": 0.03,
          "misidentification": 0.01}
"""Table 4 over both sets (2560 + 12 456 frames): the rates are the paper's upper bounds as
stated in §4.1 (< 0.3 %, < 3 %, < 1 %; set B alone: 0.2 %, 2.7 %, 0.8 %)."""

PAPER = {
    "slip_angle_rms_deg": SLIP_ANGLE_RMS_DEG,
    "slip_ratio_rms": SLIP_RATIO_RMS,
    "final_error_m": FINAL_ERROR_M,
    "ftrace": FTRACE,
}
