#pragma once

#include <cstddef>
#include <initializer_list>
#include <string>

namespace cblox {

/// Small helpers that write the evaluation results as JSON text: objects with one `"key":
/// value` per line, 2-space indentation, keys in insertion order. They only format; nothing
/// checks that keys are unique.

/// `value` in the shortest form that reads back to the same double (std::to_chars), "null"
/// when it is not finite (JSON has no inf or NaN). Thread-safe (pure).
std::string jsonNumber(double value);

/// `text` as a JSON string literal: quotes, '"' and '\\' escaped, control characters
/// (< 0x20) written as \n, \t, \r or \u00XX; other bytes (UTF-8 included) copied as they are.
/// Thread-safe (pure).
std::string jsonQuoted(const std::string& text);

/// A JSON array of numbers on one line: "[1, 2.5, null]". Thread-safe (pure).
std::string jsonArray(std::initializer_list<double> values);

/// `json` (a value written by JsonObject::close() at indent "", possibly with a trailing
/// newline) re-indented for nesting at `indent`: the trailing newline is dropped and
/// `indent` is inserted after every other newline. Thread-safe (pure).
std::string jsonNest(const std::string& json, const std::string& indent);

/// Builds one JSON object. `indent` is the indentation of the object's own closing brace
/// (the depth at which it is nested); members are written at indent + 2 spaces.
/// Value type; not thread-safe for one object.
class JsonObject {
 public:
  explicit JsonObject(std::string indent) : indent_(std::move(indent)) {}

  /// Adds `"key": value` with `value` already JSON text (an array, a nested object closed
  /// at this object's indent + 2 spaces, "null", ...).
  void raw(const std::string& key, const std::string& value);
  /// Adds a number (jsonNumber()).
  void num(const std::string& key, double value) { raw(key, jsonNumber(value)); }
  /// Adds an unsigned integer, written exactly.
  void count(const std::string& key, size_t value) { raw(key, std::to_string(value)); }
  /// Adds a string (jsonQuoted()).
  void str(const std::string& key, const std::string& value) { raw(key, jsonQuoted(value)); }
  /// Adds true or false.
  void boolean(const std::string& key, bool value) { raw(key, value ? "true" : "false"); }
  /// The object text, "{\n  ...\n<indent>}" ("{}" when empty), without a trailing newline.
  std::string close() const;

 private:
  std::string indent_;
  std::string body_;
};

}  // namespace cblox
