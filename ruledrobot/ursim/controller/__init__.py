"""The emulated controller: its robot/safety/program state machine and motion
(``machine``: :class:`~ruledrobot.ursim.controller.machine.Controller`), its registers,
inputs and outputs (``registers``) and its power and safety (``safety``)."""
