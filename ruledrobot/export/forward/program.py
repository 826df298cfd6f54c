"""Forwarded execution: the URScript program that plays the plan's samples on the
controller's own clock, and the messages that feed it (docs/rtde.md, "Forwarded
execution").

The PC does not keep the controller's 2 ms beat; the controller does.  The runner sends
:func:`forward_program` to the controller; the program connects back to the runner
(``socket_open``), which sends the plan's samples ahead of time.  The program keeps them in
a ring (:class:`ForwardSettings` ``ring``) and executes one per control period
(``servoj`` with ``t`` = the period: the controller's clock sets the pace), switching the
wire's heat where each sample says.  A PC stall shorter than the buffer changes nothing in
the motion.  When the samples run short — fewer left than a stop along the path needs
(``reserve``) before the last one arrived — the program switches the heat off at once and
decelerates *along the path*: the path parameter's rate falls linearly from one sample per
period to zero over ``stop_time`` s, through the samples it holds; then it holds, reports
the sample where it stopped and ends.  The same controlled stop follows a stop request.

Messages (PC to controller) are 9 big-endian int32 (URScript
``socket_read_binary_integer(9, ...)``): ``[kind, k, level, q1..q6]`` with the joint angles
in micro-radians (:data:`MICRO`); ``kind`` :data:`SAMPLE_COLD` or :data:`SAMPLE_HOT` (a
sample, the heat off or on), :data:`END` (no sample follows), :data:`STOP` (stop along the
path now); ``level`` the heat's analog set-point at the sample in millionths of the
output's range (a scheduled power, :func:`~..heat.written_levels`; 0 otherwise): a program
made with ``levels`` sets the analog output where it changes, as it plays the sample.
The program reports through RTDE output registers: :data:`REG_SAMPLE` the last sample
it commanded (``-1`` before the first), :data:`REG_STATE` one of :class:`State`.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from ...robot.motion.trajectory import Heat
from ..heat import urscript_heat

__all__ = [
    "END",
    "MICRO",
    "REG_SAMPLE",
    "REG_STATE",
    "SAMPLE_COLD",
    "SAMPLE_HOT",
    "STOP",
    "ForwardSettings",
    "State",
    "end_message",
    "forward_program",
    "sample_messages",
    "stop_message",
]

#: joint angles travel in micro-radians (UR's client library uses the same factor)
MICRO = 1_000_000
SAMPLE_COLD, SAMPLE_HOT, END, STOP = 1, 2, 3, 4
#: RTDE output int registers the program reports through (in ur_rtde's receive recipe)
REG_SAMPLE, REG_STATE = 12, 13
#: int32 values per message
WORDS = 9
#: messages the program reads per control period at most (it refills 3 samples a
#: period faster than it plays them)
READS_PER_PERIOD = 4


class State(IntEnum):
    """The program's state (output int register :data:`REG_STATE`)."""

    CONNECTING = 0  #: opening the socket, filling the buffer
    RUNNING = 1  #: playing samples
    DONE = 2  #: the last sample played and the arm at rest there
    DRY = 3  #: the samples ran short: stopped along the path, heat off
    STOPPED = 4  #: stopped along the path on request, heat off
    FAILED = 5  #: no connection to the PC, or no samples in time


@dataclass(frozen=True)
class ForwardSettings:
    """How a forwarded run buffers and stops.

    ``period`` [s]: the control period.  ``buffer`` [s]: the longest PC stall the motion
    rides through unchanged (default 0.5 s).  ``stop_time`` [s]: the controlled stop's
    duration (the path rate falls from 1 to 0 over it; it uses ``stop_time / 2`` of plan
    time).  ``lookahead``, ``gain``: servoj's.
    """

    period: float
    buffer: float = 0.5
    stop_time: float = 0.2
    lookahead: float = 0.1
    gain: float = 300.0

    def __post_init__(self) -> None:
        if not (self.period > 0 and math.isfinite(self.period)):
            raise ValueError(f"period: expected seconds > 0, got {self.period!r}")
        if not (0.05 <= self.buffer <= 5.0):
            raise ValueError(f"buffer: expected 0.05 to 5 s, got {self.buffer!r}")
        if not (0.02 <= self.stop_time <= 2.0):
            raise ValueError(f"stop_time: expected 0.02 to 2 s, got {self.stop_time!r}")

    @property
    def stop_periods(self) -> int:
        """Control periods of the controlled stop."""
        return max(2, math.ceil(self.stop_time / self.period))

    @property
    def reserve(self) -> int:
        """Samples a controlled stop needs ahead of the one playing.

        It covers about half of ``stop_periods``, and two more for the interpolation."""
        return self.stop_periods // 2 + 3

    @property
    def ahead(self) -> int:
        """Samples the runner keeps ahead of the one playing: the buffer and the reserve."""
        return math.ceil(self.buffer / self.period) + self.reserve

    @property
    def ring(self) -> int:
        """Samples the program holds: what the runner keeps ahead, and some slack."""
        return self.ahead + READS_PER_PERIOD + 2


def sample_messages(q: np.ndarray, hot: np.ndarray | None, k0: int,
                    levels: np.ndarray | None = None) -> bytes:  # fmt: skip
    """The messages of samples ``k0, k0 + 1, ...``.

    ``q`` (n, 6) [rad], ``hot`` (n,) or None, ``levels`` (n,) analog set-points in [0, 1]
    or None."""
    q = np.asarray(q, dtype=float).reshape(-1, 6)
    n = q.shape[0]
    out = np.empty((n, WORDS), dtype=">i4")
    out[:, 0] = SAMPLE_COLD if hot is None else np.where(np.asarray(hot, bool), SAMPLE_HOT,
                                                          SAMPLE_COLD)  # fmt: skip
    out[:, 1] = np.arange(k0, k0 + n)
    out[:, 2] = 0 if levels is None else np.rint(np.clip(levels, 0.0, 1.0) * MICRO)
    micro = np.rint(q * MICRO)
    if np.any(np.abs(micro) >= 2**31):
        raise ValueError("forward: a joint angle beyond +-2147 rad cannot be sent")
    out[:, 3:] = micro
    return out.tobytes()


def end_message(k: int) -> bytes:
    """The message that says no sample follows sample ``k - 1``."""
    return struct.pack(f">{WORDS}i", END, int(k), *([0] * (WORDS - 2)))


def stop_message() -> bytes:
    """The message that asks for a controlled stop along the path."""
    return struct.pack(f">{WORDS}i", STOP, *([0] * (WORDS - 1)))


def _heat_set(heat: Heat | None, levels: bool) -> str:
    """The program's ``heat_set(on, l)``: switches the heat where ``on`` changes, or with
    ``levels`` (an analog output with a scheduled power) sets the output to ``l`` (0 when
    not ``on``) where that changes."""
    if levels and heat is not None and heat.kind == "analog":
        return f"""  def heat_set(on, l):
    global heat
    global level
    v = 0.0
    if on:
      v = l
    end
    if v != level:
      set_standard_analog_out({heat.index}, v)
      level = v
    end
    heat = on
  end
"""
    if heat is not None:
        on, off = urscript_heat(heat, True), urscript_heat(heat, False)
    else:
        on = off = "sync()  # no heat output"
    return f"""  def heat_set(on, l):
    global heat
    if on != heat:
      if on:
        {on}
      else:
        {off}
      end
      heat = on
    end
  end
"""


def forward_program(host: str, port: int, settings: ForwardSettings, heat: Heat | None,
                    connect_timeout: float = 10.0, levels: bool = False) -> str:  # fmt: skip
    """Return the URScript program of a forwarded run (module doc).

    It connects to ``host:port`` (the runner), fills its buffer, plays the samples, stops
    along the path when they run short or on request, and reports in :data:`REG_SAMPLE` /
    :data:`REG_STATE`; with ``levels`` it sets ``heat``'s analog output to each sample's
    set-point."""
    s = settings
    ring = s.ring
    prefill = s.ahead
    fill_periods = math.ceil(connect_timeout / s.period)
    hold_periods = math.ceil((10.0 * s.lookahead + 0.5) / s.period)
    servo = f"t={s.period!r}, lookahead_time={s.lookahead!r}, gain={s.gain!r}"
    zeros6 = ", ".join(["0.0"] * (6 * ring))
    falses = ", ".join(["False"] * ring)
    zeros1 = ", ".join(["0.0"] * ring)
    return f"""def rr_forward():
  # ruledrobot forwarded run: the plan's samples arrive ahead of time from {host}:{port}
  # and play on this controller's clock, one per period (docs/rtde.md)
  global RING = {ring}
  global buf = [{zeros6}]
  global hot = [{falses}]
  global lvl = [{zeros1}]
  global head = 0
  global tail = 0
  global ended = False
  global asked = False
  global heat = False
  global level = 0.0
{_heat_set(heat, levels)}  def receive():
    global tail
    global ended
    global asked
    n = 0
    more = True
    while more and n < {READS_PER_PERIOD} and tail - head < RING and not ended and not asked:
      m = socket_read_binary_integer({WORDS}, "rr_fwd", 0)
      if m[0] == 0:
        more = False
      elif m[1] == {END}:
        ended = True
      elif m[1] == {STOP}:
        asked = True
      else:
        j = (tail % RING) * 6
        i = 0
        while i < 6:
          buf[j + i] = m[4 + i] / {float(MICRO)!r}
          i = i + 1
        end
        hot[tail % RING] = m[1] == {SAMPLE_HOT}
        lvl[tail % RING] = m[3] / {float(MICRO)!r}
        tail = tail + 1
      end
      n = n + 1
    end
  end
  def sample(k, f):
    j = (k % RING) * 6
    if f <= 0 or k + 1 >= tail:
      return [buf[j], buf[j + 1], buf[j + 2], buf[j + 3], buf[j + 4], buf[j + 5]]
    end
    l = ((k + 1) % RING) * 6
    return [buf[j] + f * (buf[l] - buf[j]), buf[j + 1] + f * (buf[l + 1] - buf[j + 1]),
            buf[j + 2] + f * (buf[l + 2] - buf[j + 2]), buf[j + 3] + f * (buf[l + 3] - buf[j + 3]),
            buf[j + 4] + f * (buf[l + 4] - buf[j + 4]), buf[j + 5] + f * (buf[l + 5] - buf[j + 5])]
  end
  def settle(q):
    k = 0
    far = True
    while far and k < {hold_periods}:
      servoj(q, {servo})
      a = get_actual_joint_positions()
      i = 0
      far = False
      while i < 6:
        if norm(a[i] - q[i]) > 0.00001:
          far = True
        end
        i = i + 1
      end
      k = k + 1
    end
  end
  write_output_integer_register({REG_SAMPLE}, -1)
  write_output_integer_register({REG_STATE}, {State.CONNECTING.value})
  if not socket_open("{host}", {int(port)}, "rr_fwd"):
    textmsg("ruledrobot forwarding: cannot connect to the runner at {host}:{port}")
    write_output_integer_register({REG_STATE}, {State.FAILED.value})
    halt
  end
  waited = 0
  while tail - head < {prefill} and not ended and not asked:
    receive()
    sync()
    waited = waited + 1
    if waited > {fill_periods}:
      textmsg("ruledrobot forwarding: no samples from the runner in {connect_timeout:g} s")
      write_output_integer_register({REG_STATE}, {State.FAILED.value})
      halt
    end
  end
  write_output_integer_register({REG_STATE}, {State.RUNNING.value})
  last = sample(0, 0)
  while head < tail or not ended:
    receive()
    if asked or (not ended and tail - head < {s.reserve}):
      heat_set(False, 0.0)
      s = head - 1.0
      rate = 1.0
      while rate > 0:
        rate = rate - {1.0 / s.stop_periods!r}
        if rate < 0:
          rate = 0.0
        end
        s = s + rate
        if s < 0:
          s = 0.0
        end
        if s > tail - 1:
          s = tail - 1.0
        end
        k = floor(s)
        last = sample(k, s - k)
        servoj(last, {servo})
        write_output_integer_register({REG_SAMPLE}, k)
      end
      settle(last)
      if asked:
        write_output_integer_register({REG_STATE}, {State.STOPPED.value})
        textmsg("ruledrobot forwarding: stopped along the path on request")
      else:
        write_output_integer_register({REG_STATE}, {State.DRY.value})
        textmsg("ruledrobot forwarding: the samples ran short: stopped along the path")
      end
      socket_close("rr_fwd")
      halt
    end
    heat_set(hot[head % RING], lvl[head % RING])
    last = sample(head, 0)
    servoj(last, {servo})
    write_output_integer_register({REG_SAMPLE}, head)
    head = head + 1
  end
  heat_set(False, 0.0)
  settle(last)
  write_output_integer_register({REG_STATE}, {State.DONE.value})
  socket_close("rr_fwd")
end
"""
