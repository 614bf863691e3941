"""Motion editing with a trained diffusion model: in-painting over frames (in-betweening) or feature dims
(body-part editing), and long multi-prompt motion stitched by in-painting the overlaps.

Public API: `load_input_motion` and `dataset_motions` (a BVH file, joints .npy or dataset clip in the model's
representation), `inbetween` and `edit_parts` (B edits at once, an `EditResult`), `generate_long` (timed prompts in
one continuous motion), `smooth_joints` / `smoothness_of_joints` (vvMDM's temporal filter and its metric),
`clean_foot_skate` / `foot_sliding` (feet pinned during ground contacts, and the sliding they had), the
sampling options every edit takes (`SamplingOptions`), the masks (`frame_keep`, `resolve_joints`; a part's dims: `Representation.part_keep`) and
`close_root_path` (HumanML3D root closure after in-betweening)."""

from motiondiff.edit.api import EditResult, edit_parts, inbetween
from motiondiff.edit.foot_cleanup import FootCleanup, clean_foot_skate, foot_sliding
from motiondiff.edit.inpaint import EDIT_MODES, SamplingOptions, inpaint
from motiondiff.edit.inputs import InputMotion, dataset_motions, load_input_motion
from motiondiff.edit.long_motion import LongMotion, generate_long
from motiondiff.edit.masks import EditError, frame_keep, resolve_joints, to_frames
from motiondiff.edit.smoothing import smooth_joints, smoothness_of_joints
from motiondiff.edit.trajectory import close_root_path, needs_root_closure

__all__ = [
    "EDIT_MODES",
    "EditError",
    "EditResult",
    "FootCleanup",
    "InputMotion",
    "LongMotion",
    "SamplingOptions",
    "clean_foot_skate",
    "close_root_path",
    "dataset_motions",
    "edit_parts",
    "foot_sliding",
    "frame_keep",
    "generate_long",
    "inbetween",
    "inpaint",
    "load_input_motion",
    "needs_root_closure",
    "resolve_joints",
    "smooth_joints",
    "smoothness_of_joints",
    "to_frames",
]
