"""The UR protocol vocabulary shared by the runner, the emulator and the calibration reader.

* :mod:`.primary` — the primary/secondary client interface (ports 30001/30002):
  message framing, the robot-state message and its KinematicsInfo sub-package,
  the version message; a bounded reader of a controller's kinematics.

Packet layouts follow UR's "Client Interface" documentation (big-endian), as
implemented by UR's own client library (``Universal_Robots_Client_Library``).
"""
