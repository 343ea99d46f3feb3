"""Yamauchi et al. re-run: slip-compensated odometry and slip-angle feed-forward on sand slopes
(``slipenv reproduce yamauchi``).

Yamauchi, Nagatani, Hashimoto and Fujino, "Slip compensated odometry for a tracked vehicle
when rotating on a loose weak slope": track slip kinematics (Eq. 1-7), Endo's slip-ratio
relation (Eq. 8), a slip-angle regression on roll, angular displacement and rotation radius
(Eq. 9) and a path-following law with slip-angle feed-forward (§3, Eq. 9-10).

By default the Wong-Chiang track model (``tracked_patako_wong_chiang``) on the paper's loose,
cohesionless Toyoura sand (``toyoura_sand``), the world of ``slipenv/TrackedSlopeCircle-v0``,
repeats the paper's rotation runs
(:mod:`.rotation`), identifies Endo's n and Eq. 9 from them (:mod:`.slips`), replays the
odometries on held-out runs (:mod:`.odometry`) and drives the 15° circle with both laws
(:mod:`.circle`), each episode one :func:`slipenv.rollout.rollout`. The paper's numbers are in
:mod:`.paper`, the run plan and what was calibrated on which measurement in :mod:`.settings`.
:func:`run` (:mod:`.experiment`) prints the paper-vs-simulation table (:mod:`.report`), saves
the figures (:mod:`.plots`), the JSON and, with ``docs_dir``, the results page (:mod:`.docs`,
``docs/reproductions/yamauchi.md``), where the measured numbers, the departure from the paper
and what limits the result are discussed. The fitted model the tracked env observes with is
version-controlled data (:mod:`.model_file`), fitted in that default world. Other worlds
(``--vehicle tracked_patako``, the per-wheel track law; ``--soil dry_sand``) write their own
pages (``DIR/yamauchi_per_wheel.md``, ``DIR/yamauchi_<world>.md``).
"""

from .circle import LimitObservation, circle_episode, mean_episodes
from .experiment import run
from .model_file import MODEL_FILE, save_model
from .odometry import TrueSlipAngle, TrueSlipOdometry, odometry_errors, replay
from .paper import PAPER
from .rotation import InfoRecorder, RotationRun, TurnLimit, collect_runs, rotation_run, split_runs
from .settings import ENV_ID, FULL, QUICK, STEER_ON, TARGETS, Settings
from .slips import fit_n, run_slips, slip_run
from .world import make_world

__all__ = [
    "ENV_ID",
    "FULL",
    "MODEL_FILE",
    "PAPER",
    "QUICK",
    "STEER_ON",
    "TARGETS",
    "InfoRecorder",
    "LimitObservation",
    "RotationRun",
    "Settings",
    "TrueSlipAngle",
    "TrueSlipOdometry",
    "TurnLimit",
    "circle_episode",
    "collect_runs",
    "fit_n",
    "make_world",
    "mean_episodes",
    "odometry_errors",
    "replay",
    "rotation_run",
    "run",
    "run_slips",
    "save_model",
    "slip_run",
    "split_runs",
]
