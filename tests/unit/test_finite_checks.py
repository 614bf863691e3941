"""Finite by construction: NaN/Inf settings are refused before any work, a model's NaN output is refused before
anything is written, JSON never holds a bare NaN, and the training evaluation logs val/fid=inf for a model that
generates NaN instead of stopping the run."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import torch
from hydra import compose, initialize_config_dir

from motiondiff.cli.validate import RULES_EDIT, RULES_SAMPLE, check
from motiondiff.lit.generation import NonFiniteOutput, check_finite_output, generate_features
from motiondiff.runtime.atomic import finite_or_null, write_json
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.paths import CONF_DIR
from motiondiff.runtime.scripting import register_resolvers

register_resolvers()


def _cfg(name: str, *overrides: str):
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
        return compose(name, overrides=list(overrides))


@pytest.mark.parametrize(("name", "rules"), [("sample", RULES_SAMPLE), ("edit", RULES_EDIT)])
@pytest.mark.parametrize("value", ["nan", "inf", "-inf"])
def test_guidance_must_be_finite(name, rules, value):
    with pytest.raises(UsageError, match=f"guidance={value.replace('+', '')}"):
        check(_cfg(name, f"guidance={value}"), rules)


@pytest.mark.parametrize("override", ["+sampler.rho=nan", "rho=inf", "+extra.deep=[1, nan]"])
def test_any_number_of_the_config_must_be_finite(override):
    key = override.lstrip("+").split("=")[0]
    with pytest.raises(UsageError, match="must be a finite number") as err:
        check(_cfg("sample", override), RULES_SAMPLE)
    assert key in str(err.value)


def test_user_text_is_not_a_number_setting():
    check(_cfg("sample", "text=nan"), RULES_SAMPLE)  # the prompt "nan": checked as text later, not as a number


@pytest.mark.parametrize(
    "values",
    [np.array([1.0, np.nan]), torch.tensor([[np.inf]]), [np.zeros(3), np.array([-np.inf])]],
)
def test_non_finite_outputs_are_refused(values):
    with pytest.raises(NonFiniteOutput, match="nothing was written"):
        check_finite_output(values)


def test_finite_outputs_pass():
    check_finite_output([np.zeros((2, 3)), torch.ones(4)])


class _NaNModel(torch.nn.Module):
    """Samples NaN: what one broken weight does to every motion."""

    condition_kind = "none"
    device = torch.device("cpu")

    def sample(self, cond, lengths, **_):
        return torch.full((len(lengths), int(lengths.max()), 3), float("nan"))

    def denormalise(self, x):
        return x


def test_generation_refuses_a_nan_motion():
    with pytest.raises(NonFiniteOutput):
        generate_features(_NaNModel(), [None, None], torch.tensor([4, 3]))


def test_json_never_holds_nan(tmp_path):
    with pytest.raises(ValueError):
        write_json(tmp_path / "a.json", {"fid": float("nan")})
    assert not (tmp_path / "a.json").exists()
    data = {"fid": float("nan"), "rows": [1.0, float("inf"), np.float32("nan")], "n": 3, "name": "x"}
    write_json(tmp_path / "b.json", finite_or_null(data))
    assert json.loads((tmp_path / "b.json").read_text()) == {"fid": None, "rows": [1.0, None, None], "n": 3,
                                                             "name": "x"}  # fmt: skip


def test_training_evaluation_logs_inf_fid_for_nan_samples(monkeypatch):
    from motiondiff.eval.callbacks import GenerationEvaluation

    callback = GenerationEvaluation(evaluator_dir="/nonexistent")
    callback.evaluators = object()  # as if the dataset had evaluators

    def nan_metrics(trainer, module):
        raise NonFiniteOutput("the generated motion holds NaN")

    monkeypatch.setattr(callback, "_metrics", nan_metrics)
    logged = {}
    module = type("M", (), {"training": True, "condition_kind": "action", "train": lambda self, mode: None,
                            "log": lambda self, k, v, **kw: logged.__setitem__(k, v)})()  # fmt: skip
    trainer = type("T", (), {"sanity_checking": False, "current_epoch": 0, "global_step": 7})()
    callback.on_validation_epoch_end(trainer, module)
    assert math.isinf(logged["val/fid"]) and logged["val/accuracy"] == 0.0
