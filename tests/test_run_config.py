"""RunConfig's payload: what a run started in another process (a trial, a bench) gets."""

from __future__ import annotations

import dataclasses
import json

import pytest

from bearchair.evaluation import worker
from bearchair.evaluation.protocol import ChairEntry, expand_protocol
from bearchair.executive.config import RunConfig


def test_a_payload_round_trips_through_json(tmp_path):
    config = RunConfig(
        chair_path=tmp_path / "a.obj",
        placement="inaccessible",
        helper="disobeys",
        seed=17,
        out_dir=tmp_path / "run",
        timeout_s=123.0,
        record=True,
        imagination_workers=1,
        tree_spec="module:factory",
        mute=True,
    )
    assert RunConfig.from_payload(json.loads(json.dumps(config.to_payload()))) == config


def test_a_payload_without_a_field_keeps_its_default_and_ignores_foreign_keys(tmp_path):
    config = RunConfig.from_payload({"seed": 3, "label": "a bench's", "trial_index": 2})
    assert config == dataclasses.replace(RunConfig(), seed=3)
    assert RunConfig.from_payload({"chair_path": None}).chair_path is None


def test_the_worker_runs_the_trial_payload_muted_inside_the_harness_timeout(tmp_path):
    spec = expand_protocol([ChairEntry(tmp_path / "a.obj", "chair", 90.0)], "paper", 0)[0]
    payload = spec.to_payload(tmp_path / "run", 300.0, imagination_workers=1)
    config = worker.trial_run_config(payload)
    assert (config.chair_path, config.placement, config.helper, config.seed) == (
        spec.chair_path,
        spec.placement,
        spec.helper,
        spec.seed,
    )
    assert config.out_dir == tmp_path / "run" and config.imagination_workers == 1
    assert config.mute and not config.gui and not config.record
    assert config.timeout_s == worker.mission_timeout_s(300.0) == 270.0
    assert config.tree_spec == "mission"


@pytest.mark.parametrize("missing", ["out_dir", "seed", "timeout_s"])
def test_a_trial_payload_without_its_run_is_refused(tmp_path, missing):
    payload = {"out_dir": str(tmp_path), "placement": "accessible", "helper": "obeys"}
    payload |= {"seed": 1, "timeout_s": 60}
    del payload[missing]
    with pytest.raises(KeyError, match=missing):
        worker.trial_run_config(payload)
