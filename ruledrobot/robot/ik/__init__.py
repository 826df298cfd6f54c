"""Inverse kinematics: the UR closed form (``analytic``), its refinement on a calibrated
chain (``calibrated`` with its numba and numpy kernels), path IK (``path``) and how far a
pose misses the arm's reach (``workspace``).  Imports nothing of the robot layer but its
input checks."""
