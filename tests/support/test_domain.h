// A DDS domain id that no other test process on this machine uses while this one runs, so DDS
// tests never collide, however ctest schedules them. Ids 1..232 (0 is left to real services) are
// claimed with an exclusive, non-blocking flock on a file per id in the temp directory; the lock
// is held until the process exits (the kernel releases it even after a crash). Each call claims
// a further id, so tests in one process get distinct domains too. The lock's descriptor is
// inherited by the processes a test starts (no O_CLOEXEC), so a `mpdrig serve` left running by a
// test that crashed keeps its domain claimed until it too is gone, and no later test meets it.
#pragma once

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <string>

namespace mpdrig::testing {

inline int ClaimTestDomain() {
  const std::string dir = std::filesystem::temp_directory_path().string();
  for (int id = 1; id <= 232; ++id) {
    const std::string path = dir + "/mpdrig-test-dds-domain-" + std::to_string(id) + ".lock";
    const int fd = ::open(path.c_str(), O_CREAT | O_RDWR, 0666);  // inherited: see above
    if (fd < 0) continue;
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return id;  // fd stays open: the claim holds
    ::close(fd);
  }
  return -1;  // all taken: the caller's assertion reports it
}

}  // namespace mpdrig::testing
