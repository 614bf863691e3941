"""Edit a motion: python edit.py input=<file.bvh | joints.npy | clip id> kind=inbetween|parts [text="..." ...]"""

from motiondiff.cli.entry import edit

if __name__ == "__main__":
    edit()
