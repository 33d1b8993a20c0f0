#include "drivers/calibration/opencv_storage.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <mutex>

#include <libxml/parser.h>
#include <libxml/tree.h>
#include <libxml/xmlerror.h>

namespace cblox {
namespace {

// A calibration file or an image list is a few kilobytes; anything larger is refused unread.
constexpr size_t kMaxFileBytes = size_t{1} << 20;

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

// ---------------------------------------------------------------------------------------------
// XML

// libxml2's last error on this thread: "line N: message".
std::string lastXmlError() {
  const xmlError* e = xmlGetLastError();
  if (e == nullptr || e->message == nullptr) return "not well-formed XML";
  std::string message = e->message;
  while (!message.empty() && isSpace(message.back())) message.pop_back();
  return "not well-formed XML (line " + std::to_string(e->line) + ": " + message + ")";
}

std::string elementName(const xmlNode* element) {
  return reinterpret_cast<const char*>(element->name);
}

std::string at(const xmlNode* node) {
  return "line " + std::to_string(xmlGetLineNo(node)) + ": <" + elementName(node) + ">";
}

// OpenCV's values in an element's text: separated by white space; a value starting with a
// double quote runs to the next double quote that ends the text or is followed by white space
// (libxml2 has already decoded &quot;, so a quote inside a string is told by what follows it).
bool splitValues(const std::string& text, std::vector<std::string>* values) {
  size_t i = 0;
  while (true) {
    while (i < text.size() && isSpace(text[i])) ++i;
    if (i == text.size()) return true;
    if (text[i] == '"') {
      size_t close = i + 1;
      while (true) {
        close = text.find('"', close);
        if (close == std::string::npos) return false;
        if (close + 1 == text.size() || isSpace(text[close + 1])) break;
        ++close;
      }
      values->push_back(text.substr(i + 1, close - i - 1));
      i = close + 1;
    } else {
      const size_t end = i;
      while (i < text.size() && !isSpace(text[i])) ++i;
      values->push_back(text.substr(end, i - end));
    }
  }
}

// The tree of one element (see readOpenCvStorage). Depth is bounded by libxml2's limit.
YAML::Node fromXml(const xmlNode* element, std::string* error) {
  std::vector<const xmlNode*> children;
  std::string text;
  for (const xmlNode* n = element->children; n != nullptr; n = n->next) {
    switch (n->type) {
      case XML_ELEMENT_NODE:
        children.push_back(n);
        break;
      case XML_TEXT_NODE:
      case XML_CDATA_SECTION_NODE:
        if (n->content != nullptr) text += reinterpret_cast<const char*>(n->content);
        break;
      case XML_COMMENT_NODE:
      case XML_PI_NODE:
        break;
      default:
        *error = at(element) + ": unsupported XML content (an entity reference?)";
        return {};
    }
  }
  if (!children.empty()) {
    if (std::any_of(text.begin(), text.end(), [](char c) { return !isSpace(c); })) {
      *error = at(element) + ": both text and elements";
      return {};
    }
    const bool sequence = elementName(children.front()) == "_";
    YAML::Node node(sequence ? YAML::NodeType::Sequence : YAML::NodeType::Map);
    for (const xmlNode* child : children) {
      const std::string name = elementName(child);
      if ((name == "_") != sequence) {
        *error = at(child) + ": sequence items (<_>) and named values mixed";
        return {};
      }
      YAML::Node value = fromXml(child, error);
      if (!error->empty()) return {};
      if (sequence) {
        node.push_back(value);
        continue;
      }
      if (static_cast<const YAML::Node&>(node)[name]) {
        *error = at(child) + ": given twice";
        return {};
      }
      node[name] = value;
    }
    if (!sequence) {
      if (xmlChar* type = xmlGetProp(element, reinterpret_cast<const xmlChar*>("type_id"))) {
        if (!static_cast<const YAML::Node&>(node)["type_id"]) {
          node["type_id"] = std::string(reinterpret_cast<const char*>(type));
        }
        xmlFree(type);
      }
    }
    return node;
  }
  std::vector<std::string> values;
  if (!splitValues(text, &values)) {
    *error = at(element) + ": unterminated quoted string";
    return {};
  }
  if (values.empty()) return YAML::Node(YAML::NodeType::Null);
  if (values.size() == 1) return YAML::Node(values.front());
  YAML::Node node(YAML::NodeType::Sequence);
  for (const std::string& v : values) node.push_back(v);
  return node;
}

std::optional<YAML::Node> readXml(const std::string& text, std::string* error) {
  static std::once_flag init;
  std::call_once(init, [] { xmlInitParser(); });
  xmlResetLastError();
  xmlDocPtr doc = xmlReadMemory(text.data(), static_cast<int>(text.size()), nullptr, nullptr,
                                XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING);
  if (doc == nullptr) {
    *error = lastXmlError();
    return std::nullopt;
  }
  std::optional<YAML::Node> root;
  const xmlNode* element = xmlDocGetRootElement(doc);
  if (element == nullptr || elementName(element) != "opencv_storage") {
    *error = "the root element is not <opencv_storage>";
  } else {
    YAML::Node node = fromXml(element, error);
    if (error->empty()) root = std::move(node);
  }
  xmlFreeDoc(doc);
  return root;
}

// ---------------------------------------------------------------------------------------------
// YAML and JSON

std::optional<YAML::Node> readYaml(const std::string& text, const char* format,
                                   std::string* error) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    *error = std::string("not well-formed ") + format + " (" + e.what() + ")";
  } catch (const std::exception& e) {
    *error = std::string("cannot read as ") + format + " (" + e.what() + ")";
  }
  return std::nullopt;
}

bool readFile(const std::string& path, std::string* text, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = "cannot open";
    return false;
  }
  // In pieces, so that a small file costs a small buffer and a large one stops at the limit.
  char piece[1 << 16];
  while (in.read(piece, sizeof piece) || in.gcount() > 0) {
    text->append(piece, static_cast<size_t>(in.gcount()));
    if (text->size() > kMaxFileBytes) {
      *error = "over " + std::to_string(kMaxFileBytes) + " bytes: too large for a calibration file";
      return false;
    }
  }
  if (in.bad()) {
    *error = "cannot read";
    return false;
  }
  if (const size_t nul = text->find('\0'); nul != std::string::npos) {
    *error = "NUL byte at offset " + std::to_string(nul) +
             ": binary data, not an OpenCV YAML/XML/JSON text file";
    return false;
  }
  return true;
}

std::optional<int64_t> readCount(const YAML::Node& node) {
  if (!node.IsScalar()) return std::nullopt;
  const std::optional<double> v = parseOpenCvNumber(node.Scalar());
  if (!v || !(*v >= 0) || *v > std::numeric_limits<int>::max() || std::floor(*v) != *v) {
    return std::nullopt;
  }
  return static_cast<int64_t>(*v);
}

}  // namespace

std::optional<YAML::Node> readOpenCvStorage(const std::string& path, std::string* error) {
  std::string text;
  if (!readFile(path, &text, error)) {
    *error = path + ": " + *error;
    return std::nullopt;
  }
  const size_t start = std::min(text.find_first_not_of(" \t\r\n"), text.size());
  std::optional<YAML::Node> root;
  std::string reason;
  if (text.compare(start, 5, "%YAML") == 0) {
    // Only the directive's line becomes a comment: the lines before it are blank.
    const size_t line_end = std::min(text.find('\n', start), text.size());
    text.replace(start, line_end - start, 1, '#');
    root = readYaml(text, "YAML", &reason);
  } else if (start < text.size() && text[start] == '<') {
    root = readXml(text, &reason);
  } else {
    root = readYaml(text, start < text.size() && text[start] == '{' ? "JSON" : "YAML", &reason);
  }
  if (root && !root->IsMap()) reason = "the top level is not a map of named values";
  if (!reason.empty()) {
    *error = path + ": " + reason;
    return std::nullopt;
  }
  return root;
}

std::optional<double> parseOpenCvNumber(std::string_view text) {
  std::string lower(text);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (lower == ".nan") return std::numeric_limits<double>::quiet_NaN();
  if (lower == ".inf" || lower == "+.inf") return std::numeric_limits<double>::infinity();
  if (lower == "-.inf") return -std::numeric_limits<double>::infinity();
  std::string_view digits = text;
  const bool plus = !digits.empty() && digits.front() == '+';
  if (plus) digits.remove_prefix(1);
  const size_t first = plus || digits.empty() || digits.front() != '-' ? 0 : 1;
  // from_chars also reads "inf" and "nan", which OpenCV does not write.
  if (digits.size() <= first ||
      !(std::isdigit(static_cast<unsigned char>(digits[first])) || digits[first] == '.')) {
    return std::nullopt;
  }
  double value = 0.0;
  const auto [end, status] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (status != std::errc() || end != digits.data() + digits.size()) return std::nullopt;
  return value;
}

std::string readOpenCvMatrix(const YAML::Node& node, OpenCvMatrix* matrix) {
  if (!node.IsMap()) return "not a matrix (expected rows, cols, dt and data)";
  for (const char* key : {"rows", "cols", "dt", "data"}) {
    if (!node[key]) return std::string("not a matrix: ") + key + " is missing";
  }
  if (const YAML::Node type = node["type_id"];
      type && !(type.IsScalar() && type.Scalar() == "opencv-matrix")) {
    return "type_id is not opencv-matrix";
  }
  const std::optional<int64_t> rows = readCount(node["rows"]);
  const std::optional<int64_t> cols = readCount(node["cols"]);
  if (!rows || !cols) return "rows and cols must be integers >= 0";
  const YAML::Node dt = node["dt"];
  std::string depth = dt.IsScalar() ? dt.Scalar() : std::string();
  if (depth.size() == 2 && depth[0] == '1') depth.erase(0, 1);
  if (depth.size() != 1 || std::string_view("ucwsifdh").find(depth[0]) == std::string::npos) {
    return "dt '" + (dt.IsScalar() ? dt.Scalar() : YAML::Dump(dt)) +
           "': expected one channel (u, c, w, s, i, f, d or h)";
  }
  const YAML::Node data = node["data"];
  const int64_t count = *rows * *cols;
  const size_t listed = data.IsSequence() ? data.size() : data.IsScalar() ? 1 : 0;
  if (!(data.IsSequence() || data.IsScalar() || data.IsNull())) return "data is not a list";
  if (static_cast<uint64_t>(count) != listed) {
    return "rows x cols is " + std::to_string(count) + " but data holds " + std::to_string(listed) +
           " numbers";
  }
  OpenCvMatrix m;
  m.rows = static_cast<int>(*rows);
  m.cols = static_cast<int>(*cols);
  m.values.reserve(listed);
  for (size_t i = 0; i < listed; ++i) {
    const YAML::Node item = data.IsSequence() ? data[i] : data;
    const std::optional<double> v =
        item.IsScalar() ? parseOpenCvNumber(item.Scalar()) : std::nullopt;
    if (!v) return "data[" + std::to_string(i) + "] is not a number";
    m.values.push_back(*v);
  }
  *matrix = std::move(m);
  return "";
}

}  // namespace cblox
