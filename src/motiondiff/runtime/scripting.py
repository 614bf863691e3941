"""What every entry point does before its work (the CLI scripts and the `python -m motiondiff...` studies alike):
config resolvers, offline project-local tool caches, one-line user errors, key=value arguments."""

from __future__ import annotations

import difflib
import itertools
import math
import os
import re
import secrets
import shutil
import sys
from pathlib import Path

from omegaconf import DictConfig, ListConfig, OmegaConf

from motiondiff.runtime.boundary import (  # noqa: F401  (USER_ERRORS re-exported)
    USER_ERRORS,
    guarded,
    note_new_parents,
    refuse_if_in_use,
    refuse_used_folder,
    run_folder,
    stop_on_sigterm,
)
from motiondiff.runtime.command_help import command_help
from motiondiff.runtime.errors import UsageError
from motiondiff.runtime.file_kinds import NAME_MAX, over_long_name
from motiondiff.runtime.hardware import (
    fast_cpu_precision,  # torch: imported when a config asks, not to start a command
)
from motiondiff.runtime.paths import CONF_DIR, REPO_DIR, work_dir
from motiondiff.runtime.settings import MAX_SWEEP_JOBS, MIN_FREE_BYTES


def new_run_id() -> str:
    """A run's part of its folder name (pid and a random token): two runs started in the same second never share a
    folder, whether in two processes or one after the other in one process."""
    return f"{os.getpid():x}{secrets.token_hex(2)}"


RUN_ID = new_run_id()  # drawn again by every run_hydra call (two runs in one process and second differ too)
USER_TEXT_KEYS = ("text", "prompts", "action", "prompt", "captions")  # user text: data, never interpolated


def register_resolvers() -> None:
    if not OmegaConf.has_resolver("repo_dir"):
        OmegaConf.register_new_resolver("repo_dir", lambda: str(REPO_DIR))
    if not OmegaConf.has_resolver("work_dir"):
        OmegaConf.register_new_resolver("work_dir", lambda: str(work_dir()))
    if not OmegaConf.has_resolver("run_id"):
        OmegaConf.register_new_resolver("run_id", lambda: RUN_ID)
    if not OmegaConf.has_resolver("fast_cpu_precision"):
        OmegaConf.register_new_resolver("fast_cpu_precision", _fast_cpu_precision)


def _fast_cpu_precision() -> str:

    return fast_cpu_precision()


def quiet_tool_caches() -> None:
    """Offline defaults and project-local caches for W&B, matplotlib and Hugging Face (never the user's home)."""
    cache = Path(os.environ.get("MOTIONDIFF_CACHE_DIR", work_dir() / ".cache" / "motiondiff"))
    os.environ.setdefault("WANDB_MODE", "offline")
    os.environ.setdefault("WANDB_SILENT", "true")
    os.environ.setdefault("WANDB_CACHE_DIR", str(cache / "wandb"))
    os.environ.setdefault("WANDB_CONFIG_DIR", str(cache / "wandb"))
    os.environ.setdefault("MPLCONFIGDIR", str(cache / "matplotlib"))
    os.environ.setdefault("HF_HOME", str(cache / "huggingface"))
    os.environ.setdefault("HF_HUB_OFFLINE", "1")
    os.environ.setdefault("TRANSFORMERS_OFFLINE", "1")


def user_errors(fn):
    """Report expected failures as one clear line instead of a traceback (``boundary.guarded``): exit code 2, and
    130 for Ctrl-C."""
    return guarded(fn)


def literal(text: str) -> str:
    """``text`` as OmegaConf stores it literally: ``${...}`` escaped, so a prompt is never resolved as config."""
    return text.replace("${", "\\${")


def literal_user_text(cfg: DictConfig) -> None:
    """Make the user-text keys (``USER_TEXT_KEYS``) literal in place: ``text='${oc.env:HOME}'`` stays that text."""
    for key in USER_TEXT_KEYS:
        if key not in cfg:
            continue
        node = cfg._get_node(key)
        raw = node._value() if node is not None else None
        if isinstance(raw, str) and "${" in raw:
            cfg[key] = literal(raw)
        elif isinstance(node, ListConfig):
            for i in range(len(node)):
                item = node._get_node(i)._value()
                if isinstance(item, str) and "${" in item:
                    node[i] = literal(item)


def key_value_args(argv: list[str], keys) -> dict[str, str]:
    """``key=value`` arguments of a ``python -m motiondiff...`` command, each key one of ``keys``."""
    args = {}
    for a in argv:
        key, eq, value = a.partition("=")
        if not eq or key not in keys:
            raise UsageError(f"unknown argument {a!r}; arguments are key=value with key one of {', '.join(keys)}")
        args[key] = value
    return args


def to_dict(cfg: DictConfig | dict | None) -> dict | None:
    """Plain containers (checkpoints store hyper-parameters that load with torch.load(weights_only=True))."""
    if cfg is None:
        return None
    if isinstance(cfg, DictConfig):
        return OmegaConf.to_container(cfg, resolve=True)  # type: ignore[return-value]
    return dict(cfg)


def run_hydra(config_name: str, run) -> None:
    """One Hydra run of ``run(cfg)`` with the project's config ``config_name`` (command line overrides from
    sys.argv), after the resolvers and tool caches are set; user errors become one line and exit code 2."""
    import hydra

    if any(a in ("--help", "-h") for a in sys.argv[1:]):  # the settings explained (Hydra's: --hydra-help)
        print(command_help(config_name))
        return
    global RUN_ID
    RUN_ID = new_run_id()  # this run's folder is its own, not an earlier in-process run's of the same second
    register_resolvers()
    quiet_tool_caches()
    if not any(a.startswith("hydra.job.name=") for a in sys.argv[1:]):  # log files named after the command
        # beside the other overrides (Hydra reads them as one run of words: `-m a=1`, `a=1 --cfg job`)
        at = next((i for i, a in enumerate(sys.argv) if i and "=" in a and not a.startswith("-")), len(sys.argv))
        sys.argv.insert(at, f"hydra.job.name={config_name}")
    check_overrides(config_name, sys.argv[1:])

    def task(cfg: DictConfig):
        from hydra.core.hydra_config import HydraConfig

        hydra_cfg = HydraConfig.get()
        stop_on_sigterm(Path(hydra_cfg.runtime.output_dir))
        with run_folder(Path(hydra_cfg.runtime.output_dir), hydra_cfg.job.name):
            literal_user_text(cfg)
            return run(cfg)

    hydra.main(version_base="1.3", config_path=str(CONF_DIR), config_name=config_name)(guarded(task))()


def check_overrides(config_name: str, argv: list[str]) -> None:
    """Compose the config with the command line's overrides once before Hydra's run, so a misspelt key, a missing
    config group option or a syntax error is one ``error:`` line and exit code 2 (Hydra's own report is several
    lines and exit code 1), and no run folder is made. Sweeps (-m) and Hydra's flags are left to Hydra."""
    note_new_parents(None)
    if any(a in ("-m", "--multirun") for a in argv):
        guarded(check_sweep_size)([a for a in argv if not a.startswith("-")])
    if any(a.startswith("-") for a in argv):
        return
    guarded(check_override_kinds)(config_name, argv)
    from hydra import compose, initialize_config_dir
    from hydra.core.global_hydra import GlobalHydra
    from hydra.errors import HydraException
    from omegaconf.errors import OmegaConfBaseException

    try:
        with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3"):
            cfg = compose(config_name, overrides=[a for a in argv if not a.startswith("hydra.job.name=")],
                          return_hydra_config=True)  # fmt: skip
    except (HydraException, OmegaConfBaseException) as err:
        print(f"error: {_override_error(err)}", file=sys.stderr)
        sys.exit(2)
    except ValueError as err:  # the override parser's own limits (a 5000-digit number: Python's int-string bound)
        longest = max(argv, key=len)
        key = longest.split("=", 1)[0] if "=" in longest else longest[:20]
        print(f"error: cannot read {key}= ({len(longest)} characters): {str(err).splitlines()[0][:120]}; give a "
              "shorter value", file=sys.stderr)  # fmt: skip
        sys.exit(2)
    finally:
        GlobalHydra.instance().clear()
    try:
        run_dir = Path(str(OmegaConf.select(cfg, "hydra.run.dir")))
    except OmegaConfBaseException as err:
        if "oc.env" in str(err) or "Environment variable" in str(err):  # an unset variable: Hydra would trace
            print(f"error: the run folder cannot be named: {str(err).splitlines()[0]} (set the variable or give "
                  "paths.output_dir=)", file=sys.stderr)  # fmt: skip
            sys.exit(2)
        return  # resolved by Hydra at run time only
    guarded(check_writable)(run_dir)
    note_new_parents(run_dir)  # what a failed run takes away again, besides its own folder
    guarded(refuse_if_in_use)(run_dir)  # before Hydra writes its config and log into another run's folder
    guarded(refuse_used_folder)(run_dir, _selected(cfg, "ckpt_path"))  # nor into a finished run's


def _selected(cfg: DictConfig, key: str) -> str | None:
    try:
        value = OmegaConf.select(cfg, key, default=None)
    except Exception:  # noqa: BLE001 - an interpolation Hydra resolves only at run time
        return None
    return None if value is None else str(value)


def check_sweep_size(overrides: list[str]) -> None:
    """Refuse a multirun (-m) of more than MAX_SWEEP_JOBS jobs before Hydra lists them (``seed=range(0,1000000)``
    would plan a million runs and start none for minutes). Counted from Hydra's own override parser."""
    from hydra.core.override_parser.overrides_parser import OverridesParser
    from hydra.errors import HydraException

    try:
        parsed = OverridesParser.create().parse_overrides(overrides)
    except HydraException:
        return  # Hydra reports its own syntax errors
    counts = [(o.input_line, sum(1 for _ in itertools.islice(o.sweep_iterator(), MAX_SWEEP_JOBS + 1)))
              for o in parsed if o.is_sweep_override() and not o.is_interval_sweep()]  # fmt: skip
    if math.prod(max(n, 1) for _, n in counts) > MAX_SWEEP_JOBS:
        each = ", ".join(f"{line}: {n if n <= MAX_SWEEP_JOBS else f'over {MAX_SWEEP_JOBS}'}" for line, n in counts)
        raise UsageError(f"this sweep makes more than {MAX_SWEEP_JOBS} jobs (values per setting: {each}): sweep "
                         "fewer values, or split it into several sweeps")  # fmt: skip


# The commands whose configs are closed: a setting added with +key or removed with ~key is a mistake there (training
# configs are open: +dataset.datamodule.bucket_chunk=N and the like are documented)
CLOSED_COMMANDS = ("sample", "edit", "evaluate")


def check_override_kinds(config_name: str, argv: list[str]) -> None:
    """Refuse, for the closed commands, a setting added with ``+key=`` (a misspelt ``+lenght=3`` would be ignored)
    or removed with ``~key`` (the command then fails deep inside), naming the settings that come closest."""
    if config_name not in CLOSED_COMMANDS:
        return
    for arg in argv:
        key = arg.split("=", 1)[0]
        if key.startswith(("+", "~")) and not key.lstrip("+~").startswith("hydra."):
            name = key.lstrip("+~")
            known = _top_level_keys(config_name)
            close = difflib.get_close_matches(name.split(".")[0], known, n=3)
            hint = f" (did you mean {', '.join(close)}?)" if close else ""
            what = "removes" if key.startswith("~") else "adds"
            raise UsageError(f"{arg!r} {what} a setting; {config_name} takes only its own settings{hint}: set one as "
                             f"key=value (`--cfg job` lists them)")  # fmt: skip


def _top_level_keys(config_name: str) -> list[str]:
    text = (CONF_DIR / f"{config_name}.yaml").read_text()
    return sorted({m.group(1) for m in re.finditer(r"^([A-Za-z_][\w]*):", text, re.MULTILINE)} - {"defaults", "hydra"})


def check_writable(folder: Path) -> None:
    """Whether ``folder`` can be made (a trial folder in its nearest existing parent), so a run folder that cannot
    be created fails as one line before Hydra tries."""
    import tempfile

    folder = folder.absolute()
    long = over_long_name(folder)
    if long is not None:
        raise UsageError(f"cannot make the run folder: a folder name of {len(long.encode())} bytes ({long[:24]}...) is "
                         f"longer than the file system's {NAME_MAX}; choose a shorter hydra.run.dir= or paths.output_dir=")  # fmt: skip
    parent = next((p for p in (folder, *folder.parents) if p.exists()), None)
    if parent is None or not parent.is_dir():
        raise UsageError(f"cannot make the run folder {folder}: {parent} is a file, not a folder (set another "
                         "paths.output_dir= or hydra.run.dir=)")  # fmt: skip
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".motiondiff-check-", dir=parent))
    except OSError as err:
        raise UsageError(f"cannot make the run folder {folder} ({err.strerror} in {parent}): set a writable "
                         "paths.output_dir= or hydra.run.dir=") from None  # fmt: skip
    free = shutil.disk_usage(parent).free
    if free < MIN_FREE_BYTES:
        raise UsageError(f"the disk of the run folder {folder} has {free // 1024} KiB free; a run needs at least "
                         f"{MIN_FREE_BYTES >> 20} MiB: free some disk space, or set paths.output_dir= on another "
                         "disk")  # fmt: skip


def _override_error(err: Exception) -> str:
    """Hydra's several-line composition error as one line that names the setting and what is allowed."""
    text = str(err)
    ambiguous = re.match(r"Ambiguous value for argument '([^'=]+)=([^']*)'", text)
    if ambiguous:  # key=a,b outside a sweep
        key, value = ambiguous.groups()
        return (f"{key}={value} has commas: write a list as '{key}=[{value}]', quote text as \"{key}='{value}'\", or "
                "sweep the values with -m")  # fmt: skip
    unknown = re.match(r"Could not override '([^']+)'", text)
    if unknown and "not in struct" in f"{text} {err.__cause__}" or unknown and "To append" in text:
        return f"unknown setting {unknown.group(1)!r}: check its spelling (`--cfg job` lists the settings)"
    lines = [line.strip() for line in text.split("Config search path")[0].splitlines() if line.strip()]
    lines = [line for line in lines if not line.startswith(("full_key:", "object_type", "reference_type"))]
    head, _, options = "\n".join(lines).partition("Available options in")
    if options:
        group, _, names = options.partition(":")
        return f"{head.strip()}; {group.strip()} is one of {', '.join(names.split())}"
    return "; ".join(lines)
