"""tests/support/test_domain.h for the Python tests: a DDS domain id (1..232) that no other test
process on this machine uses while this one runs, claimed with the same lock files, so C++ and
Python tests never share one. The claim holds while the lock file stays open (the kernel releases
it when the process is gone). Python opens it non-inheritable, so pass the domain's lock to the
child that serves it (subprocess.Popen(..., pass_fds=(claims[domain],))) for a child left running
to keep the domain claimed, as the C++ tests' children do."""

import fcntl
import os
import tempfile

claims = {}  # domain -> its open lock file


def claim_test_domain() -> int:
    for domain in range(1, 233):
        path = os.path.join(tempfile.gettempdir(), f"mpdrig-test-dds-domain-{domain}.lock")
        try:
            fd = os.open(path, os.O_CREAT | os.O_RDWR | os.O_CLOEXEC, 0o666)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            continue
        claims[domain] = fd
        return domain
    raise RuntimeError("every test DDS domain is taken")
