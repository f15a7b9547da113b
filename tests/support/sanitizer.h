// Whether this test binary is built with AddressSanitizer (deploy/test-sanitize.sh). Tests that
// measure resident memory skip there: ASan keeps freed memory in a quarantine (up to 256 MB) and
// adds shadow memory, so RSS measures the sanitizer, not the code under test. Header-only.
#pragma once

namespace mpdrig::testing {

constexpr bool kUnderAddressSanitizer =
#if defined(__SANITIZE_ADDRESS__)
    true;
#else
    false;
#endif

}  // namespace mpdrig::testing
