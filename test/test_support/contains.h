#pragma once

// Test helpers: gtest assertions that a message or one of a list of lines contains a substring.
// Test-only; thread-safe (no shared state).

#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace cblox::test {

/// Succeeds if `haystack` contains `needle`; the failure message shows both.
inline ::testing::AssertionResult contains(const std::string& haystack, const std::string& needle) {
  if (haystack.find(needle) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "'" << haystack << "' does not contain '" << needle << "'";
}

/// Succeeds if some line of `lines` contains `needle`; the failure message lists the lines.
inline ::testing::AssertionResult containsLine(const std::vector<std::string>& lines,
                                               const std::string& needle) {
  for (const std::string& line : lines) {
    if (line.find(needle) != std::string::npos) return ::testing::AssertionSuccess();
  }
  ::testing::AssertionResult failure = ::testing::AssertionFailure();
  failure << "no line contains '" << needle << "'; lines:";
  for (const std::string& line : lines) failure << "\n  " << line;
  return failure;
}

}  // namespace cblox::test
