"""The settings of a research study: its Hydra config conf/study/<name>.yaml (every key with its default and what it
means) composed with the command line's ``key=value`` words in Hydra's override grammar (``weights=[0,1,2]``,
``text='a person waves'``).

One place reads every study's command line, so the defaults live in the YAML instead of the code, a list is a list,
and every mistake (an unknown key, a malformed word, text where a number belongs) is one UsageError line that names
the argument and lists the study's keys. A key's type is that of its YAML default; a key whose default is null (or
??? : required) takes text (a path or a name) unless TYPES gives its type, and only those keys accept null. conf/study is composed as
a config folder of its own, so a study key named like one of the project's config groups (``sampler``, ``latent``)
stays a plain key.
"""

from __future__ import annotations

from omegaconf import DictConfig, OmegaConf

from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.paths import CONF_DIR

_KINDS = {bool: "true or false", int: "a whole number", float: "a number", str: "text", list: "a list [a, b, ...]"}
_SAMPLING = {"steps": int, "guidance": float, "smooth_sigma": float}
# per study, the keys that take numbers or lists although their default is null, or null although it is not
TYPES = {"action_accuracy": _SAMPLING, "behaviour": _SAMPLING, "editing": {"steps": int, "guidance": float},
         "sampler_curve": {"runs": list}, "foot_cleanup": {"steps": int}}  # fmt: skip


def study_config(name: str, argv: list[str]) -> DictConfig:
    """conf/study/<name>.yaml with the overrides ``argv``, as a flat config with the YAML's keys."""
    from hydra import compose, initialize_config_dir
    from hydra.core.override_parser.overrides_parser import OverridesParser
    from hydra.errors import HydraException

    path = CONF_DIR / "study" / f"{name}.yaml"
    if not path.is_file():
        raise UsageError(f"no study {name!r}: no config {path}")
    defaults = OmegaConf.load(path)
    names = list(defaults.keys())  # (`in` would skip the required ??? keys)
    keys = f"{name}'s keys: {', '.join(names)} (defaults in conf/study/{name}.yaml)"
    parser = OverridesParser.create()
    for arg in argv:
        try:
            override = parser.parse_override(arg)
        except HydraException as err:
            raise UsageError(f"cannot read argument {arg!r} ({_first_line(err)}): write key=value, a list as "
                             f"key=[a,b], text with spaces or commas quoted as key='a, b'; {keys}") from None  # fmt: skip
        if override.key_or_group not in names or override.package is not None or override.type.name != "CHANGE":
            raise UsageError(f"unknown argument {arg!r}; {keys}")
        if override.is_sweep_override():
            raise UsageError(f"{arg!r} is several values: quote text with commas as key='a, b', write a list as "
                             f"key=[a,b]; {keys}")  # fmt: skip
    try:
        with initialize_config_dir(config_dir=str(path.parent), version_base="1.3"):
            cfg = compose(config_name=name, overrides=list(argv))
    except HydraException as err:
        raise UsageError(f"{_first_line(err)}; {keys}") from None
    required = [k for k in names if OmegaConf.is_missing(defaults, k)]
    missing = [k for k in required if OmegaConf.is_missing(cfg, k) or cfg[k] is None]
    if missing:
        raise UsageError(f"{name} needs {' '.join(f'{k}=...' for k in missing)}; {keys}")
    plain = OmegaConf.to_container(defaults)
    for key in names:
        default = None if key in required else plain[key]
        cfg[key] = _checked(key, _plain(cfg[key]), default, TYPES.get(name, {}).get(key))
    return cfg


def _plain(value):
    return OmegaConf.to_container(value) if OmegaConf.is_config(value) else value


def _kind(value) -> type | None:
    return next((k for k in _KINDS if isinstance(value, k)), None)  # bool before int: True is an int too


def _checked(key: str, value, default, declared: type | None):
    """``value`` as the type of ``default`` (or ``declared``): whole numbers widen to float, numbers become text
    where text belongs, one value where a list belongs becomes a list of one; anything else is a UsageError."""
    kind = declared or (str if default is None else _kind(default))
    if value is None:
        if default is None or declared is not None:
            return None
        raise UsageError(f"{key} cannot be null; it is {_KINDS[kind]} (default {default!r})")
    if kind is list:
        items = value if isinstance(value, list) else [value]
        floats = default and any(isinstance(d, float) for d in default)
        item_kind = float if floats else _kind(default[0]) if default else str
        return [_checked(f"{key}[{i}]", v, None, item_kind) for i, v in enumerate(items)]
    found = _kind(value)
    if found is kind:
        return value
    if kind is float and found is int:
        return float(value)
    if kind is str and found in (int, float):
        return str(value)
    raise UsageError(f"{key} must be {_KINDS[kind]}, got {value!r}")


def _first_line(err: Exception) -> str:
    return str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
