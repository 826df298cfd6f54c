"""An error the run's child does not expect (a defect) stops the arm as any stop does and
is reported with its words and place, not as a dead client.

Found on 6 Dec 2026: a forwarded run's socket closed under the child (BrokenPipeError);
the child left through its ``finally: os._exit(0)`` and the run read "the ur_rtde client
process died (exit code 0)", with no word of the error and no safe stop of its own.
Here the child's ``_run`` runs in this process on a stand-in session whose control
connection raises; the protocol messages it sends are the evidence."""

from __future__ import annotations

from ruledrobot.export import run_child


class _Link:
    def __init__(self) -> None:
        self.sent: list[tuple] = []

    def send(self, *msg: object) -> None:
        self.sent.append(msg)

    def stage(self, *_: object) -> None:
        pass


class _Session:
    """What ``_run`` uses of a session; connecting the control interface fails with an
    error no stop rule knows."""

    def __init__(self) -> None:
        self.link = _Link()
        self.window = 0
        self.stopped: list[tuple] = []

    def connect_control(self) -> None:
        raise KeyError("tcp_offset")  # a defect's kind of error: not the robot's

    def safe_stop(self, mode: str, deceleration: float, budget: float) -> None:
        self.stopped.append((mode, deceleration, budget))

    def settle(self) -> None:
        pass

    def info(self) -> dict:
        return {"sent": 0}


def test_an_unexpected_error_stops_the_arm_and_says_what_and_where(capsys):
    s = _Session()
    run_child._run(s, {"window": 10, "mode": "forward", "stop_deceleration": 2.0,
                       "stop_budget": 1.5, "connect_timeout": 5.0})  # fmt: skip
    assert s.stopped == [("forward", 2.0, 1.5)]  # the safe stop, as on any stop
    kinds = [m[0] for m in s.link.sent]
    assert kinds == ["stopping", "done"], kinds
    _, status, message = s.link.sent[0]
    done = s.link.sent[1][1]
    assert status == done["status"] == "client_error"
    assert "KeyError: 'tcp_offset'" in message and "test_run_child_defect.py:" in message
    assert "defect of ruledrobot" in message and done["message"] == message
    assert "Traceback" in capsys.readouterr().err  # the whole traceback for the report
