"""The emulated arm: the backend interface and the kinematic arm (``backend``), the
MuJoCo-backed arm (``physics``), the catalogue model an emulator runs with its
calibration and the KinematicsInfo it serves (``emulated``)."""
