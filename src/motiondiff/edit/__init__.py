"""Motion editing with a trained diffusion model: in-painting over frames (in-betweening) or feature dims
(body-part editing), and long multi-prompt motion stitched by in-painting the overlaps.

Public API: `load_input_motion` (a BVH file, joints .npy or dataset clip in the model's representation),
`inbetween` and `edit_parts` (B edits at once, an `EditResult`), the masks they use (`frame_keep`, `part_keep`,
`resolve_joints`) and `close_root_path` (HumanML3D root closure after in-betweening)."""

from motiondiff.edit.api import EditResult, InputMotion, dataset_motions, edit_parts, inbetween, load_input_motion
from motiondiff.edit.inpaint import EDIT_MODES, inpaint
from motiondiff.edit.masks import EditError, frame_keep, part_keep, resolve_joints, to_frames
from motiondiff.edit.trajectory import close_root_path, needs_root_closure

__all__ = [
    "EDIT_MODES",
    "EditError",
    "EditResult",
    "InputMotion",
    "close_root_path",
    "dataset_motions",
    "edit_parts",
    "frame_keep",
    "inbetween",
    "inpaint",
    "load_input_motion",
    "needs_root_closure",
    "part_keep",
    "resolve_joints",
    "to_frames",
]
