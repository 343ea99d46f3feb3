"""Find what the simulation gets wrong about a measured log, name the cause, fix the model.

The workflow of DESIGN §5 (``slipenv diagnose LOG_DIR --json PATH --report DIR``):

1. **Replay** (``segments.py``, ``replay.py``): the log is cut into segments that start on a
   ground-truth pose; each is replayed from there by integrating the logged wheel motion with
   the nominal kinematics of ``meta.json`` (radii, track width, counts per radian, the
   declared slope). ``simreplay.py`` replays the same segments in PyBullet for the report.
2. **Show** (``report.py``, ``plots.py``): trajectory overlay, residuals over time and against
   torque, yaw rate, roll, pitch, speed and position, NIS and whiteness of the segment ends.
3. **Name the cause** (``effects.py``, ``fit.py``, ``select.py``): every effect of the
   vocabulary the data can test is fitted by nonlinear least squares (cluster-robust standard
   errors) in K-fold cross-validation, and compared with the nominal model on held-out
   segments; an effect counts only if its gain is significant, large and material.
4. **Extend** (``extension.py``): ``apply_model(config, report)`` carries the named effects
   with their fitted parameters into the simulated world (``gymnasium.make(..., model=...)``).
5. **Measure the gain**: held-out error before and after, in the JSON report.

``proprio.py`` covers logs without ground truth (yaw rate against wheel speeds); ``synth.py``
generates logs with a hidden effect from the physics, for the tests and
``benchmarks/diagnose_hit_rate.py``.

Entry points: ``slipenv.diagnose.cli.diagnose(logs, where)``, ``cli.load_logs(path)``,
``extension.apply_model(config, model)``, ``synth.generate(seed, effect, kind)``.
"""
