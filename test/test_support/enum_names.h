#pragma once

// Test helper: an enum's name/parse pair round-trips every value and rejects a bad name
// without touching its output. Test-only; thread-safe (no shared state).

#include <initializer_list>
#include <string>

#include <gtest/gtest.h>

namespace cblox::test {

/// For every value v of `values` (at least two): parse(name(v)) succeeds and yields v, even
/// when the output held another value before; parse(bad) fails and leaves the output as it
/// was.
template <typename Enum>
void expectNamesRoundTrip(std::initializer_list<Enum> values, const char* (*name)(Enum),
                          bool (*parse)(const std::string&, Enum*), const std::string& bad) {
  ASSERT_GE(values.size(), 2u);
  const Enum first = *values.begin(), second = *(values.begin() + 1);
  for (const Enum v : values) {
    Enum back = v == first ? second : first;
    ASSERT_TRUE(parse(name(v), &back)) << name(v);
    EXPECT_EQ(back, v) << name(v);
  }
  Enum untouched = first;
  EXPECT_FALSE(parse(bad, &untouched)) << bad;
  EXPECT_EQ(untouched, first);
}

}  // namespace cblox::test
