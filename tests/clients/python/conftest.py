"""The Python module against a running `mpdrig serve`, over loopback DDS, in a domain of the
test's own (claimed like tests/support/test_domain.h, so C++ and Python tests never share one).
ctest sets MPDRIG_EXE (the service) and PYTHONPATH (the build tree's package)."""

from __future__ import annotations

import fcntl
import os
import subprocess
import tempfile
import time

import pytest

_claims = []  # open lock files: a claim holds while the process lives


def claim_test_domain() -> int:
    for domain in range(1, 233):
        path = os.path.join(tempfile.gettempdir(), f"mpdrig-test-dds-domain-{domain}.lock")
        fd = os.open(path, os.O_CREAT | os.O_RDWR | os.O_CLOEXEC, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            continue
        _claims.append(fd)
        return domain
    raise RuntimeError("no free DDS test domain")


class Service:
    """`mpdrig serve` in a process of its own; stopped with SIGTERM at the end of the test."""

    def __init__(self, *args: str):
        exe = os.environ.get("MPDRIG_EXE")
        if not exe:
            pytest.skip("MPDRIG_EXE is not set (run through ctest)")
        self.domain = claim_test_domain()
        self.process = subprocess.Popen([exe, "serve", "--domain", str(self.domain), *args],
                                        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()


@pytest.fixture
def serve():
    """serve(*args) starts `mpdrig serve --domain <own> *args`; returns it (its .domain)."""
    started = []

    def start(*args: str) -> Service:
        service = Service(*args)
        started.append(service)
        return service

    yield start
    for service in started:
        service.stop()
