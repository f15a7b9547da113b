"""mpdrig.Rig(..., security=DIR) against `mpdrig serve --security`: a student's identity commands
the student's own rig, may watch a rig the class grants (make-class NAME:WATCH) but not command
it, and cannot even read another student's rig. A class of two students made by
deploy/security/make-class (alice, and bob who may watch alice's rig); loopback, a domain of the
test's own."""

from __future__ import annotations

import os
import pathlib
import subprocess
import time

import pytest

import mpdrig

# Real time at 100 Hz, noise-free sensors: the choke's measured position is exact once it has
# travelled (the actuator's rate limit and lag: a few seconds at most for 20 deg).
RIG_ARGS = ("--clock", "realtime", "--rate-hz", "100", "--sensor-noise", "none",
            "--choke-deg", "31", "--rig", "alice", "--rig", "bob")
# Secure discovery (authentication handshakes) takes a second or two on a loaded machine.
TIMEOUT_S = 30.0


@pytest.fixture
def school(tmp_path: pathlib.Path):
    source = os.environ.get("MPDRIG_SOURCE_DIR")
    if not source:
        pytest.skip("MPDRIG_SOURCE_DIR is not set (run through ctest)")
    out = tmp_path / "class"
    made = subprocess.run([os.path.join(source, "deploy/security/make-class"), str(out),
                           "alice", "bob:alice"], capture_output=True, text=True)
    if made.returncode != 0:
        pytest.fail(f"make-class failed: {made.stderr}")
    return out


def choke_reaches(rig: mpdrig.Rig, deg: float, within_s: float) -> bool:
    until = time.monotonic() + within_s
    while time.monotonic() < until:
        if abs(rig.sensors(fresh=True).choke_position_deg - deg) < 0.01:
            return True
    return False


def test_student_commands_own_rig_and_only_watches_what_the_class_grants(serve, school):
    service = serve("--security", str(school / "service"), *RIG_ARGS)
    with mpdrig.Rig("alice", domain=service.domain, timeout=TIMEOUT_S,
                    security=school / "alice") as alice:
        assert alice.security == str(school / "alice")
        assert alice.sensors().choke_position_deg == pytest.approx(31.0, abs=0.01)
        alice.choke(50.0)
        assert choke_reaches(alice, 50.0, 20.0), "alice's own command did not move her choke"
        # alice may not read bob's rig at all: refused when the readers are made, saying why.
        with pytest.raises(mpdrig.RigError, match="do not allow reading rig 'bob'"):
            mpdrig.Rig("bob", domain=service.domain, timeout=TIMEOUT_S,
                       security=school / "alice")

    # bob may watch alice's rig (bob:alice): he reads it, and his command is refused by DDS
    # Security before it is sent. (After alice's Rig has gone: Cyclone shares one domain
    # instance per domain id in a process, and two identities in one instance do not both
    # complete discovery, so a second identity belongs in a process of its own, as on a second
    # student's machine.)
    with mpdrig.Rig("alice", domain=service.domain, timeout=TIMEOUT_S,
                    security=school / "bob") as watcher:
        assert watcher.sensors(fresh=True).choke_position_deg == pytest.approx(50.0, abs=0.01)
        with pytest.raises(mpdrig.RigError, match="do not allow commanding rig 'alice'"):
            watcher.choke(80.0)
        assert not choke_reaches(watcher, 80.0, 1.0)
        assert watcher.sensors(fresh=True).choke_position_deg == pytest.approx(50.0, abs=0.01)


def test_invalid_identity_directory_is_refused_saying_why(serve, school):
    service = serve("--security", str(school / "service"), *RIG_ARGS)
    with pytest.raises(mpdrig.RigError, match="does not exist"):
        mpdrig.Rig("alice", domain=service.domain, timeout=5, security=school / "nobody")
    # Without security the service's rigs are invisible: no status in any partition.
    with pytest.raises(TimeoutError, match="no rig 'alice'"):
        mpdrig.Rig("alice", domain=service.domain, timeout=3)
