"""Reina et al. re-run: FTrace's visual slip angle and sComp odometry on sand (``slipenv
reproduce reina``).

Reina, Ishigami, Nagatani and Yoshida, "Odometry correction using visual slip angle estimation
for planetary exploration rovers" (Advanced Robotics 24, 2010), §4: the rover driven straight at
about 8 cm/s up a sandy slope with transverse inclination (about 7 m) and across sandy mounds
(about 13 m), its slip angle from the wheel trace in a rear camera (FTrace) and its odometry
corrected for both slips (sComp).

:mod:`.drive` runs each test in ``slipenv/Configurable-v0`` with ``estimator="scomp"`` (one
:func:`slipenv.rollout.rollout` per drive), :mod:`.analysis` computes the ground truth, fits
s_x(β) (Eq. 12) on test 1, replays plain, compass-enhanced and sComp odometry and scores FTrace
(Table 4); :func:`run` (:mod:`.experiment`) prints the paper-vs-simulation table
(:mod:`.report`), saves the figures (:mod:`.plots`), the JSON and, with ``docs_dir``, the page
``docs/reproductions/reina.md`` (:mod:`.docs`). The paper's numbers are in :mod:`.paper`.
"""

from .drive import ENV_ID, Drive, DriveRecorder, HeadingHold, drive, env_kwargs
from .experiment import run
from .paper import PAPER
from .settings import QUICK, TARGETS, TESTS, Settings

__all__ = [
    "ENV_ID",
    "PAPER",
    "QUICK",
    "TARGETS",
    "TESTS",
    "Drive",
    "DriveRecorder",
    "HeadingHold",
    "Settings",
    "drive",
    "env_kwargs",
    "run",
]
