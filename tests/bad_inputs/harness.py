"""Run an entry point's `run(cfg)` in this process, as `python <script>.py key=value ...` would, with outputs in a
temporary folder: fast enough for a catalogue of many cases, and the folder can be checked for leftovers."""

from __future__ import annotations

import importlib
from pathlib import Path

from hydra import compose, initialize_config_dir
from hydra.core.hydra_config import HydraConfig
from omegaconf import open_dict

REPO = Path(__file__).resolve().parents[2]


def run_entry(script: str, tmp_path: Path, *overrides: str):
    """Compose conf/<script>.yaml with ``overrides`` and call motiondiff.cli.<script>.run on it; the run folder
    is tmp_path/run (returned with the result)."""
    from motiondiff.cli.common import register_resolvers

    register_resolvers()
    out = tmp_path / "run"
    out.mkdir(exist_ok=True)
    with initialize_config_dir(str(REPO / "conf"), version_base="1.3"):
        cfg = compose(script, overrides=[f"paths.output_dir={tmp_path / 'outputs'}",
                                         f"paths.cache_dir={tmp_path / 'cache'}", *overrides],
                      return_hydra_config=True)  # fmt: skip
    with open_dict(cfg):
        cfg.hydra.runtime.output_dir = str(out)
        HydraConfig.instance().set_config(cfg)
        del cfg["hydra"]
    return importlib.import_module(f"motiondiff.cli.{script}").run(cfg), out


def files_under(folder: Path) -> list[Path]:
    return sorted(p for p in Path(folder).rglob("*") if p.is_file()) if Path(folder).exists() else []
