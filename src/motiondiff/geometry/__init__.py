"""Geometry: skeletons, rotations, forward and inverse kinematics, and the check every motion array passes."""
