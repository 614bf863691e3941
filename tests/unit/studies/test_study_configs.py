"""Every research study reads its command line through its Hydra config conf/study/<name>.yaml
(`motiondiff.studies.config.study_config`): the configs exist and compose, lists arrive as lists, and a mistake is
one UsageError that names the argument."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
from omegaconf import OmegaConf

from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.paths import CONF_DIR
from motiondiff.studies.config import study_config

STUDIES_DIR = Path(__file__).resolve().parents[3] / "src" / "motiondiff" / "studies"


def _has_main(path: Path) -> bool:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return any(isinstance(node, ast.FunctionDef) and node.name == "main" for node in tree.body)


STUDIES = sorted(p.stem for p in STUDIES_DIR.glob("*.py") if _has_main(p))


def _required(name: str) -> list[str]:
    """Placeholder values for the study's required (???) keys."""
    defaults = OmegaConf.load(CONF_DIR / "study" / f"{name}.yaml")
    return [f"{k}=x" for k in defaults.keys() if OmegaConf.is_missing(defaults, k)]


def test_every_study_with_a_main_has_a_config_and_every_config_a_study():
    assert len(STUDIES) >= 8 and {"behaviour", "editing", "weight_control", "sampler_curve"} <= set(STUDIES)
    configs = {p.stem for p in (CONF_DIR / "study").glob("*.yaml")}
    assert configs == set(STUDIES)


@pytest.mark.parametrize("name", STUDIES)
def test_config_composes_with_every_key_commented(name):
    path = CONF_DIR / "study" / f"{name}.yaml"
    keys = list(OmegaConf.load(path).keys())
    cfg = study_config(name, _required(name))
    assert list(cfg.keys()) == keys and len(keys) >= 3
    for line in path.read_text().splitlines():
        if line and not line.startswith((" ", "#")):  # a top-level key: says what it is
            assert "#" in line, f"{path.name}: no comment on {line!r}"
    for key in keys:  # lists are YAML lists, not comma strings
        assert not (isinstance(cfg[key], str) and "," in cfg[key]), (name, key)


def test_an_unknown_key_is_one_error_naming_it_and_the_keys():
    with pytest.raises(UsageError, match=r"unknown argument 'num_sample=3'.*num_samples.*conf/study/behaviour.yaml"):
        study_config("behaviour", ["num_sample=3"])
    with pytest.raises(UsageError, match="unknown argument '\\+extra=1'"):
        study_config("behaviour", ["+extra=1"])


def test_lists_arrive_as_lists_and_numbers_as_numbers():
    cfg = study_config("weight_control", ["checkpoint=a.ckpt", "weights=[0,1]", "level_steps=[2,2,3]"])
    assert list(cfg.weights) == [0.0, 1.0] and all(isinstance(w, float) for w in cfg.weights)
    assert list(cfg.level_steps) == [2, 2, 3] and cfg.checkpoint == "a.ckpt"
    assert list(study_config("weight_control", ["checkpoint=a"]).weights) == [0, 0.5, 1, 1.5, 2]
    cfg = study_config("editing", ["modes=[overwrite]", "steps=null", "text='a person walks, then waves'"])
    assert list(cfg.modes) == ["overwrite"] and cfg.steps is None and cfg.text == "a person walks, then waves"
    assert list(study_config("sampler_curve", ["runs=[/tmp/a-1/run_x,b]"]).runs) == ["/tmp/a-1/run_x", "b"]


@pytest.mark.parametrize(
    "name, argv, message",
    [
        ("editing", ["hold_from=abc"], "hold_from must be a number, got 'abc'"),
        ("editing", ["seed=1.5"], "seed must be a whole number"),
        ("editing", ["seed=null"], "seed cannot be null"),
        ("editing", ["modes=overwrite,repaint"], "is several values.*key=\\[a,b\\]"),
        ("weight_control", ["checkpoint=a", "weights=[0,x]"], "weights\\[1\\] must be a number"),
        ("weight_control", ["checkpoint=a", "weights=[0,1"], "cannot read argument 'weights=\\[0,1'"),
        ("guided_compare", ["mdm=shipped"], "guided_compare needs latent=..."),
    ],
)
def test_a_bad_value_is_one_error_naming_the_argument(name, argv, message):
    with pytest.raises(UsageError, match=message) as err:
        study_config(name, argv)
    assert "\n" not in str(err.value)


def test_defaults_shared_with_the_commands_agree():
    """The defaults a study shares with edit.py and sample.py are the same numbers."""
    edit, sample = OmegaConf.load(CONF_DIR / "edit.yaml"), OmegaConf.load(CONF_DIR / "sample.yaml")
    assert OmegaConf.load(CONF_DIR / "study" / "editing.yaml").boundary_blend == edit.boundary_blend
    assert OmegaConf.load(CONF_DIR / "study" / "weight_control.yaml").rho == sample.rho
