#include "drivers/calibration/opencv_storage.h"

#include <fstream>
#include <mutex>
#include <sstream>

#include <libxml/parser.h>
#include <libxml/xmlerror.h>

namespace cblox {
namespace {

// A calibration file is small; anything larger is refused before it is parsed.
constexpr size_t kMaxFileBytes = size_t{16} << 20;

// What OpenCV 4.6's FileStorage parses as XML: any content that does not start, after
// white space, with "%YAML" or "{" (JSON).
bool parsedAsXml(const std::string& text) {
  const size_t start = text.find_first_not_of(" \t\r\n");
  if (start == std::string::npos) return true;
  return text.compare(start, 5, "%YAML") != 0 && text[start] != '{';
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

}  // namespace

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
  if (parsedAsXml(text)) {
    if (const std::string e = xmlWellFormedError(text); !e.empty()) {
      *error = path + ": " + e;
      return {};
    }
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
