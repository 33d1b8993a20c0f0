#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace cblox {

/// Reads a file in OpenCV's FileStorage format (what cv::FileStorage writes: YAML, XML or
/// JSON) that came from outside, without OpenCV's own parsers: OpenCV 4.6's readers
/// dereferenced a null pointer, looped forever and ran past 25 s on malformed files
/// (RELIABILITY.md B5, B14, B15, B16), and a process reading its calibration at start must
/// refuse such a file, not die or hang. By content:
/// - "%YAML" first: OpenCV YAML, read by yaml-cpp with the "%YAML:1.0" line (a directive
///   yaml-cpp does not know) read as a comment, so line numbers stay true;
/// - "<" first: XML, read by libxml2 (no network, no entity substitution, libxml2's depth
///   limit) and mapped onto the same tree: the children of <opencv_storage> are the top-level
///   keys; an element with child elements is a map, or a sequence when they are all named
///   "_"; an element with text is a scalar, or a sequence when the text holds several values
///   (white space separates them; a value in double quotes is one string); an empty element
///   is null; a type_id attribute becomes a "type_id" key, as in OpenCV's JSON;
/// - anything else (OpenCV's JSON, "{" first): yaml-cpp (JSON is YAML's flow style).
/// Refused with "<path>: <reason>" in `*error`: a file that cannot be read, is over 1 MiB, has
/// a NUL byte, is not well-formed (the parser's message and line), or whose top level is not
/// a map of named values. Returns the top-level map. Thread-safe.
std::optional<YAML::Node> readOpenCvStorage(const std::string& path, std::string* error);

/// A matrix OpenCV wrote (cv::Mat, one channel), its elements row by row as doubles.
struct OpenCvMatrix {
  int rows = 0;
  int cols = 0;
  std::vector<double> values;
};

/// Reads an OpenCV matrix node of readOpenCvStorage's tree: a map with rows and cols
/// (integers >= 0), dt (one channel of any depth: u c w s i f d h, optionally "1" before it)
/// and data (exactly rows x cols numbers; OpenCV's .Nan, .Inf and -.Inf are read as such).
/// Returns "" with `*matrix` set, or the reason it is not one (nothing allocated beyond what
/// the node holds). Thread-safe.
std::string readOpenCvMatrix(const YAML::Node& node, OpenCvMatrix* matrix);

/// A number as OpenCV writes it: decimal ("2.", "-1.0000000000000000e-01", "7"), or .Nan,
/// .Inf, -.Inf (any case). nullopt for anything else, including trailing characters.
std::optional<double> parseOpenCvNumber(std::string_view text);

}  // namespace cblox
