"""File formats: BVH, joint maps between skeletons, archives, and the prepared-dataset format."""
