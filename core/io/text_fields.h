#pragma once

// Splitting the comma-separated lines of dataset files, source specs and command arguments.
// Header-only.

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace cblox {

/// `s` without leading and trailing blanks (space, tab, CR, LF). Thread-safe (pure).
inline std::string trimBlanks(const std::string& s) {
  const size_t first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return {};
  const size_t last = s.find_last_not_of(" \t\r\n");
  return s.substr(first, last - first + 1);
}

/// The comma-separated fields of `line`, each trimmed; empty fields are kept ("a,,b" gives
/// three, a trailing comma one more, an empty line none). Thread-safe (pure).
inline std::vector<std::string> splitCommas(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) fields.push_back(trimBlanks(field));
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

/// Exactly `count` finite decimal numbers, comma-separated ("1.5,-2,0.25"; blanks around
/// them allowed), or nullopt with *error saying which field is wrong. Thread-safe (pure).
inline std::optional<std::vector<double>> parseNumbers(const std::string& text, size_t count,
                                                       std::string* error) {
  const std::vector<std::string> fields = splitCommas(text);
  if (fields.size() != count) {
    *error = "expected " + std::to_string(count) + " comma-separated numbers, got '" + text + "'";
    return std::nullopt;
  }
  std::vector<double> values;
  for (const std::string& field : fields) {
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(field.c_str(), &end);
    if (field.empty() || end != field.c_str() + field.size() || errno == ERANGE ||
        !std::isfinite(v)) {
      *error = "'" + field + "' is not a finite number";
      return std::nullopt;
    }
    values.push_back(v);
  }
  return values;
}

}  // namespace cblox
