#include "core/eval/json_writer.h"

#include <charconv>
#include <cmath>
#include <cstdio>

namespace cblox {

std::string jsonNumber(double value) {
  if (!std::isfinite(value)) return "null";
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::string jsonQuoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char escape[8];
          std::snprintf(escape, sizeof(escape), "\\u%04x", static_cast<unsigned char>(c));
          out += escape;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

std::string jsonArray(std::initializer_list<double> values) {
  std::string out = "[";
  for (const double v : values) {
    if (out.size() > 1) out += ", ";
    out += jsonNumber(v);
  }
  return out + "]";
}

std::string jsonNest(const std::string& json, const std::string& indent) {
  std::string text = json;
  while (!text.empty() && text.back() == '\n') text.pop_back();
  std::string out;
  out.reserve(text.size() + text.size() / 8 * indent.size());
  for (const char c : text) {
    out += c;
    if (c == '\n') out += indent;
  }
  return out;
}

void JsonObject::raw(const std::string& key, const std::string& value) {
  if (!body_.empty()) body_ += ",\n";
  body_ += indent_ + "  " + jsonQuoted(key) + ": " + value;
}

std::string JsonObject::close() const {
  if (body_.empty()) return "{}";
  return "{\n" + body_ + "\n" + indent_ + "}";
}

}  // namespace cblox
