"""URScript in the emulator: programs split and parsed (``program``), the functions it
runs (``functions``), standalone programs (``runner``), ur_rtde's control-script register
protocol (``handshake``) and what a running program sees of the controller (``host``)."""
