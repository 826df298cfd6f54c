"""The URScript interpreter (ursim/script: syntax, transpile, interpreter, library, sockets):
the language, controller time, errors with lines, sockets, UR's control-loop example."""

from __future__ import annotations

import socket
import struct
import threading

import numpy as np
import pytest

from ruledrobot.robot import load
from ruledrobot.ursim import DEFAULT_Q
from ruledrobot.ursim.controller.machine import Controller
from ruledrobot.ursim.script.interpreter import MAX_SPIN

MODEL = load("ur5e")


def _run(text: str, ticks: int = 5000, ctrl: Controller | None = None) -> Controller:
    ctrl = ctrl or Controller(MODEL)
    assert ctrl.load_script(text), [m for _, lv, m in ctrl.events if lv <= 1]
    for _ in range(ticks):
        ctrl.tick()
        if ctrl.runner is None:
            break
    return ctrl


def _messages(ctrl: Controller, level: int = 3) -> list[str]:
    return [m for _, lv, m in ctrl.events if lv == level]


def _errors(ctrl: Controller) -> list[str]:
    return [m for _, lv, m in ctrl.events if lv <= 1]


def test_variables_lists_functions_and_control_flow() -> None:
    ctrl = _run(
        "def prog():\n"
        "  global total = 0\n"
        "  buf = [0, 0, 0, 0]\n"
        "  def add(a, b=2):\n"
        "    return a + b\n"
        "  end\n"
        "  def bump():\n"
        "    global total\n"
        "    total = total + 1\n"
        "  end\n"
        "  i = 0\n"
        "  while i < 4:\n"
        "    if i == 0:\n"
        "      buf[i] = add(i)\n"
        "    elif i == 1 or i == 2:\n"
        "      buf[i] = add(i, b=10) * 2\n"
        "    else:\n"
        "      buf[i] = -(7 % 4) / 2\n"
        "    end\n"
        "    bump()\n"
        "    i = i + 1\n"
        "  end\n"
        "  pose = p[0.1, 0.2, 0.3, 0, 0, 0]\n"
        "  pose[2] = pose[2] + 1\n"
        "  textmsg(buf)\n"
        "  textmsg(total, pose[2])\n"
        "  textmsg(not (True xor False), length(buf))\n"
        "end\n"
    )
    assert _errors(ctrl) == []
    msgs = _messages(ctrl)
    assert "[2, 22, 24, -1.5]" in msgs
    assert "4 1.3" in msgs
    assert "False 4" in msgs
    assert ctrl.runtime_state == 1  # finished


def test_threads_run_join_kill_in_controller_time() -> None:
    """A thread counting periods with sync() runs beside the main program; sleep(0.1) is
    50 periods of controller time; join waits for a thread; kill ends one."""
    ctrl = _run(
        "def prog():\n"
        "  global n = 0\n"
        "  global done = False\n"
        "  thread counter():\n"
        "    global n\n"
        "    while True:\n"
        "      n = n + 1\n"
        "      sync()\n"
        "    end\n"
        "  end\n"
        "  thread short():\n"
        "    global done\n"
        "    sleep(0.02)\n"
        "    done = True\n"
        "  end\n"
        "  c = run counter()\n"
        "  s = run short()\n"
        "  sleep(0.1)\n"
        "  kill c\n"
        "  join s\n"
        "  write_output_integer_register(12, n)\n"
        "  textmsg(done)\n"
        "end\n"
    )
    assert _errors(ctrl) == []
    assert ctrl.values["output_int_register_12"] == 50  # one count per 2 ms period
    assert "True" in _messages(ctrl)


def test_moves_read_back_state_and_blend() -> None:
    """movej to a list computed from the arm's state; consecutive blended moves form one
    path (as the controller's lookahead does)."""
    ctrl = _run(
        "def prog():\n"
        "  q = get_actual_joint_positions()\n"
        "  k = 0\n"
        "  while k < 3:\n"
        "    q[0] = q[0] + 0.05\n"
        "    movej(q, a=3, v=1, r=0.001)\n"
        "    k = k + 1\n"
        "  end\n"
        "  q[1] = q[1] + 0.05\n"
        "  movej(q, a=3, v=1)\n"
        "end\n"
    )
    assert _errors(ctrl) == []
    want = np.array(DEFAULT_Q) + np.array([0.15, 0.05, 0, 0, 0, 0])
    np.testing.assert_allclose(ctrl.backend.state().q, want, atol=1e-9)


@pytest.mark.parametrize(
    ("body", "line", "reason"),
    [
        ("  a = [1, 2]\n  b = a[2]\n", 3, "index 2 out of range"),
        ("  x = 1 / 0\n", 2, "division by zero"),
        ("  x = 1\n  if x:\n    y = [1] + 2\n  end\n", 4, "'+' takes numbers"),
        ("  n = 3\n  set_standard_digital_out(n * 3, True)\n", 3, "0..7"),
        ("  while True:\n    x = 1\n  end\n", 2, "infinite loop"),
        ("  q = [0, 0, 0, 0, 0, 0]\n  q[0] = 10\n  movej(p[5, 5, 5, 0, 0, 0])\n", 4,
         "out of reach"),
    ],
)
def test_runtime_errors_stop_the_program_naming_the_line(body: str, line: int, reason: str) -> None:
    ctrl = _run("def prog():\n" + body + "end\n")
    errs = _errors(ctrl)
    assert len(errs) == 1 and f"line {line}" in errs[0] and reason in errs[0], errs
    assert ctrl.runtime_state == 1


def test_an_infinite_loop_is_caught_within_one_period() -> None:
    ctrl = Controller(MODEL)
    assert ctrl.load_script("def spin():\n  i = 0\n  while True:\n    i = i + 1\n  end\nend\n")
    ctrl.tick()
    assert ctrl.runtime_state == 1
    assert f"{MAX_SPIN} iterations" in _errors(ctrl)[0]


def test_a_secondary_program_runs_beside_the_primary() -> None:
    ctrl = Controller(MODEL)
    assert ctrl.load_script("def p():\n  while True:\n    sync()\n  end\nend\n")
    assert ctrl.load_script("sec s():\n  i = 0\n  while i < 3:\n"
                            "    set_standard_digital_out(i, True)\n    i = i + 1\n  end\nend\n")
    ctrl.tick()
    assert ctrl.runtime_state == 2 and ctrl.std_do == 0b111


def test_the_current_line_is_reported_while_a_program_waits() -> None:
    ctrl = Controller(MODEL)
    assert ctrl.load_script("def p():\n  x = 1\n  sleep(1)\n  sleep(1)\nend\n")
    for _ in range(10):
        ctrl.tick()
    assert ctrl._script_line() == 3
    for _ in range(500):
        ctrl.tick()
    assert ctrl._script_line() == 4


def test_sockets_read_binary_integers_and_time_out_in_controller_time() -> None:
    """socket_open connects to a loopback server; socket_read_binary_integer returns
    [n, ...] when the data is there and [0, -1, ...] after its timeout (controller time);
    socket_send_int reaches the server."""
    srv = socket.create_server(("127.0.0.1", 0))
    srv.settimeout(10.0)
    port = srv.getsockname()[1]
    got: list[bytes] = []

    def serve() -> None:
        conn, _ = srv.accept()
        with conn:
            conn.sendall(struct.pack(">3i", 7, -8, 1_000_000))
            conn.settimeout(10.0)
            data = b""
            while len(data) < 4:
                chunk = conn.recv(4 - len(data))
                if not chunk:
                    break
                data += chunk
            got.append(data)

    th = threading.Thread(target=serve, daemon=True)
    th.start()
    try:
        ctrl = _run(
            "def prog():\n"
            f'  ok = socket_open("127.0.0.1", {port}, "pc")\n'
            '  v = socket_read_binary_integer(3, "pc", 2)\n'
            '  w = socket_read_binary_integer(2, "pc", 0.1)\n'
            '  socket_send_int(v[1] + v[2] + v[3], "pc")\n'
            "  textmsg(ok, v)\n"
            "  textmsg(w)\n"
            '  socket_close("pc")\n'
            "end\n",
            ticks=20_000,
        )
        th.join(10.0)
    finally:
        srv.close()
    assert _errors(ctrl) == []
    assert "True [3, 7, -8, 1000000]" in _messages(ctrl)
    assert "[0, -1, -1]" in _messages(ctrl)
    assert got == [struct.pack(">i", 999_999)]


def test_ur_control_loop_example_follows_setpoints_from_registers() -> None:
    """A program in the form of UR's rtde_control_loop example: the PC writes a setpoint
    to input double registers 0-5 and a flag to input int register 0; the program moves
    there and says so in output int register 0 — here the inputs are set directly."""
    text = (
        "def rtde_control_loop():\n"
        "  write_output_integer_register(0, 0)\n"
        "  tmp = [0, 0, 0, 0, 0, 0]\n"
        "  moves = 0\n"
        "  while moves < 2:\n"
        "    if read_input_integer_register(0) == 1:\n"
        "      i = 0\n"
        "      while i < 6:\n"
        "        tmp[i] = read_input_float_register(i)\n"
        "        i = i + 1\n"
        "      end\n"
        "      write_output_integer_register(0, 1)\n"
        "      movej(tmp, a=3, v=1.5)\n"
        "      write_output_integer_register(0, 0)\n"
        "      moves = moves + 1\n"
        "    end\n"
        "    sync()\n"
        "  end\n"
        "end\n"
    )
    ctrl = Controller(MODEL)
    assert ctrl.load_script(text)
    for delta in (0.1, -0.2):
        target = (np.array(DEFAULT_Q) + delta).tolist()
        names = ["input_int_register_0"] + [f"input_double_register_{i}" for i in range(6)]
        ctrl.apply_inputs(dict(zip(names, [1, *target], strict=True)), names)
        for _ in range(5):
            ctrl.tick()
        assert ctrl.values["output_int_register_0"] == 1  # moving
        ctrl.apply_inputs({"input_int_register_0": 0}, ["input_int_register_0"])
        for _ in range(3000):
            ctrl.tick()
            if ctrl.values["output_int_register_0"] == 0:
                break
        np.testing.assert_allclose(ctrl.backend.state().q, target, atol=1e-9)
    for _ in range(3):
        ctrl.tick()
    assert ctrl.runtime_state == 1  # two moves made: the program ended
    assert _errors(ctrl) == []


def test_pose_sub_then_pose_add_gives_the_pose_back() -> None:
    """UR's manual: pose_add multiplies the rotations p_1.R * p_2.R, pose_sub takes
    p_to.R * inv(p_from.R): adding back what was subtracted gives the pose."""
    ctrl = _run(
        "def prog():\n"
        "  a = p[0.1, -0.2, 0.3, 0.4, -1.1, 0.7]\n"
        "  b = p[-0.3, 0.2, 0.5, 1.2, 0.3, -0.5]\n"
        "  c = pose_add(pose_sub(a, b), b)\n"
        "  d = 0\n"
        "  i = 0\n"
        "  while i < 6:\n"
        "    d = d + norm(c[i] - a[i])\n"
        "    i = i + 1\n"
        "  end\n"
        "  write_output_float_register(0, d)\n"
        "end\n"
    )
    assert _errors(ctrl) == []
    assert ctrl.values["output_double_register_0"] < 1e-12


def test_a_paused_move_resumes_to_its_target_on_play() -> None:
    """Found in review: after the dashboard's pause (the arm brakes) and play, the program
    took the braked move for done; a controller resumes the interrupted move."""
    ctrl = Controller(MODEL)
    target = (np.array(DEFAULT_Q) + 0.3).tolist()
    assert ctrl.load_script(f"def p():\n  movej({target}, a=1, v=0.5)\n  textmsg(\"there\")\nend\n")
    for _ in range(200):
        ctrl.tick()
    assert ctrl.pause_program()
    for _ in range(400):
        ctrl.tick()
    stopped = ctrl.backend.state().q.copy()
    assert np.abs(stopped - target).max() > 0.05  # braked on the way
    assert ctrl.play()
    for _ in range(3000):
        ctrl.tick()
        if ctrl.runner is None:
            break
    np.testing.assert_allclose(ctrl.backend.state().q, target, atol=1e-6)
    assert "there" in _messages(ctrl)
