// LIVO_SKIP() << "reason": skips a test whose environment is missing (../shared/data, root for a
// network namespace, a tool or library the set-up installs) -- except under CI=true, where that
// environment is provided and a skip would hide a test: there it is a failure naming the reason.
// ctest shows a skip as skipped (tests/test_main.cpp, SKIP_RETURN_CODE in tests/CMakeLists.txt).
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

namespace livo_test {

/// True under CI=true: tests that need root or ../shared/data must run there.
inline bool mustNotSkip() {
  const char* ci = std::getenv("CI");
  return ci != nullptr && std::strcmp(ci, "true") == 0;
}

inline ::testing::TestPartResult::Type skipKind() {
  return mustNotSkip() ? ::testing::TestPartResult::kFatalFailure : ::testing::TestPartResult::kSkip;
}

inline const char* skipPrefix() { return mustNotSkip() ? "CI=true: this test must run, but it would skip: " : ""; }

}  // namespace livo_test

// As GTEST_SKIP() / GTEST_FAIL() (a return from the current void function with a streamed message).
#define LIVO_SKIP()                                                                                          \
  return ::testing::internal::AssertHelper(::livo_test::skipKind(), __FILE__, __LINE__, ::livo_test::skipPrefix()) = \
             ::testing::Message()
