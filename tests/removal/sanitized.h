// Whether the test runs under AddressSanitizer. `make test-sanitize` links the tests with it
// while their own sources keep the Release build's flags (so that ccache serves them from that
// build), so it is asked at run time: ASan's runtime defines __asan_init.
//
// The sanitized run looks for memory errors and undefined behaviour on the code's paths; the
// heaviest brute-force checks (the library instrumented at -O1 runs them 8-10x slower) take a
// regular sample of their cases there and all of them in the Release run.
#pragma once

extern "C" void __asan_init() __attribute__((weak));

namespace vcut::removal::test {

inline bool sanitized() { return &__asan_init != nullptr; }

}  // namespace vcut::removal::test
