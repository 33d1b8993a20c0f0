#include "drivers/calibration/opencv_storage.h"

#include <algorithm>
#include <fstream>
#include <mutex>
#include <sstream>

#include <libxml/parser.h>
#include <libxml/xmlerror.h>
#include <yaml-cpp/yaml.h>

namespace cblox {
namespace {

// A calibration file is small; anything larger is refused before it is parsed.
constexpr size_t kMaxFileBytes = size_t{16} << 20;

// Which parser OpenCV 4.6's FileStorage picks by content: after white space, "%YAML" is
// YAML, "{" is JSON, anything else XML.
enum class OpenCvFormat { kXml, kYaml, kJson };
OpenCvFormat formatOf(const std::string& text, size_t* start) {
  *start = std::min(text.find_first_not_of(" \t\r\n"), text.size());
  if (text.compare(*start, 5, "%YAML") == 0) return OpenCvFormat::kYaml;
  if (*start < text.size() && text[*start] == '{') return OpenCvFormat::kJson;
  return OpenCvFormat::kXml;
}

// Empty when `text` is well-formed XML (libxml2, no network, no entity substitution), else
// libxml2's first error with its line.
std::string xmlWellFormedError(const std::string& text) {
  static std::once_flag init;
  std::call_once(init, [] { xmlInitParser(); });
  xmlResetLastError();
  xmlDocPtr doc = xmlReadMemory(text.data(), static_cast<int>(text.size()), nullptr, nullptr,
                                XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING);
  if (doc != nullptr) {
    xmlFreeDoc(doc);
    return "";
  }
  const xmlError* e = xmlGetLastError();
  if (e == nullptr || e->message == nullptr) return "not well-formed XML";
  std::string message = e->message;
  while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) {
    message.pop_back();
  }
  return "not well-formed XML (line " + std::to_string(e->line) + ": " + message + ")";
}

// Empty when `text` (OpenCV YAML: "%YAML:1.0" first) is well-formed YAML by yaml-cpp, else its
// message.
std::string yamlWellFormedError(const std::string& text) {
  try {
    (void)YAML::Load(yamlDirectiveAsComment(text));
    return "";
  } catch (const YAML::Exception& e) {
    return std::string("not well-formed YAML (") + e.what() + ")";
  }
}

}  // namespace

std::string yamlDirectiveAsComment(std::string text) {
  text.replace(0, std::min(text.find('\n'), text.size()), 1, '#');
  return text;
}

cv::FileStorage openOpenCvStorage(const std::string& path, std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = path + ": cannot open";
    return {};
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  if (text.size() > kMaxFileBytes) {
    *error = path + ": " + std::to_string(text.size()) + " bytes: too large for a calibration file";
    return {};
  }
  if (const size_t nul = text.find('\0'); nul != std::string::npos) {
    *error = path + ": NUL byte at offset " + std::to_string(nul) +
             ": binary data, not an OpenCV YAML/XML text file";
    return {};
  }
  size_t start = 0;
  const OpenCvFormat format = formatOf(text, &start);
  const std::string refusal = format == OpenCvFormat::kXml ? xmlWellFormedError(text)
                              : format == OpenCvFormat::kYaml
                                  ? yamlWellFormedError(text.substr(start))
                                  : "";
  if (!refusal.empty()) {
    *error = path + ": " + refusal;
    return {};
  }
  try {
    cv::FileStorage fs(path, cv::FileStorage::READ);
    if (!fs.isOpened()) *error = path + ": cannot parse as OpenCV YAML/XML";
    return fs;
  } catch (const cv::Exception& e) {
    *error = path + ": cannot parse as OpenCV YAML/XML: " + e.msg;
    return {};
  }
}

}  // namespace cblox
