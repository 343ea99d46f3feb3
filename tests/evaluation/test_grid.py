"""Grid files: cells of env ids × variations × policies × seeds, validated before any work."""

from __future__ import annotations

import pytest

from slipenv.evaluation.grid import load_grid

GOOD = """
env_ids: [slipenv/TrackedSlopeCircle-v0, slipenv/HuskySand-v0]
policies: [baseline, stanley]
seeds: {start: 3, count: 2}
soils: [toyoura_sand, loose_sand]
slopes_deg: [5, 10]
env_kwargs: {max_episode_s: 20}
max_steps: 50
"""


def _grid(tmp_path, text: str):
    path = tmp_path / "grid.yaml"
    path.write_text(text)
    return path


def test_cells_are_the_product_of_every_axis_in_grid_order(tmp_path):
    cells = load_grid(_grid(tmp_path, GOOD))
    assert len(cells) == 2 * (2 * 2) * 2 * 2
    first = cells[0]
    assert (first.env_id, first.variation, first.policy, first.seed) == (
        "slipenv/TrackedSlopeCircle-v0", "soil=toyoura_sand,slope=5deg", "baseline", 3)
    assert first.env_kwargs["soil"] == "toyoura_sand" and first.max_steps == 50
    assert first.env_kwargs["max_episode_s"] == 20
    # The slope tilts the preset's own terrain: the tracked env keeps its downhill direction.
    assert first.env_kwargs["terrain"]["slope_deg"] == 5.0
    assert first.env_kwargs["terrain"]["downhill_azimuth_deg"] == -90.0
    assert len({c.key for c in cells}) == len(cells)


def test_cell_keys_are_stable_across_loads_and_change_with_the_cell(tmp_path):
    a = load_grid(_grid(tmp_path, GOOD))
    b = load_grid(_grid(tmp_path, GOOD.replace("max_steps: 50", "max_steps: 51")))
    assert [c.key for c in a] == [c.key for c in load_grid(_grid(tmp_path, GOOD))]
    assert not {c.key for c in a} & {c.key for c in b}


@pytest.mark.parametrize(("edit", "needle"), [
    (("policies:", "policys:"), "unknown key 'policys'; did you mean 'policies'?"),
    (("HuskySand-v0", "HuskySnad-v0"), "env_ids: unknown slipenv env id"),
    (("stanley", "stanly"), "policies: --policy: unknown policy 'stanly'"),
    (("loose_sand", "loose_snad"), "unknown soil 'loose_snad'; did you mean 'loose_sand'?"),
    (("max_episode_s: 20", "max_episode_sec: 20"), "unknown slipenv option 'max_episode_sec'"),
    (("{start: 3, count: 2}", "[0, 0]"), "seeds repeat"),
    (("max_steps: 50", "max_steps: -1"), "max_steps must be an integer >= 1"),
    (("seeds: {start: 3, count: 2}", ""), "missing required key(s) seeds"),
    # a path value is checked with the config, before any cell runs (it was a cell's error)
    (("{max_episode_s: 20}", "{max_episode_s: 20, path_kwargs: {speed_mps: -1}}"),
     "speed_mps must be > 0"),
])
def test_a_grid_with_a_typo_is_an_error_naming_the_file_and_the_key(tmp_path, edit, needle):
    path = _grid(tmp_path, GOOD.replace(*edit))
    with pytest.raises(ValueError) as info:
        load_grid(path)
    assert needle in str(info.value) and str(path) in str(info.value)


def test_slopes_on_a_mounds_terrain_tilt_the_plane_under_the_mounds(tmp_path):
    text = "env_ids: [slipenv/RoverMounds-v0]\npolicies: [baseline]\nseeds: [0]\nslopes_deg: [5]\n"
    (cell,) = load_grid(_grid(tmp_path, text))
    terrain = cell.env_kwargs["terrain"]
    assert terrain["kind"] == "mounds" and terrain["slope_deg"] == 5.0
    assert "placed_mounds" not in terrain


