#pragma once
/// \file
/// Tests that repeat, many times over, code that a cheaper test already runs skip themselves in
/// the sanitized build (`make test-sanitize`). There the Eigen-heavy inner loops run 15-25 times
/// slower than in the Release build (EstimateLog.MitCsail: 3.7 s -> 89 s), and a statistic over
/// many draws finds no memory error that one draw would not. `make test` runs them all. Each skip
/// names the test that keeps its code under the sanitizers.

#include <gtest/gtest.h>

#if defined(__SANITIZE_ADDRESS__)
#define IFAB_SKIP_WHEN_SANITIZED(covered_by) \
  GTEST_SKIP() << "sanitized build: the same code runs under the sanitizers in " << (covered_by)
#else
#define IFAB_SKIP_WHEN_SANITIZED(covered_by) static_cast<void>(0)
#endif
