"""The Python module against a running `mpdrig serve`, over loopback DDS, in a domain of the
test's own (claimed like tests/support/test_domain.h, so C++ and Python tests never share one).
ctest sets MPDRIG_EXE (the service) and PYTHONPATH (the build tree's package)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, os.pardir,
                                "support"))
from test_domain import claim_test_domain, claims  # noqa: E402 (tests/support is not a package)

class Service:
    """`mpdrig serve` in a process of its own; stopped with SIGTERM at the end of the test."""

    def __init__(self, *args: str):
        exe = os.environ.get("MPDRIG_EXE")
        if not exe:
            pytest.skip("MPDRIG_EXE is not set (run through ctest)")
        self.domain = claim_test_domain()
        # The domain's lock goes to the service too (its own domain's only): one left running
        # keeps the domain claimed. Its output is not read: discarded, so it never fills a pipe.
        self.process = subprocess.Popen([exe, "serve", "--domain", str(self.domain), *args],
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                        pass_fds=(claims[self.domain],))

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
