"""The shipped slip model is data: read through importlib.resources, written only on request,
never into an installed package; a missing file is an error, not a silent fallback."""

from __future__ import annotations

import json

import pytest

from slipenv.envs import registration
from slipenv.experiments.yamauchi import model_file

RECORD = {"beta_model": {"coef": [0.0, 0.1, 0.2, 0.3]}, "n": 0.8, "source": "test"}


@pytest.mark.parametrize("folder", ["site-packages", "dist-packages"])
def test_saving_into_an_installed_package_is_refused(tmp_path, folder):
    target = tmp_path / "lib" / folder / "slipenv" / "data" / "m.json"
    with pytest.raises(ValueError, match="installed package"):
        model_file.save_model(RECORD, target)
    assert not target.exists()


def test_saving_to_a_checkout_path_writes_the_record(tmp_path):
    out = model_file.save_model(RECORD, tmp_path / "data" / "m.json")
    assert json.loads(out.read_text()) == RECORD


def test_the_old_boolean_flag_is_a_clear_error():
    with pytest.raises(ValueError, match="save_model must be a file path"):
        model_file.model_path(True)


def test_the_shipped_model_is_read_as_package_data():
    assert model_file.MODEL_FILE.is_file()
    saved = json.loads(model_file.MODEL_FILE.read_text())
    kwargs = registration.yamauchi_observation()["estimator_kwargs"]
    assert kwargs == {"beta_model": saved["beta_model"], "n": saved["n"]}


def test_a_missing_model_file_is_an_error_not_a_fallback(tmp_path, monkeypatch):
    monkeypatch.setattr(registration, "yamauchi_model_file", lambda: tmp_path / "none.json")
    with pytest.raises(FileNotFoundError, match="package data"):
        registration.yamauchi_observation()


def test_a_model_file_without_n_names_the_missing_key(tmp_path, monkeypatch):
    broken = tmp_path / "m.json"
    broken.write_text(json.dumps({"beta_model": {}}))
    monkeypatch.setattr(registration, "yamauchi_model_file", lambda: broken)
    with pytest.raises(ValueError, match="'n'"):
        registration.yamauchi_observation()
