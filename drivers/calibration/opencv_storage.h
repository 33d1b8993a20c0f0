#pragma once

#include <string>

#include <opencv2/core.hpp>

namespace cblox {

/// Opens an OpenCV YAML/XML file (cv::FileStorage, READ) that came from outside, refusing
/// before OpenCV parses it what OpenCV 4.6's parsers are known to crash on (RELIABILITY.md B5,
/// B14): a file over 16 MiB; a NUL byte (its parsers read the buffer as a C string: the YAML
/// parser threw std::length_error); and content OpenCV would parse as XML (anything not
/// starting with "%YAML" or "{") that is not well-formed XML by libxml2 (its XML parser
/// dereferenced a null pointer on "<?xml vsn=" at the end of the file); and "%YAML" content
/// that yaml-cpp does not find well-formed (its YAML parser looped forever on an unterminated
/// quoted scalar). JSON ("{") goes to OpenCV unchecked. Returns an opened
/// storage, or a closed one with `*error` set ("<path>: ..."): the file cannot be read, is
/// refused as above (libxml2's message and line), or OpenCV refused it (its cv::Exception
/// message). Never throws cv::Exception. Thread-safe.
cv::FileStorage openOpenCvStorage(const std::string& path, std::string* error);

/// OpenCV YAML text ("%YAML:1.0" on its first line, a directive yaml-cpp does not know) with
/// that line turned into a comment, so yaml-cpp reads the rest with its line numbers.
std::string yamlDirectiveAsComment(std::string text);

}  // namespace cblox
