#pragma once

// Splitting the comma-separated lines of dataset files and source specs. Header-only.

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

}  // namespace cblox
