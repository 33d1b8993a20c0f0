#pragma once

// Command lines of the cblox programs (CLI11, Debian's libcli11-dev): the parse step with the
// exit statuses every program documents, and a check for number options. The options the
// daemons share are in daemon/common/daemon_options.h.

#include <charconv>
#include <cmath>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

namespace cblox {

/// Makes every option of `app` and of its subcommands take its last value when given more
/// than once (a list option keeps all its values).
inline void takeLastValues(CLI::App& app) {
  for (CLI::Option* option : app.get_options()) {
    option->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  }
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) takeLastValues(*sub);
}

/// Parses the command line into the options of `app` and of its subcommands. An option given
/// more than once takes its last value, as with the hand-written parsers before CLI11
/// (scripts/cblox-launch puts a process's extra arguments after the --config and --lcm-url it
/// passes, so they win). Returns std::nullopt when the program goes on; otherwise the exit
/// status, after CLI11 printed its text: 0 for --help / -h (the usage on stdout), 2 for a
/// usage error (the message on stderr). Call from main().
inline std::optional<int> parseCommandLine(CLI::App& app, int argc, char** argv) {
  takeLastValues(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  return std::nullopt;
}

/// `text`, all of it, as a finite number (std::from_chars); std::nullopt for anything else
/// (inf, nan, trailing characters, an empty text).
inline std::optional<double> parseFiniteNumber(const std::string& text) {
  double value = 0.0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || !std::isfinite(value)) return std::nullopt;
  return value;
}

/// What a number option must be beyond finite.
enum class NumberBound { kPositive, kNonNegative };

/// A CLI11 check of a number option's value: finite (parseFiniteNumber()), and > 0 or >= 0
/// as `bound` says. CLI11 prefixes the message with the option ("--threshold: needs a finite
/// number, got 'abc'"). An integer option still fails on "1.5" when CLI11 converts it.
inline CLI::Validator finiteNumber(NumberBound bound) {
  const bool positive = bound == NumberBound::kPositive;
  return CLI::Validator(
      [positive](const std::string& text) -> std::string {
        const std::optional<double> value = parseFiniteNumber(text);
        if (!value) return "needs a finite number, got '" + text + "'";
        if (positive ? *value > 0.0 : *value >= 0.0) return "";
        return std::string(positive ? "must be > 0" : "must be >= 0") + ", got '" + text + "'";
      },
      positive ? "POSITIVE" : "NONNEGATIVE");
}

}  // namespace cblox
