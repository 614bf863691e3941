"""The quaternion formulas written once, on components, for both array libraries: `rotations` (numpy) and
`torch_rotations` (torch, differentiable) unpack, call these and stack. Quaternions are (w, x, y, z)."""

from __future__ import annotations


def hamilton(a, b) -> list:
    """Components of the Hamilton product a * b (apply b first, then a); a, b: the four components each."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return [
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ]


def matrix_entries(q) -> list:
    """The nine entries, row by row, of the rotation matrix of a unit quaternion's components."""
    w, x, y, z = q
    return [
        1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
        2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
    ]  # fmt: skip
