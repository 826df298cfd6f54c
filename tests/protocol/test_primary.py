"""The primary-interface reader on packets built from UR's documented layout."""

from __future__ import annotations

import socket
import struct
import threading
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.protocol.primary import (
    KINEMATICS_INFO,
    KinematicsInfo,
    PrimaryProtocolError,
    Version,
    kinematics_info_subpackage,
    parse_kinematics_info,
    parse_robot_state,
    read_kinematics_info,
    robot_state_message,
    split_messages,
    version_message,
)

THETA = [1e-4, -2e-4, 3e-4, 0.0, 1e-5, -1e-5]
A = [0.0, -0.42503, -0.39216, 0.0, 0.0, 0.0]
D = [0.16251, 0.0, 0.0, 0.13329, 0.09970, 0.09961]
ALPHA = [1.5708, 0.0, 0.0, 1.5708, -1.5708, 0.0]


def _by_hand(checksum=(11, 22, 33, 44, 55, 66), status=1) -> bytes:
    """A robot-state message with a joint-data stub and KinematicsInfo, packed by hand
    from the documented layout (independent of the module's builder)."""
    stub = struct.pack(">IB", 5 + 3, 1) + b"\x00\x01\x02"
    body = struct.pack(">6I", *checksum) + struct.pack(">24d", *THETA, *A, *D, *ALPHA)
    body += struct.pack(">I", status)
    kin = struct.pack(">IB", 5 + len(body), 5) + body
    payload = stub + kin
    return struct.pack(">iB", 5 + len(payload), 16) + payload


def test_documented_layout_is_read():
    msgs, rest = split_messages(_by_hand())
    assert rest == b"" and len(msgs) == 1 and msgs[0][0] == 16
    subs = parse_robot_state(msgs[0][1])
    assert set(subs) == {1, 5} and len(subs[5]) == 220
    info = parse_kinematics_info(subs[KINEMATICS_INFO])
    assert info.checksum == (11, 22, 33, 44, 55, 66) and info.calibration_status == 1
    np.testing.assert_array_equal(info.dh(), np.stack([THETA, A, D, ALPHA], axis=1))


def test_builder_matches_the_hand_packed_layout():
    info = KinematicsInfo((11, 22, 33, 44, 55, 66), np.array(THETA), np.array(A), np.array(D),
                          np.array(ALPHA), 1)  # fmt: skip
    stub = struct.pack(">IB", 8, 1) + b"\x00\x01\x02"
    assert robot_state_message([stub, kinematics_info_subpackage(info)]) == _by_hand()


@settings(max_examples=50, deadline=None)
@given(cut=st.integers(min_value=0, max_value=len(_by_hand()) - 1))
def test_a_message_split_anywhere_waits_for_the_rest(cut):
    data = _by_hand()
    msgs, rest = split_messages(data[:cut])
    assert msgs == [] and rest == data[:cut]
    msgs, rest = split_messages(rest + data[cut:])
    assert len(msgs) == 1 and rest == b""


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (struct.pack(">iB", 3, 16), r"size field 3 outside"),
        (struct.pack(">iB", 1 << 30, 16), r"size field 1073741824 outside"),
        (struct.pack(">iB", -5, 16), r"size field -5 outside"),
    ],
)
def test_bad_sizes_are_refused(data, message):
    with pytest.raises(PrimaryProtocolError, match=message):
        split_messages(data)


def test_truncated_and_wrong_sub_packages_are_refused():
    body = split_messages(_by_hand())[0][0][1]
    with pytest.raises(PrimaryProtocolError, match="sub-package type 5 at byte 8"):
        parse_robot_state(body[:-1])
    with pytest.raises(PrimaryProtocolError, match="truncated sub-package header"):
        parse_robot_state(body + b"\x00\x00")
    with pytest.raises(PrimaryProtocolError, match="224 bytes, expected 225"):
        parse_kinematics_info(parse_robot_state(body)[5][:-1])
    nan = struct.pack(">6I", *range(6)) + struct.pack(">24d", *([float("nan")] * 24)) + b"\0" * 4
    with pytest.raises(PrimaryProtocolError, match="NaN"):
        parse_kinematics_info(nan)


class _Server:
    """A loopback controller stand-in that sends ``chunks`` then stays silent."""

    def __init__(self, chunks: list[bytes], close: bool = False) -> None:
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(1)
        self.port = self.sock.getsockname()[1]
        self.chunks, self.close = chunks, close
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        self.sock.settimeout(5)
        try:
            conn, _ = self.sock.accept()
        except OSError:
            return
        with conn:
            for c in self.chunks:
                conn.sendall(c)
                time.sleep(0.01)
            if not self.close:
                time.sleep(1.5)

    def __enter__(self) -> _Server:
        return self

    def __exit__(self, *exc: object) -> None:
        self.sock.close()
        self.thread.join(3)


def test_reader_gets_version_and_kinematics_from_a_stream():
    v = version_message(Version("URControl", 5, 15, 2, 1234, "Nov 1 2024"))
    data = v + _by_hand()
    with _Server([data[:7], data[7:300], data[300:]]) as srv:
        info, version = read_kinematics_info("127.0.0.1", srv.port, timeout=2.0)
    assert version is not None and version.text == "5.15.2.1234" and version.project == "URControl"
    assert info.checksum == (11, 22, 33, 44, 55, 66)


def test_reader_gives_up_on_a_silent_controller_within_its_deadline():
    with _Server([]) as srv:
        t0 = time.monotonic()
        with pytest.raises(TimeoutError, match=r"no KinematicsInfo within 0\.5 s"):
            read_kinematics_info("127.0.0.1", srv.port, timeout=0.5)
        assert time.monotonic() - t0 < 1.0


def test_reader_refuses_garbage_and_early_close():
    with _Server([b"\xff" * 64]) as srv:
        with pytest.raises(PrimaryProtocolError, match="size field"):
            read_kinematics_info("127.0.0.1", srv.port, timeout=2.0)
    with _Server([version_message(Version("URControl", 5, 1, 0, 0))], close=True) as srv:
        with pytest.raises(PrimaryProtocolError, match="closed the connection"):
            read_kinematics_info("127.0.0.1", srv.port, timeout=2.0)
