"""Motion editing with a trained diffusion model: in-painting over frames (in-betweening) or feature dims
(body-part editing), and long multi-prompt motion stitched by in-painting the overlaps."""

from motiondiff.edit.inpaint import EDIT_MODES, inpaint

__all__ = ["EDIT_MODES", "inpaint"]
