#pragma once

#include <string>

#include <opencv2/core.hpp>

namespace cblox {

/// Opens an OpenCV YAML/XML file (cv::FileStorage, READ) that came from outside: a file
/// holding a NUL byte is refused before OpenCV parses it, because OpenCV 4.6's parsers read
/// the buffer as a C string (an embedded NUL made the XML parser dereference a null pointer,
/// RELIABILITY.md B14, and the YAML parser throw std::length_error, B5). Returns an opened
/// storage, or a closed one with `*error` set ("<path>: ..."): the file cannot be read, is not
/// text, or OpenCV refused it (its cv::Exception message). Never throws cv::Exception.
/// Thread-safe (nothing shared).
cv::FileStorage openOpenCvStorage(const std::string& path, std::string* error);

}  // namespace cblox
