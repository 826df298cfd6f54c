"""Outputs set through ur_rtde's IO interface read back through its receive interface as
on a UR controller (issue 31): standard digital outputs are bits 0-7 of
``actual_digital_output_bits``, configurable ones 8-15, tool ones 16-17
(``getDigitalOutState(16)`` is tool output 0: ur_rtde 1.6.5 has no
``getToolDigitalOutState``); analog outputs are ``standard_analog_output0/1``.

ur_rtde's ``io_example`` sets two outputs back to back and reads them 10 ms later.
Its socket runs Nagle's algorithm (the no-delay option is lost when boost::asio's
connect reopens the socket), so the second package waits for the controller's ACK
of the first; the emulator delayed that ACK by Linux's 40 ms timer (an IO
connection gets no data back to carry it), and the second output read back low.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator

import pytest

from ruledrobot.ursim import Emulator
from tests.support.emulators import UR, start_emulator

pytest.importorskip("rtde_io")

#: how long io_example waits before it reads an output back [s]
IO_EXAMPLE_WAIT = 0.01
#: the read-back bound here: io_example's wait with room for this VM's scheduling noise,
#: half of the 40 ms a delayed ACK cost the second package of a burst
READBACK_BOUND = 0.02


def read_back(check: Callable[[], bool], bound: float = READBACK_BOUND) -> float | None:
    """Seconds until ``check()`` holds, polled every millisecond; None beyond ``bound``."""
    t0 = time.perf_counter()
    while True:
        if check():
            return time.perf_counter() - t0
        if time.perf_counter() - t0 > bound:
            return None
        time.sleep(0.001)


@pytest.fixture(params=["ur5e", "ur5"])
def io_ur(request: pytest.FixtureRequest) -> Iterator[tuple[Emulator, UR]]:
    """An emulator (e-Series 500 Hz, CB3 125 Hz) and ur_rtde's interfaces to it."""
    emu = start_emulator(request.node.nodeid, model=request.param)
    u = UR(emu.host)
    try:
        yield emu, u
    finally:
        u.release()
        emu.close()


def test_io_example_reads_back_every_output_of_a_burst(io_ur: tuple[Emulator, UR]) -> None:
    """io_example's pattern: outputs set back to back, read after 10 ms (a real controller
    answers so); every output of each burst reads back, the last as soon as the first."""
    emu, u = io_ur
    io, r = u.io, u.r
    late = []
    for k in range(8):
        on = k % 2 == 0
        assert io.setStandardDigitalOut(7, on)
        assert io.setConfigurableDigitalOut(2, on)
        assert io.setToolDigitalOut(0, on)
        assert io.setToolDigitalOut(1, on)
        assert io.setAnalogOutputVoltage(0, 0.25 if on else 0.75)
        time.sleep(IO_EXAMPLE_WAIT)
        took = read_back(lambda on=on: [r.getDigitalOutState(b) for b in (7, 10, 16, 17)]
                         == [on] * 4 and r.getStandardAnalogOutput0() == (0.25 if on else 0.75))
        if took is None:
            late.append((k, r.getActualDigitalOutputBits(), r.getStandardAnalogOutput0()))
    assert not late, f"bursts not read back within {READBACK_BOUND * 1e3:.0f} ms: {late}"
    # in the controller's own time: each burst reached the outputs within two periods
    period = 0.002 if emu.model_name == "ur5e" else 0.008
    times = [t for t, *_ in emu.io_log]
    bursts = [times[5 * k:5 * k + 5] for k in range(8)]
    assert all(len(b) == 5 and b[-1] - b[0] <= 2 * period + 1e-9 for b in bursts), bursts


def test_each_digital_output_is_its_bit_as_on_a_controller(io_ur: tuple[Emulator, UR]) -> None:
    """Standard 0-7 -> bits 0-7, configurable 0-7 -> bits 8-15, tool 0-1 -> bits 16-17."""
    _, u = io_ur
    io, r = u.io, u.r
    outputs = ([(io.setStandardDigitalOut, n, n) for n in range(8)]
               + [(io.setConfigurableDigitalOut, n, 8 + n) for n in range(8)]
               + [(io.setToolDigitalOut, n, 16 + n) for n in range(2)])  # fmt: skip
    for setter, pin, bit in outputs:
        assert setter(pin, True)
        assert read_back(lambda bit=bit: r.getActualDigitalOutputBits() == 1 << bit) is not None, (
            f"{setter.__name__}({pin}, True): bits {r.getActualDigitalOutputBits():#x}, "
            f"expected bit {bit} alone")  # fmt: skip
        assert r.getDigitalOutState(bit)
        assert not any(r.getDigitalOutState(b) for b in range(18) if b != bit)
        assert setter(pin, False)
        assert read_back(lambda: r.getActualDigitalOutputBits() == 0) is not None
    assert read_back(lambda: not r.getDigitalOutState(16)) is not None


def test_analog_outputs_read_back_as_set(io_ur: tuple[Emulator, UR]) -> None:
    """setAnalogOutputVoltage / setAnalogOutputCurrent (ur_rtde 1.6.5's names; the value is
    the fraction of the range) read back through getStandardAnalogOutput0 / 1."""
    _, u = io_ur
    io, r = u.io, u.r
    for a0, a1 in ((0.3, 0.6), (1.0, 0.0), (0.0, 0.125)):
        assert io.setToolDigitalOut(0, True)  # first in the burst: the analog ones follow it
        assert io.setAnalogOutputVoltage(0, a0)
        assert io.setAnalogOutputCurrent(1, a1)
        took = read_back(lambda a0=a0, a1=a1: r.getStandardAnalogOutput0() == pytest.approx(a0)
                         and r.getStandardAnalogOutput1() == pytest.approx(a1))  # fmt: skip
        assert took is not None, (a0, a1, r.getStandardAnalogOutput0(),
                                  r.getStandardAnalogOutput1())  # fmt: skip
        assert r.getDigitalOutState(16)
