"""The compiled track model equals its own text run as plain Python.

``slipenv.terramechanics.track`` is compiled with numba from its one text; ``NUMBA_DISABLE_JIT=1``
runs the same functions as plain Python (the oracle). Here one composed substep
(`track.track_substep`) runs both ways on the same random fields and inputs, over every
upwinding case of the shear field (belt forward, reversing, at rest) and of the side walls
(ground moving ahead, back, at rest), with each shear law (`track.SHEAR_LAWS`): every state
and output agrees to 1e-12 relative. The two
differ only in rounding (numba's libm calls against Python's); a wrong index, sign or sweep
direction in the compiled loops would be off by far more.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from slipenv.terramechanics.track import SETTING_NAMES, SHEAR_LAWS, SOIL_ROWS, track_substep

REL = 1e-12
NT, NC, NW = 2, 8, 4
STATE = ("j", "e", "walls", "out", "sinkage_m", "sums", "compaction_n")

# (belt speeds, track ground speeds) per case [m/s]: forward, reversing, at rest, mixed
CASES = {
    "both_forward": ([0.06, 0.05], [0.05, 0.04]),
    "pivot": ([0.06, -0.05], [0.01, -0.02]),
    "reversing": ([-0.05, -0.06], [-0.04, -0.05]),
    "at_rest": ([0.0, 5e-4], [0.0, -5e-5]),
    "belts_stopped_sliding": ([0.0, 0.0], [0.02, -0.03]),
}


def _inputs(case: str, law: str = "resultant") -> dict:
    rng = np.random.default_rng(sorted(CASES).index(case))
    u, vx = CASES[case]
    spread = rng.uniform(0.0, 1.0, (NT * NC, NW))
    spread /= spread.sum(axis=0)
    soil = {"width_m": [0.11, 0.12], "inv_cell_area_m2": [1 / (0.11 * 0.03), 1 / (0.12 * 0.03)],
            "k_c": [990.0, 1200.0], "k_phi": [1.5e6, 1.0e6], "n_exp": [1.1, 0.9],
            "cohesion_pa": [1040.0, 0.0], "tan_phi": [0.53, 0.7],
            "shear_modulus_m": [0.025, 0.01], "friction_angle_rad": [0.49, 0.61]}
    settings = {"dx_m": 0.03, "dt_s": 1 / 240, "direction_length_m": 1e-3,
                "damping_ratio": 1.0, "cell_mass_kg": 0.9, "unit_weight_n_m3": 13.1e3,
                "max_wall_height_m": 0.1, "shear_law": float(SHEAR_LAWS.index(law)),
                "longitudinal_modulus_ratio": 0.8, "lateral_modulus_ratio": 1.5}
    return {
        "load_n": rng.uniform(0.0, 40.0, NW), "belt_speed_mps": np.array(u),
        "track_speed_mps": np.array(vx), "lateral_speed_mps": rng.normal(0.0, 0.02, NT),
        "yaw_rate_rad_s": float(rng.normal(0.0, 0.2)),
        "slip_sinkage": rng.uniform(1.0, 2.0, NT), "deformable": np.array([1.0, 1.0]),
        "spread": spread, "reduce": rng.uniform(-1.0, 1.0, (NW + 2 * NT, NT * NC)),
        "x_cell_m": np.tile(0.12 - 0.03 * (np.arange(NC) + 0.5), (NT, 1)),
        "soil": np.array([soil[k] for k in SOIL_ROWS]),
        "settings": np.array([settings[k] for k in SETTING_NAMES]),
        "j": rng.normal(0.0, 0.01, (2, NT, NC + 1)), "e": rng.normal(0.0, 1e-3, (2, NT, NC)),
        "walls": np.abs(rng.normal(0.0, 1e-3, (2, 2, NT, NC))) * np.array([1.0, 1e-3])[
            :, None, None, None],
        "out": np.zeros((6, NT, NC)), "sinkage_m": np.zeros((NT, NC)),
        "sums": np.zeros((NW + 2 * NT, 6)), "compaction_n": np.zeros(NT),
    }


def _run(case: str, law: str = "resultant") -> dict:
    """The substep on `case`'s inputs with shear law `law` (three substeps, so the swept fields
    feed back)."""
    a = _inputs(case, law)
    for _ in range(3):
        track_substep(*a.values())
    return {k: a[k].tolist() for k in STATE}


_SCRIPT = """
import json, sys
from tests.terramechanics.test_track_compiled import CASES, SHEAR_LAWS, _run
print(json.dumps({f"{case}/{law}": _run(case, law) for case in CASES for law in SHEAR_LAWS}))
"""


@pytest.fixture(scope="module")
def plain_python() -> dict:
    """Every case run by the same text with numba's compilation off."""
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    out = subprocess.run([sys.executable, "-c", _SCRIPT], check=True, capture_output=True,
                         text=True, env=env, cwd=os.path.dirname(os.path.dirname(
                             os.path.dirname(os.path.abspath(__file__)))))
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("law", SHEAR_LAWS)
@pytest.mark.parametrize("case", sorted(CASES))
def test_the_compiled_substep_equals_its_text_run_as_plain_python(case, law, plain_python):
    compiled = _run(case, law)
    for name in STATE:
        got, want = np.array(compiled[name]), np.array(plain_python[f"{case}/{law}"][name])
        scale = max(np.abs(want).max(), 1e-300)
        np.testing.assert_allclose(got, want, rtol=0.0, atol=REL * scale, err_msg=name)
    assert np.abs(np.array(compiled["out"])).max() > 0.0  # the case exercised the forces
    if law != "resultant":  # the law reached the cells
        assert compiled["out"] != _run(case, "resultant")["out"]
