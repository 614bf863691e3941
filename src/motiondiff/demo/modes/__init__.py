"""The demo's four modes, one module each, without web code: each turns the page's inputs into one call of the
public API (`motiondiff.pipelines`) and returns its MotionOutput; `demo.requests` writes and zips the files.

- generate: N samples of a prompt (or an action), side by side;
- edit: regenerate body parts of a motion on the page or an uploaded file, keeping the rest of the body;
- inbetween: keep the start and end of a motion (an uploaded BVH) and generate the frames between;
- timeline: one motion through several timed prompts (`MotionPipeline.long`).
"""
