"""Joint motion: the trajectory type and its metadata (``trajectory``), finite-difference
rates against the limits (``rates``), UR's trajectory generator (``ur_motion``) and its
per-tick kinematics (``arm_kinematics``)."""
