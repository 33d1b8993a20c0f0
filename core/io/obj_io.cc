#include "core/io/obj_io.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <string_view>
#include <vector>

#include "core/io/io_detail.h"

namespace cblox {
namespace {

bool setError(std::string* error, const std::string& message) {
  if (error != nullptr) *error = message;
  return false;
}

// Splits at spaces and tabs into `tokens` (cleared first).
void splitWhitespace(std::string_view line, std::vector<std::string_view>* tokens) {
  tokens->clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) tokens->push_back(line.substr(start, i - start));
  }
}

enum class ParseStatus { kOk, kMalformed, kOutOfRange };

// Parses the whole token as a float ("nan" and "inf" included). Values too small for a float
// become the nearest float (0 or a denormal) instead of failing.
ParseStatus parseFloat(std::string_view token, float* value) {
  const char* begin = token.data();
  const char* end = token.data() + token.size();
  if (begin != end && *begin == '+') ++begin;  // from_chars does not accept a leading '+'
  if (begin == end || *begin == '+') return ParseStatus::kMalformed;
  const auto r = std::from_chars(begin, end, *value);
  if (r.ptr != end) return ParseStatus::kMalformed;
  if (r.ec == std::errc()) return ParseStatus::kOk;
  if (r.ec != std::errc::result_out_of_range) return ParseStatus::kMalformed;
  double d = 0.0;
  const auto rd = std::from_chars(begin, end, d);
  if (rd.ptr == end && (rd.ec == std::errc() || rd.ec == std::errc::result_out_of_range) &&
      std::abs(d) < 1.0) {
    *value = static_cast<float>(d);  // underflow: rounds to 0 or a denormal
    return ParseStatus::kOk;
  }
  return ParseStatus::kOutOfRange;
}

ParseStatus parseInteger(std::string_view token, long long* value) {
  const char* begin = token.data();
  const char* end = token.data() + token.size();
  if (begin != end && *begin == '+') ++begin;
  if (begin == end || *begin == '+') return ParseStatus::kMalformed;
  const auto r = std::from_chars(begin, end, *value);
  if (r.ptr != end) return ParseStatus::kMalformed;
  if (r.ec == std::errc::result_out_of_range) return ParseStatus::kOutOfRange;
  return r.ec == std::errc() ? ParseStatus::kOk : ParseStatus::kMalformed;
}

uint8_t toColorChannel(float value, float scale) {
  const float v = value * scale;
  if (!(v > 0.0f)) return 0;
  if (v >= 255.0f) return 255;
  return static_cast<uint8_t>(std::lround(v));
}

bool isIgnoredKeyword(std::string_view keyword) {
  static constexpr std::string_view kIgnored[] = {"vp",     "o",      "g", "s",
                                                  "usemtl", "mtllib", "l", "p"};
  return std::find(std::begin(kIgnored), std::end(kIgnored), keyword) != std::end(kIgnored);
}

class ObjParser {
 public:
  explicit ObjParser(const std::string& path) : path_(path) {}

  // Parses the whole file; on failure error_ holds the message.
  bool parse(std::string_view data);
  // Moves the result into *mesh and fills *stats (may be null).
  void finish(Mesh* mesh, ObjReadStats* stats);
  const std::string& error() const { return error_; }

 private:
  bool statement(int line, std::string_view text);
  bool vertex(int line);
  bool face(int line);
  bool numbers(int line, size_t min_count, size_t max_count, const char* form);
  // Parses tokens_[i] as a float named `what` (for messages).
  bool number(int line, size_t i, const char* what, float* value);
  // Sets error_ to "<path>:<line>: " followed by the parts.
  bool fail(int line, std::initializer_list<std::string_view> what) {
    error_ = path_;
    error_ += ':';
    error_ += std::to_string(line);
    error_ += ": ";
    for (const std::string_view part : what) error_.append(part);
    return false;
  }

  const std::string& path_;
  std::vector<std::string_view> tokens_;
  std::vector<int> corners_;
  std::vector<Eigen::Vector3f> vertices_;
  std::vector<std::array<float, 3>> raw_colors_;  // one per vertex; zeros when it had none
  std::vector<Eigen::Vector3i> triangles_;
  size_t colored_vertices_ = 0;
  bool colors_above_one_ = false;
  ObjReadStats stats_;
  std::string error_;
};

bool ObjParser::parse(std::string_view data) {
  size_t pos = 0;
  int line_number = 0;
  std::string joined;  // a statement continued over several lines
  int joined_line = 0;
  bool continuing = false;
  while (pos < data.size()) {
    size_t eol = data.find('\n', pos);
    if (eol == std::string_view::npos) eol = data.size();
    std::string_view line = data.substr(pos, eol - pos);
    pos = eol + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.find('\0') != std::string_view::npos) {
      return fail(line_number, {"NUL byte: binary data, not a text OBJ file"});
    }
    if (!line.empty() && line.back() == '\\') {
      if (!continuing) {
        joined.clear();
        joined_line = line_number;
        continuing = true;
      }
      joined.append(line.substr(0, line.size() - 1));
      joined += ' ';
      continue;
    }
    if (continuing) {
      joined.append(line);
      continuing = false;
      if (!statement(joined_line, joined)) return false;
    } else if (!statement(line_number, line)) {
      return false;
    }
  }
  if (continuing && !statement(joined_line, joined)) return false;
  return true;
}

bool ObjParser::statement(int line, std::string_view text) {
  const size_t comment = text.find('#');
  if (comment != std::string_view::npos) text = text.substr(0, comment);
  splitWhitespace(text, &tokens_);
  if (tokens_.empty()) return true;
  const std::string_view keyword = tokens_[0];
  if (keyword == "v") return vertex(line);
  if (keyword == "f") return face(line);
  if (keyword == "vt") {
    ++stats_.ignored_statements;
    return numbers(line, 1, 3, "'vt u [v [w]]'");
  }
  if (keyword == "vn") {
    ++stats_.ignored_statements;
    return numbers(line, 3, 3, "'vn x y z'");
  }
  if (isIgnoredKeyword(keyword)) {
    ++stats_.ignored_statements;
    return true;
  }
  if (stats_.unknown_statements++ == 0) {
    stats_.first_unknown_keyword = std::string(keyword);
    stats_.first_unknown_line = line;
  }
  return true;
}

bool ObjParser::number(int line, size_t i, const char* what, float* value) {
  switch (parseFloat(tokens_[i], value)) {
    case ParseStatus::kOk:
      return true;
    case ParseStatus::kOutOfRange:
      return fail(
          line, {"'", tokens_[0], "': ", what, " value '", tokens_[i], "' is out of float range"});
    case ParseStatus::kMalformed:
      break;
  }
  return fail(line,
              {"'", tokens_[0], "': expected a number for ", what, ", found '", tokens_[i], "'"});
}

bool ObjParser::numbers(int line, size_t min_count, size_t max_count, const char* form) {
  const size_t count = tokens_.size() - 1;
  if (count < min_count || count > max_count) {
    return fail(line, {"expected ", form, ", found ", std::to_string(count), " values"});
  }
  for (size_t i = 1; i < tokens_.size(); ++i) {
    float unused = 0.0f;
    const std::string what = "value " + std::to_string(i);
    if (!number(line, i, what.c_str(), &unused)) return false;
  }
  return true;
}

bool ObjParser::vertex(int line) {
  const size_t count = tokens_.size() - 1;
  if (count != 3 && count != 4 && count != 6) {
    return fail(line, {"expected 'v x y z [w]' or 'v x y z r g b', found ", std::to_string(count),
                       " values"});
  }
  static constexpr const char* kNames[] = {"x", "y", "z", "w"};
  static constexpr const char* kColorNames[] = {"red", "green", "blue"};
  Eigen::Vector3f p;
  for (int k = 0; k < 3; ++k) {
    if (!number(line, static_cast<size_t>(k) + 1, kNames[k], &p[k])) return false;
  }
  std::array<float, 3> color = {0.0f, 0.0f, 0.0f};
  if (count == 4) {
    float w = 0.0f;
    if (!number(line, 4, kNames[3], &w)) return false;
  } else if (count == 6) {
    for (size_t k = 0; k < 3; ++k) {
      if (!number(line, k + 4, kColorNames[k], &color[k])) return false;
      if (!std::isfinite(color[k])) {
        return fail(
            line, {"'v': colour value ", kColorNames[k], " '", tokens_[k + 4], "' is not finite"});
      }
      if (color[k] > 1.0f) colors_above_one_ = true;
    }
    ++colored_vertices_;
  }
  if (vertices_.size() >= static_cast<size_t>(std::numeric_limits<int>::max())) {
    return fail(line, {"too many vertices (more than ",
                       std::to_string(std::numeric_limits<int>::max()), ")"});
  }
  vertices_.push_back(p);
  raw_colors_.push_back(color);
  return true;
}

bool ObjParser::face(int line) {
  const size_t count = tokens_.size() - 1;
  if (count < 3) {
    return fail(line, {"face has ", std::to_string(count), " corners, expected at least 3"});
  }
  const auto num_vertices = static_cast<long long>(vertices_.size());
  corners_.clear();
  for (size_t c = 1; c < tokens_.size(); ++c) {
    const std::string_view corner = tokens_[c];
    // Split "i[/[t][/n]]" into at most three fields.
    std::string_view fields[3];
    size_t num_fields = 0;
    size_t start = 0;
    while (true) {
      const size_t slash = corner.find('/', start);
      if (num_fields == 3) {
        return fail(line, {"face corner '", corner,
                           "' has more than three '/'-separated fields, expected i, i/t, i//n "
                           "or i/t/n"});
      }
      fields[num_fields++] = corner.substr(
          start, slash == std::string_view::npos ? std::string_view::npos : slash - start);
      if (slash == std::string_view::npos) break;
      start = slash + 1;
    }
    long long index = 0;
    const ParseStatus status = parseInteger(fields[0], &index);
    if (status == ParseStatus::kMalformed) {
      return fail(line, {"face corner '", corner, "': expected an integer vertex index, found '",
                         fields[0], "'"});
    }
    if (status == ParseStatus::kOk && index == 0) {
      return fail(line, {"face corner '", corner,
                         "': vertex index 0 is invalid (OBJ indices count from 1)"});
    }
    if (status == ParseStatus::kOutOfRange || index > num_vertices || -index > num_vertices) {
      return fail(line, {"face corner '", corner, "': vertex index ", fields[0],
                         " is out of range: ", std::to_string(num_vertices),
                         " vertices defined so far (indices count from 1, negative ones back "
                         "from the last vertex)"});
    }
    // Texture and normal indices: checked, not used. Only "i//n" may leave t empty.
    for (size_t f = 1; f < num_fields; ++f) {
      const char* name = f == 1 ? "texture" : "normal";
      if (fields[f].empty() && f == 1 && num_fields == 3) continue;
      long long unused = 0;
      if (parseInteger(fields[f], &unused) != ParseStatus::kOk || unused == 0) {
        return fail(line, {"face corner '", corner, "': expected a non-zero integer ", name,
                           " index, found '", fields[f], "'"});
      }
    }
    corners_.push_back(static_cast<int>(index > 0 ? index - 1 : num_vertices + index));
  }
  for (size_t k = 1; k + 1 < corners_.size(); ++k) {
    triangles_.emplace_back(corners_[0], corners_[k], corners_[k + 1]);
  }
  ++stats_.faces;
  return true;
}

void ObjParser::finish(Mesh* mesh, ObjReadStats* stats) {
  Mesh out;
  out.vertices = std::move(vertices_);
  out.triangles = std::move(triangles_);
  if (colored_vertices_ > 0 && colored_vertices_ == out.vertices.size()) {
    const float scale = colors_above_one_ ? 1.0f : 255.0f;
    out.colors.reserve(raw_colors_.size());
    for (const std::array<float, 3>& c : raw_colors_) {
      out.colors.push_back(Color{toColorChannel(c[0], scale), toColorChannel(c[1], scale),
                                 toColorChannel(c[2], scale)});
    }
  }
  stats_.vertices = out.vertices.size();
  stats_.triangles = out.triangles.size();
  stats_.colors_dropped = colored_vertices_ > 0 && colored_vertices_ < out.vertices.size();
  if (stats != nullptr) *stats = std::move(stats_);
  *mesh = std::move(out);
}

}  // namespace

bool readObj(const std::string& path, Mesh* mesh, std::string* error, ObjReadStats* stats) {
  std::string data;
  if (!io_detail::readWholeFile(path, &data, error)) return false;

  ObjParser parser(path);
  if (!parser.parse(data)) return setError(error, parser.error());
  parser.finish(mesh, stats);
  return true;
}

bool writeObj(const std::string& path, const Mesh& mesh, std::string* error) {
  const std::string invalid = mesh.validate();
  if (!invalid.empty()) return setError(error, path + ": cannot write OBJ: " + invalid);
  const bool colors = mesh.hasColors();

  io_detail::BufferedFileWriter writer;
  if (!writer.open(path, error)) return false;
  std::string& out = writer.buffer();
  out += "# written by cblox: ";
  out += std::to_string(mesh.numVertices());
  out += colors ? " vertices (with r g b colours in [0, 1]), " : " vertices, ";
  out += std::to_string(mesh.numTriangles());
  out += " triangles\n";

  for (size_t i = 0; i < mesh.numVertices(); ++i) {
    const Eigen::Vector3f& p = mesh.vertices[i];
    out += 'v';
    for (int k = 0; k < 3; ++k) {
      out += ' ';
      io_detail::appendFloatText(&out, p[k]);
    }
    if (colors) {
      const Color& c = mesh.colors[i];
      for (const uint8_t channel : {c.r, c.g, c.b}) {
        out += ' ';
        io_detail::appendFloatText(&out, static_cast<float>(channel) / 255.0f);
      }
    }
    out += '\n';
    if (!writer.flushIfFull()) break;
  }
  for (size_t i = 0; i < mesh.numTriangles() && writer.good(); ++i) {
    const Eigen::Vector3i& t = mesh.triangles[i];
    out += 'f';
    for (int k = 0; k < 3; ++k) {
      out += ' ';
      io_detail::appendIntText(&out, static_cast<long long>(t[k]) + 1);
    }
    out += '\n';
    if (!writer.flushIfFull()) break;
  }
  return writer.close(error);
}

}  // namespace cblox
