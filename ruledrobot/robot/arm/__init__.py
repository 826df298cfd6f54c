"""The arm: nominal UR tables (``ur_tables``), calibrations (``calibration``,
``calibration_random``), the model (``model``: DH table, limits, masses, base, tool),
its DH chain (``kinematics``: FK, Jacobian, skeleton), the catalogue (``catalogue``) and
the arm's physical shape (``shape``)."""
