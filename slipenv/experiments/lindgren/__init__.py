"""Lindgren et al. §5 re-run in simulation (``slipenv reproduce lindgren``).

Lindgren, Hague, Probert Smith and Marchant, "Relating torque and slip in an odometric model
for an autonomous agricultural vehicle": a 2WD farm vehicle's navigation EKF with a linear
torque/slip law (Eq. 24) in the odometric observation (Eq. 32-41), judged by four sensor
schemes on 4 m circles (Tables 1-3, Fig. 4-6) and by the final error after a laser cut on
straights with 180° turns (Fig. 7).

Each drive of ``slipenv/FarmField-v0`` records its raw sensor frames (:mod:`.recording`), and
the EKF schemes run offline over the same frames (:mod:`.filters`), as in the paper; the
statistics are in :mod:`.metrics`, the paper's numbers in :mod:`.paper`, the settings and
why they have their values in :mod:`.settings`. Both experiments run in two blocks on the same
paths and seeds: the headline, in the world the filter does not assume (the curved
Janosi/Okello law, the estimator's default process noise, per-wheel radii for the no-slip
filter measured as the paper's operators did, :mod:`.calibration`), and an ablation with the
filter's own linear law in the world; :mod:`.regime` places the field's operating point on the
paper's torque/slip curve. :func:`run` (:mod:`.experiment`) prints the
paper-vs-simulation table (:mod:`.report`), saves the figures (:mod:`.plots`), the JSON and,
with ``docs_dir``, the results page (:mod:`.docs`, ``docs/reproductions/lindgren.md``), where
the measured numbers and the discussion of what differs from the paper live.
"""

from .calibration import calibrate, effective_radius_m
from .experiment import run
from .filters import FilterRun, pose_errors, run_filter
from .metrics import circles_metrics, dropout_experiment
from .paper import PAPER
from .recording import FrameRecorder, Recording, record
from .regime import curve_position, okello_bracket, operating_point
from .settings import (
    ABLATION,
    BLOCKS,
    FIELD_NOISE,
    FILTER,
    FULL,
    HEADLINE,
    QUICK,
    SLIP_SCHEMES,
    Config,
    Setting,
    Variant,
)

__all__ = [
    "ABLATION",
    "BLOCKS",
    "FIELD_NOISE",
    "FILTER",
    "FULL",
    "HEADLINE",
    "PAPER",
    "QUICK",
    "SLIP_SCHEMES",
    "curve_position",
    "okello_bracket",
    "operating_point",
    "Config",
    "Setting",
    "Variant",
    "calibrate",
    "effective_radius_m",
    "FilterRun",
    "FrameRecorder",
    "Recording",
    "circles_metrics",
    "dropout_experiment",
    "pose_errors",
    "record",
    "run",
    "run_filter",
]
