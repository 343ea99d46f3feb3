"""Find what the simulation gets wrong about a measured log, name the cause, fix the model.

The workflow of DESIGN §5 (``slipenv diagnose LOG_DIR --json PATH --report DIR``):

1. **Replay** (``segments.py``, ``replay.py``): the log is cut into segments that start on a
   ground-truth pose; each is replayed from there by integrating the logged wheel motion with
   the nominal kinematics of ``meta.json`` (radii, track width, counts per radian, the
   declared slope). ``simreplay.py`` replays the same segments in PyBullet for the report.
2. **Show** (``report.py``, ``plots.py``): trajectory overlay, residuals over time and against
   torque, yaw rate, roll, pitch, speed and position, NIS and whiteness of the segment ends.
3. **Name the cause** (``effects/``, ``fit.py``, ``select.py``): every effect of the
   vocabulary the data can test is fitted by nonlinear least squares (cluster-robust standard
   errors) in K-fold cross-validation, and compared with the nominal model on held-out
   segments — and, for slow drifts, on held-out blocks in time replayed whole
   (``horizon.py``); an effect counts only if its gain is significant, large and material;
   further effects join by forward selection ("also"). Each
   effect is one module of ``effects/``: its parameters, replay term, fit, how it is applied
   to the simulation and how the tests hide it; the generic code iterates over the registry.
4. **Extend** (``extension.py``): ``apply_model(config, report)`` returns a new env config
   with the named effects and their fitted parameters carried into the simulated world, for
   ``gymnasium.make(env_id, config=...)``; ``make_env(env_id, report)`` does both.
5. **Measure the gain**: held-out error before and after, in the JSON report; for geometric
   causes the calibration a diff-drive controller takes (``calibration.py``) and a whole-log
   dead-reckoning plot before/after.

``proprio.py`` covers logs without ground truth (yaw rate against wheel speeds); ``synth.py``
generates logs with a hidden effect from the physics, ``kinematic.py`` kinematic logs with
hidden geometry and correlated wheel-speed noise, for the tests and
``benchmarks/diagnose_hit_rate.py``.

Entry points: ``slipenv.diagnose.cli.diagnose(logs, where)``, ``cli.load_logs(path)``,
``apply_model(config, report)``, ``make_env(env_id, report)``,
``synth.generate(seed, effect, kind)``.
"""

from slipenv.diagnose.extension import apply_model, make_env

__all__ = ["apply_model", "make_env"]
