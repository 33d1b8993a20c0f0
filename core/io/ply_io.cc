#include "core/io/ply_io.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <limits>
#include <sstream>
#include <string_view>
#include <vector>

#include "core/io/io_detail.h"

namespace cblox {
namespace {

// ---------------------------------------------------------------------------------------
// Shared helpers

bool setError(std::string* error, const std::string& message) {
  if (error != nullptr) *error = message;
  return false;
}

template <typename T>
T byteSwap(T value) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  std::reverse(std::begin(bytes), std::end(bytes));
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

enum class ScalarType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

bool parseScalarType(std::string_view name, ScalarType* type) {
  struct Entry {
    std::string_view name;
    ScalarType type;
  };
  static constexpr Entry kTypes[] = {
      {"char", ScalarType::kInt8},      {"int8", ScalarType::kInt8},
      {"uchar", ScalarType::kUint8},    {"uint8", ScalarType::kUint8},
      {"short", ScalarType::kInt16},    {"int16", ScalarType::kInt16},
      {"ushort", ScalarType::kUint16},  {"uint16", ScalarType::kUint16},
      {"int", ScalarType::kInt32},      {"int32", ScalarType::kInt32},
      {"uint", ScalarType::kUint32},    {"uint32", ScalarType::kUint32},
      {"float", ScalarType::kFloat32},  {"float32", ScalarType::kFloat32},
      {"double", ScalarType::kFloat64}, {"float64", ScalarType::kFloat64}};
  for (const Entry& e : kTypes) {
    if (e.name == name) {
      *type = e.type;
      return true;
    }
  }
  return false;
}

size_t scalarSize(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
    case ScalarType::kUint8:
      return 1;
    case ScalarType::kInt16:
    case ScalarType::kUint16:
      return 2;
    case ScalarType::kInt32:
    case ScalarType::kUint32:
    case ScalarType::kFloat32:
      return 4;
    case ScalarType::kFloat64:
      return 8;
  }
  return 0;
}

bool isFloatType(ScalarType type) {
  return type == ScalarType::kFloat32 || type == ScalarType::kFloat64;
}

const char* scalarTypeName(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
      return "char";
    case ScalarType::kUint8:
      return "uchar";
    case ScalarType::kInt16:
      return "short";
    case ScalarType::kUint16:
      return "ushort";
    case ScalarType::kInt32:
      return "int";
    case ScalarType::kUint32:
      return "uint";
    case ScalarType::kFloat32:
      return "float";
    case ScalarType::kFloat64:
      return "double";
  }
  return "?";
}

// Range of an integer type, as doubles (exact for all PLY integer types).
void integerRange(ScalarType type, double* lo, double* hi) {
  switch (type) {
    case ScalarType::kInt8:
      *lo = -128.0, *hi = 127.0;
      return;
    case ScalarType::kUint8:
      *lo = 0.0, *hi = 255.0;
      return;
    case ScalarType::kInt16:
      *lo = -32768.0, *hi = 32767.0;
      return;
    case ScalarType::kUint16:
      *lo = 0.0, *hi = 65535.0;
      return;
    case ScalarType::kInt32:
      *lo = -2147483648.0, *hi = 2147483647.0;
      return;
    case ScalarType::kUint32:
      *lo = 0.0, *hi = 4294967295.0;
      return;
    default:
      *lo = -std::numeric_limits<double>::infinity();
      *hi = std::numeric_limits<double>::infinity();
  }
}

enum class BodyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct Property {
  std::string name;
  bool is_list = false;
  ScalarType type = ScalarType::kFloat32;      // item type for lists
  ScalarType count_type = ScalarType::kUint8;  // lists only
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
  int header_line = 0;
};

struct Header {
  BodyFormat format = BodyFormat::kAscii;
  std::vector<Element> elements;
  size_t body_offset = 0;  // byte offset of the first body byte
  int body_line = 0;       // line number of the first body line (ASCII)
};

std::vector<std::string_view> splitWhitespace(std::string_view line) {
  std::vector<std::string_view> tokens;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

// ---------------------------------------------------------------------------------------
// Header

bool parseHeader(const std::string& path, std::string_view data, Header* header,
                 std::string* error) {
  const auto where = [&path](int line) {
    return path + ": header line " + std::to_string(line) + ": ";
  };
  size_t pos = 0;
  int line_number = 0;
  bool have_format = false;
  while (true) {
    if (pos >= data.size()) {
      if (line_number == 0) return setError(error, path + ": file is empty, expected a PLY file");
      return setError(error, path + ": header ends at line " + std::to_string(line_number) +
                                 " without 'end_header'");
    }
    const size_t eol = data.find('\n', pos);
    if (eol == std::string_view::npos) {
      return setError(error, path + ": header ends at line " + std::to_string(line_number + 1) +
                                 " without 'end_header'");
    }
    std::string_view line = data.substr(pos, eol - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos = eol + 1;
    ++line_number;
    if (line_number == 1) {
      if (line != "ply") {
        return setError(error, path + ": not a PLY file (the first line must be 'ply')");
      }
      continue;
    }
    const std::vector<std::string_view> tok = splitWhitespace(line);
    if (tok.empty()) continue;
    const std::string_view keyword = tok[0];
    if (keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "format") {
      if (tok.size() != 3) {
        return setError(error, where(line_number) +
                                   "expected 'format <ascii|binary_little_endian|"
                                   "binary_big_endian> 1.0'");
      }
      if (tok[1] == "ascii") {
        header->format = BodyFormat::kAscii;
      } else if (tok[1] == "binary_little_endian") {
        header->format = BodyFormat::kBinaryLittleEndian;
      } else if (tok[1] == "binary_big_endian") {
        header->format = BodyFormat::kBinaryBigEndian;
      } else {
        return setError(error, where(line_number) + "unknown format '" + std::string(tok[1]) + "'");
      }
      if (tok[2] != "1.0") {
        return setError(error, where(line_number) + "unsupported PLY version '" +
                                   std::string(tok[2]) + "', expected 1.0");
      }
      have_format = true;
    } else if (keyword == "element") {
      uint64_t count = 0;
      if (tok.size() != 3 ||
          std::from_chars(tok[2].data(), tok[2].data() + tok[2].size(), count).ec != std::errc() ||
          std::from_chars(tok[2].data(), tok[2].data() + tok[2].size(), count).ptr !=
              tok[2].data() + tok[2].size()) {
        return setError(error, where(line_number) +
                                   "expected 'element <name> <count>' with a non-negative "
                                   "integer count");
      }
      Element element;
      element.name = std::string(tok[1]);
      element.count = count;
      element.header_line = line_number;
      header->elements.push_back(std::move(element));
    } else if (keyword == "property") {
      if (header->elements.empty()) {
        return setError(error, where(line_number) + "'property' before any 'element'");
      }
      Property property;
      if (tok.size() == 5 && tok[1] == "list") {
        property.is_list = true;
        if (!parseScalarType(tok[2], &property.count_type) ||
            !parseScalarType(tok[3], &property.type)) {
          return setError(error, where(line_number) + "unknown type in 'property list " +
                                     std::string(tok[2]) + " " + std::string(tok[3]) + "'");
        }
        if (isFloatType(property.count_type)) {
          return setError(error, where(line_number) + "list count type must be an integer type");
        }
        property.name = std::string(tok[4]);
      } else if (tok.size() == 3 && tok[1] != "list") {
        if (!parseScalarType(tok[1], &property.type)) {
          return setError(
              error, where(line_number) + "unknown property type '" + std::string(tok[1]) + "'");
        }
        property.name = std::string(tok[2]);
      } else {
        return setError(error, where(line_number) +
                                   "expected 'property <type> <name>' or 'property list "
                                   "<count type> <item type> <name>'");
      }
      header->elements.back().properties.push_back(std::move(property));
    } else if (keyword == "end_header") {
      if (!have_format) return setError(error, where(line_number) + "no 'format' line before it");
      header->body_offset = pos;
      header->body_line = line_number + 1;
      return true;
    } else {
      return setError(error, where(line_number) + "unknown keyword '" + std::string(keyword) + "'");
    }
  }
}

// ---------------------------------------------------------------------------------------
// Body readers: deliver the values of one element instance in property order.

class BinaryReader {
 public:
  BinaryReader(std::string_view data, bool swap) : data_(data), swap_(swap) {}

  bool atEnd() const { return pos_ >= data_.size(); }
  size_t remaining() const { return data_.size() - pos_; }
  bool startElement() { return true; }
  bool endElement() { return true; }

  // False on truncation.
  bool read(ScalarType type, double* value) {
    const size_t size = scalarSize(type);
    if (data_.size() - pos_ < size) return false;
    const char* p = data_.data() + pos_;
    pos_ += size;
    switch (type) {
      case ScalarType::kInt8:
        *value = get<int8_t>(p);
        break;
      case ScalarType::kUint8:
        *value = get<uint8_t>(p);
        break;
      case ScalarType::kInt16:
        *value = get<int16_t>(p);
        break;
      case ScalarType::kUint16:
        *value = get<uint16_t>(p);
        break;
      case ScalarType::kInt32:
        *value = get<int32_t>(p);
        break;
      case ScalarType::kUint32:
        *value = get<uint32_t>(p);
        break;
      case ScalarType::kFloat32:
        *value = get<float>(p);
        break;
      case ScalarType::kFloat64:
        *value = get<double>(p);
        break;
    }
    return true;
  }

 private:
  template <typename T>
  T get(const char* p) const {
    T v;
    std::memcpy(&v, p, sizeof(T));
    return swap_ ? byteSwap(v) : v;
  }

  std::string_view data_;
  bool swap_;
  size_t pos_ = 0;
};

// ---------------------------------------------------------------------------------------
// Reading

struct VertexLayout {
  int x = -1, y = -1, z = -1, nx = -1, ny = -1, nz = -1, r = -1, g = -1, b = -1;
};

uint8_t toColorChannel(double v, ScalarType type) {
  if (isFloatType(type)) v *= 255.0;
  if (!(v > 0.0)) return 0;  // also NaN
  if (v >= 255.0) return 255;
  return static_cast<uint8_t>(std::lround(v));
}

class PlyParser {
 public:
  PlyParser(const std::string& path, std::string_view body, const Header& header)
      : path_(path), body_(body), header_(header) {}

  bool parse(Mesh* mesh, std::string* error);

 private:
  // What a value is, for error messages (built only on failure).
  struct What {
    const Property* property;
    int kind;       // 0 scalar, 1 list count, 2 list item
    uint64_t item;  // kind 2
    std::string text() const;
  };
  // Reads one value of `type`; fills error_ and returns false on failure.
  bool value(ScalarType type, const What& what, double* v);
  bool beginInstance();
  bool endInstance();
  std::string location() const;
  bool fail(const std::string& message) {
    error_ = location() + message;
    return false;
  }

  const std::string& path_;
  std::string_view body_;
  const Header& header_;
  bool ascii_ = false;
  BinaryReader binary_{{}, false};
  // ASCII state.
  size_t pos_ = 0;
  int line_ = 0;
  std::vector<std::string_view> tokens_;
  size_t token_ = 0;
  // Current element.
  const Element* element_ = nullptr;
  uint64_t instance_ = 0;
  std::string error_;
};

std::string PlyParser::location() const {
  std::ostringstream s;
  s << path_ << ": ";
  if (ascii_) s << "line " << line_ << ": ";
  if (element_ != nullptr) {
    s << "element '" << element_->name << "' #" << instance_ << " of " << element_->count << ": ";
  }
  return s.str();
}

bool PlyParser::beginInstance() {
  if (!ascii_) return true;
  // One instance per line; blank lines are skipped.
  while (true) {
    if (pos_ >= body_.size()) {
      ++line_;
      return fail("unexpected end of file (ASCII data truncated)");
    }
    size_t eol = body_.find('\n', pos_);
    if (eol == std::string_view::npos) eol = body_.size();
    const std::string_view line = body_.substr(pos_, eol - pos_);
    pos_ = eol + 1;
    ++line_;
    tokens_ = splitWhitespace(line);
    token_ = 0;
    if (!tokens_.empty()) return true;
  }
}

bool PlyParser::endInstance() {
  if (!ascii_ || token_ == tokens_.size()) return true;
  return fail("expected " + std::to_string(token_) + " values on the line, found " +
              std::to_string(tokens_.size()));
}

std::string PlyParser::What::text() const {
  switch (kind) {
    case 0:
      return "property '" + property->name + "'";
    case 1:
      return "the count of list '" + property->name + "'";
    default:
      return "item " + std::to_string(item) + " of list '" + property->name + "'";
  }
}

bool PlyParser::value(ScalarType type, const What& what_info, double* v) {
  if (!ascii_) {
    if (!binary_.read(type, v)) {
      return fail("unexpected end of file while reading " + what_info.text() +
                  " (binary data truncated)");
    }
    return true;
  }
  if (token_ >= tokens_.size()) {
    return fail("missing value for " + what_info.text() + ": the line has only " +
                std::to_string(tokens_.size()) + " values");
  }

  const std::string_view tok = tokens_[token_++];
  const char* begin = tok.data();
  const char* end = tok.data() + tok.size();
  if (*begin == '+') ++begin;  // from_chars does not accept a leading '+'
  if (isFloatType(type)) {
    const auto r = std::from_chars(begin, end, *v);
    if (r.ec != std::errc() || r.ptr != end) {
      if (r.ec == std::errc::result_out_of_range && r.ptr == end) {
        return fail("value '" + std::string(tok) + "' for " + what_info.text() +
                    " is out of range");
      }
      return fail("expected a number for " + what_info.text() + ", found '" + std::string(tok) +
                  "'");
    }
    if (type == ScalarType::kFloat32) *v = static_cast<float>(*v);
    return true;
  }
  long long i = 0;
  const auto r = std::from_chars(begin, end, i);
  if (r.ec != std::errc() || r.ptr != end) {
    return fail("expected an integer (" + std::string(scalarTypeName(type)) + ") for " +
                what_info.text() + ", found '" + std::string(tok) + "'");
  }
  double lo, hi;
  integerRange(type, &lo, &hi);
  if (static_cast<double>(i) < lo || static_cast<double>(i) > hi) {
    return fail("value " + std::string(tok) + " for " + what_info.text() + " does not fit type " +
                scalarTypeName(type));
  }
  *v = static_cast<double>(i);
  return true;
}

bool PlyParser::parse(Mesh* mesh, std::string* error) {
  ascii_ = header_.format == BodyFormat::kAscii;
  const bool file_big_endian = header_.format == BodyFormat::kBinaryBigEndian;
  binary_ = BinaryReader(body_, file_big_endian != (std::endian::native == std::endian::big));
  line_ = header_.body_line - 1;

  const Element* vertex_element = nullptr;
  const Element* face_element = nullptr;
  for (const Element& e : header_.elements) {
    if (e.name == "vertex" && vertex_element == nullptr) vertex_element = &e;
    if (e.name == "face" && face_element == nullptr) face_element = &e;
  }
  if (vertex_element == nullptr) {
    return setError(error, path_ + ": header declares no 'vertex' element");
  }
  VertexLayout layout;
  for (size_t i = 0; i < vertex_element->properties.size(); ++i) {
    const Property& p = vertex_element->properties[i];
    if (p.is_list) continue;
    const int idx = static_cast<int>(i);
    if (p.name == "x") layout.x = idx;
    if (p.name == "y") layout.y = idx;
    if (p.name == "z") layout.z = idx;
    if (p.name == "nx") layout.nx = idx;
    if (p.name == "ny") layout.ny = idx;
    if (p.name == "nz") layout.nz = idx;
    if (p.name == "red" || p.name == "r") layout.r = idx;
    if (p.name == "green" || p.name == "g") layout.g = idx;
    if (p.name == "blue" || p.name == "b") layout.b = idx;
  }
  if (layout.x < 0 || layout.y < 0 || layout.z < 0) {
    return setError(error, path_ + ": header line " + std::to_string(vertex_element->header_line) +
                               ": element 'vertex' lacks one of the scalar properties x, y, z");
  }
  const bool has_normals = layout.nx >= 0 && layout.ny >= 0 && layout.nz >= 0;
  const bool has_colors = layout.r >= 0 && layout.g >= 0 && layout.b >= 0;
  int face_list = -1;
  if (face_element != nullptr) {
    for (size_t i = 0; i < face_element->properties.size(); ++i) {
      const Property& p = face_element->properties[i];
      if (p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) {
        face_list = static_cast<int>(i);
        break;
      }
    }
    if (face_list < 0) {
      return setError(error, path_ + ": header line " + std::to_string(face_element->header_line) +
                                 ": element 'face' has no list property 'vertex_indices'");
    }
    if (isFloatType(face_element->properties[static_cast<size_t>(face_list)].type)) {
      return setError(error, path_ + ": header line " + std::to_string(face_element->header_line) +
                                 ": face vertex indices must have an integer type");
    }
  }

  Mesh out;
  std::vector<int> polygon;
  std::vector<double> values;
  for (const Element& e : header_.elements) {
    element_ = &e;
    // Never trust a header count for allocation beyond what the file can hold.
    const uint64_t reserve_limit = body_.size() / 2 + 1;
    if (&e == vertex_element) {
      const auto n = static_cast<size_t>(std::min<uint64_t>(e.count, reserve_limit));
      out.vertices.reserve(n);
      if (has_normals) out.normals.reserve(n);
      if (has_colors) out.colors.reserve(n);
    }
    for (instance_ = 0; instance_ < e.count; ++instance_) {
      if (!beginInstance()) return setError(error, error_);
      values.assign(e.properties.size(), 0.0);
      for (size_t pi = 0; pi < e.properties.size(); ++pi) {
        const Property& p = e.properties[pi];
        if (!p.is_list) {
          if (!value(p.type, What{&p, 0, 0}, &values[pi])) {
            return setError(error, error_);
          }
          continue;
        }
        double count_value = 0.0;
        if (!value(p.count_type, What{&p, 1, 0}, &count_value)) return setError(error, error_);
        if (count_value < 0.0) {
          fail("negative count " + std::to_string(static_cast<long long>(count_value)) +
               " of list '" + p.name + "'");
          return setError(error, error_);
        }
        const auto count = static_cast<uint64_t>(count_value);
        const bool is_face_list = &e == face_element && static_cast<int>(pi) == face_list;
        if (is_face_list) polygon.clear();
        for (uint64_t k = 0; k < count; ++k) {
          double item = 0.0;
          if (!value(p.type, What{&p, 2, k}, &item)) return setError(error, error_);
          if (is_face_list) {
            if (item < 0.0 || item >= static_cast<double>(vertex_element->count) ||
                item >= static_cast<double>(std::numeric_limits<int>::max())) {
              fail("vertex index " + std::to_string(static_cast<long long>(item)) +
                   " is out of range [0, " + std::to_string(vertex_element->count) + ")");
              return setError(error, error_);
            }
            polygon.push_back(static_cast<int>(item));
          }
        }
        if (is_face_list) {
          if (polygon.size() < 3) {
            fail("face has " + std::to_string(polygon.size()) + " vertices, expected at least 3");
            return setError(error, error_);
          }
          for (size_t k = 1; k + 1 < polygon.size(); ++k) {
            out.triangles.emplace_back(polygon[0], polygon[k], polygon[k + 1]);
          }
        }
      }
      if (!endInstance()) return setError(error, error_);
      if (&e == vertex_element) {
        const auto v = [&values](int i) { return values[static_cast<size_t>(i)]; };
        out.vertices.emplace_back(static_cast<float>(v(layout.x)), static_cast<float>(v(layout.y)),
                                  static_cast<float>(v(layout.z)));
        if (has_normals) {
          out.normals.emplace_back(static_cast<float>(v(layout.nx)),
                                   static_cast<float>(v(layout.ny)),
                                   static_cast<float>(v(layout.nz)));
        }
        if (has_colors) {
          const auto& props = e.properties;
          out.colors.push_back(
              Color{toColorChannel(v(layout.r), props[static_cast<size_t>(layout.r)].type),
                    toColorChannel(v(layout.g), props[static_cast<size_t>(layout.g)].type),
                    toColorChannel(v(layout.b), props[static_cast<size_t>(layout.b)].type)});
        }
      }
    }
  }
  element_ = nullptr;
  *mesh = std::move(out);
  return true;
}

// ---------------------------------------------------------------------------------------
// Writing

template <typename T>
void appendBinary(std::string* out, T value) {
  if constexpr (std::endian::native == std::endian::big) value = byteSwap(value);
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out->append(bytes, sizeof(T));
}

}  // namespace

bool writePly(const std::string& path, const Mesh& mesh, PlyFormat format, std::string* error) {
  const std::string invalid = mesh.validate();
  if (!invalid.empty()) return setError(error, path + ": cannot write PLY: " + invalid);
  const bool ascii = format == PlyFormat::kAscii;
  const bool normals = mesh.hasNormals();
  const bool colors = mesh.hasColors();

  io_detail::BufferedFileWriter writer;
  if (!writer.open(path, error)) return false;
  std::string& out = writer.buffer();
  out += "ply\n";
  out += ascii ? "format ascii 1.0\n" : "format binary_little_endian 1.0\n";
  out += "comment written by cblox\n";
  out += "element vertex " + std::to_string(mesh.numVertices()) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  if (normals) out += "property float nx\nproperty float ny\nproperty float nz\n";
  if (colors) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out += "element face " + std::to_string(mesh.numTriangles()) + "\n";
  out += "property list uchar int vertex_indices\n";
  out += "end_header\n";

  for (size_t i = 0; i < mesh.numVertices(); ++i) {
    const Eigen::Vector3f& p = mesh.vertices[i];
    if (ascii) {
      io_detail::appendFloatText(&out, p.x());
      out += ' ';
      io_detail::appendFloatText(&out, p.y());
      out += ' ';
      io_detail::appendFloatText(&out, p.z());
      if (normals) {
        for (int k = 0; k < 3; ++k) {
          out += ' ';
          io_detail::appendFloatText(&out, mesh.normals[i][k]);
        }
      }
      if (colors) {
        const Color& c = mesh.colors[i];
        out += ' ';
        io_detail::appendIntText(&out, c.r);
        out += ' ';
        io_detail::appendIntText(&out, c.g);
        out += ' ';
        io_detail::appendIntText(&out, c.b);
      }
      out += '\n';
    } else {
      for (int k = 0; k < 3; ++k) appendBinary(&out, p[k]);
      if (normals) {
        for (int k = 0; k < 3; ++k) appendBinary(&out, mesh.normals[i][k]);
      }
      if (colors) {
        const Color& c = mesh.colors[i];
        out.push_back(static_cast<char>(c.r));
        out.push_back(static_cast<char>(c.g));
        out.push_back(static_cast<char>(c.b));
      }
    }
    if (!writer.flushIfFull()) break;
  }
  for (size_t i = 0; i < mesh.numTriangles() && writer.good(); ++i) {
    const Eigen::Vector3i& t = mesh.triangles[i];
    if (ascii) {
      out += '3';
      for (int k = 0; k < 3; ++k) {
        out += ' ';
        io_detail::appendIntText(&out, t[k]);
      }
      out += '\n';
    } else {
      out.push_back(static_cast<char>(3));
      for (int k = 0; k < 3; ++k) appendBinary(&out, static_cast<int32_t>(t[k]));
    }
    if (!writer.flushIfFull()) break;
  }
  return writer.close(error);
}

bool readPly(const std::string& path, Mesh* mesh, std::string* error) {
  std::string data;
  if (!io_detail::readWholeFile(path, &data, error)) return false;

  Header header;
  if (!parseHeader(path, data, &header, error)) return false;
  const std::string_view body = std::string_view(data).substr(header.body_offset);

  // For binary files, check that the fixed-size part of every element fits before reading
  // (gives one clear message for truncated files and bounds allocations).
  if (header.format != BodyFormat::kAscii) {
    // Saturating arithmetic: absurd header counts must not overflow.
    constexpr uint64_t kMax = std::numeric_limits<uint64_t>::max();
    uint64_t min_bytes = 0;
    for (const Element& e : header.elements) {
      uint64_t per_instance = 0;
      for (const Property& p : e.properties) {
        per_instance += scalarSize(p.is_list ? p.count_type : p.type);
      }
      const uint64_t bytes =
          (per_instance != 0 && e.count > kMax / per_instance) ? kMax : per_instance * e.count;
      min_bytes = bytes > kMax - min_bytes ? kMax : min_bytes + bytes;
      if (min_bytes > body.size()) {
        std::ostringstream msg;
        msg << path << ": binary data truncated: element '" << e.name << "' (header line "
            << e.header_line << ") and those before it need at least " << min_bytes
            << " bytes after 'end_header', the file has " << body.size();
        return setError(error, msg.str());
      }
    }
  }

  PlyParser parser(path, body, header);
  return parser.parse(mesh, error);
}

}  // namespace cblox
