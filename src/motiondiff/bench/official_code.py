"""Import the official MDM code (GuyTevet/motion-diffusion-model) from a user's local checkout, for the benchmark's
side-by-side rows. Nothing of it is copied into this repository: its modules are imported from the checkout at run
time and taken out of ``sys.modules`` again afterwards (its top-level packages have generic names: model, diffusion,
utils, data_loaders), so nothing else in the process sees them.

Two modules are stubbed while it is imported; neither runs in any timed work:
- ``clip`` (OpenAI CLIP): MDM's constructor loads CLIP ViT-B/32 to encode captions. Both sides of the comparison get
  precomputed random caption features instead: the official side through ``y['text_embed']``, the caching path of
  MDM's own forward, which then never calls ``encode_text``. The stub's CLIP has no weights (so the parameter count is
  MDM's without CLIP, as ``parameters_wo_clip`` gives it), and encoding a caption through it is an error.
- ``model.smpl`` (the checkout's SMPL layer; it needs the ``smplx`` package and the SMPL body-model files): MDM builds
  it for its geometric losses (lambda_rcxyz, lambda_fc), which are 0 for HumanML3D's hml_vec features. It has no
  parameters.
"""

from __future__ import annotations

import importlib
import importlib.util
import subprocess
import sys
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import torch

from motiondiff.runtime.errors import UsageError

REPO_URL = "https://github.com/GuyTevet/motion-diffusion-model"
EXPECTED_FILES = ("model/mdm.py", "diffusion/gaussian_diffusion.py", "diffusion/respace.py", "utils/model_util.py")
PACKAGES = ("model", "diffusion", "utils", "data_loaders")  # the checkout's top-level packages
STUBS = ("clip", "model.smpl")


@dataclass(frozen=True)
class OfficialCode:
    """The pieces of the official code the benchmark runs, and where they came from."""

    path: Path
    commit: str
    MDM: type
    gaussian_diffusion: ModuleType
    create_gaussian_diffusion: Callable
    SpacedDiffusion: type
    space_timesteps: Callable
    ClassifierFreeSampleModel: type
    MixedPrecisionTrainer: type
    UniformSampler: type
    logger: ModuleType


class NoClip(torch.nn.Module):
    """What the stubbed ``clip.load`` returns: no weights. The benchmark feeds caption features, so encoding is an error."""

    def encode_text(self, tokens):
        raise RuntimeError("CLIP is stubbed in the benchmark: give MDM caption features as y['text_embed']")


class NoSMPL(torch.nn.Module):
    """The stubbed SMPL layer: no buffers, no parameters; the benchmark's losses never ask it for joints."""

    def forward(self, *args, **kwargs):
        raise RuntimeError("SMPL is stubbed in the benchmark: its losses keep lambda_rcxyz and lambda_fc at 0")


def _no_tokenize(*args, **kwargs):
    raise RuntimeError("CLIP is stubbed in the benchmark: give MDM caption features as y['text_embed']")


def _stub_modules() -> dict[str, ModuleType]:
    clip = ModuleType("clip")
    clip.load = lambda *args, **kwargs: (NoClip(), None)
    clip.tokenize = _no_tokenize
    clip.model = ModuleType("clip.model")
    clip.model.convert_weights = lambda model: None
    smpl = ModuleType("model.smpl")
    smpl.SMPL, smpl.JOINTSTYPE_ROOT = NoSMPL, {}
    return {"clip": clip, "clip.model": clip.model, "model.smpl": smpl}


def _top(name: str) -> str:
    return name.split(".", 1)[0]


def _owned(name: str) -> bool:
    return _top(name) in (*PACKAGES, "clip")


def _import_error(path: Path, err: ImportError) -> UsageError:
    name = err.name or ""
    if _top(name) in PACKAGES:
        return UsageError(f"the official MDM checkout at {path} is incomplete ({err}); use a full clone of {REPO_URL}")
    if isinstance(err, ModuleNotFoundError) and name:
        return UsageError(
            f"the official MDM code at {path} needs the Python package '{_top(name)}', which is not installed here "
            f"({err}); install it into this environment (only clip and the SMPL layer are stubbed by the benchmark)"
        )
    return UsageError(f"the official MDM code at {path} does not import here: {err}")


def check_checkout(path: str | Path) -> Path:
    """``path`` as an absolute Path if it holds an MDM checkout, else one clear error naming the file it lacks."""
    root = Path(path).expanduser().resolve()
    if not root.is_dir():
        raise UsageError(f"--official {path}: no such directory; give a local clone of {REPO_URL}")
    for rel in EXPECTED_FILES:
        if not (root / rel).is_file():
            raise UsageError(f"--official {path} is not an MDM checkout: expected {rel} there (a clone of {REPO_URL})")
    return root


def _commit(root: Path) -> str:
    try:
        out = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return out.stdout.strip() if out.returncode == 0 else "unknown (not a git checkout)"


def _put_packages(root: Path) -> None:
    """Register the checkout's top-level packages explicitly (they are namespace packages there, which any
    same-named directory elsewhere on sys.path could otherwise join or shadow)."""
    for name in PACKAGES:
        folder = root / name
        if not folder.is_dir():
            continue
        init = folder / "__init__.py"
        if init.is_file():
            spec = importlib.util.spec_from_file_location(name, init, submodule_search_locations=[str(folder)])
            module = importlib.util.module_from_spec(spec)
            sys.modules[name] = module
            spec.loader.exec_module(module)
        else:
            module = ModuleType(name)
            module.__path__ = [str(folder)]
            sys.modules[name] = module


def _attr(root: Path, module: str, name: str):
    try:
        return getattr(importlib.import_module(module), name)
    except AttributeError:
        raise UsageError(
            f"the official MDM checkout at {root} has no {name} in {module}; the benchmark follows {REPO_URL} "
            "as of 2025 (commit d4fd88c)"
        ) from None


def load_official(path: str | Path) -> OfficialCode:
    """Import the official model, diffusion, guidance wrapper and training pieces from the checkout at ``path``."""
    root = check_checkout(path)
    saved_path = list(sys.path)
    saved = {name: module for name, module in sys.modules.items() if _owned(name)}
    for name in saved:
        del sys.modules[name]
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FutureWarning)  # its torch.cuda.amp decorators
            sys.modules.update(_stub_modules())
            sys.path.insert(0, str(root))
            _put_packages(root)
            guidance = "utils.sampler_util" if (root / "utils" / "sampler_util.py").is_file() else "model.cfg_sampler"
            return OfficialCode(
                path=root,
                commit=_commit(root),
                MDM=_attr(root, "model.mdm", "MDM"),
                gaussian_diffusion=importlib.import_module("diffusion.gaussian_diffusion"),
                create_gaussian_diffusion=_attr(root, "utils.model_util", "create_gaussian_diffusion"),
                SpacedDiffusion=_attr(root, "diffusion.respace", "SpacedDiffusion"),
                space_timesteps=_attr(root, "diffusion.respace", "space_timesteps"),
                ClassifierFreeSampleModel=_attr(root, guidance, "ClassifierFreeSampleModel"),
                MixedPrecisionTrainer=_attr(root, "diffusion.fp16_util", "MixedPrecisionTrainer"),
                UniformSampler=_attr(root, "diffusion.resample", "UniformSampler"),
                logger=importlib.import_module("diffusion.logger"),
            )
    except ImportError as err:
        raise _import_error(root, err) from None
    finally:
        sys.path[:] = saved_path
        for name in [name for name in sys.modules if _owned(name)]:
            del sys.modules[name]
        sys.modules.update(saved)
